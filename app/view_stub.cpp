// Temporary: replaced by the viewer (app/view_*.cpp).
#include "commands.h"
namespace tpb::app {
void registerView(CLI::App& app) {
    CLI::App* cmd = app.add_subcommand("view", "Interactive viewer (not built yet)");
    cmd->callback([] { throw CLI::RuntimeError("the viewer is not built yet", 2); });
}
}  // namespace tpb::app
