// tpb: Transient Photon Beams. `tpb --help` lists the subcommands; `tpb <cmd> --help` each one's flags.
#include "commands.h"
#include "error.h"

#include <cstdio>

int main(int argc, char** argv) {
    CLI::App app{"tpb: progressive transient photon beams (Marco et al. 2017) - render, inspect and view "
                 "time-resolved light transport in participating media"};
    app.require_subcommand(1);
    tpb::app::registerRender(app);
    tpb::app::registerInfo(app);
    tpb::app::registerBench(app);
    tpb::app::registerConverge(app);
#ifdef TPB_HAVE_VIEWER
    tpb::app::registerView(app);
#endif
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : tpb::app::kExitUserError;
    } catch (const tpb::UserError& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tpb::app::kExitUserError;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "internal error: %s\n", e.what());
        return 1;
    }
    return tpb::app::exitCode();
}
