// tpb: Transient Photon Beams. `tpb --help` lists the subcommands; `tpb <cmd> --help` each one's flags.
#include "cli/interrupt.h"
#include <CLI/CLI.hpp>
#include "cli/commands.h"
#include "base/error.h"

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
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // A bad flag (its range was checked while parsing, app/cli/common.h flags::): nothing ran.
        if (e.get_exit_code() == 0) return app.exit(e);
        std::fprintf(stderr, "error: %s\nRun with --help for the flags and their ranges.\n", e.what());
        return tpb::app::kExitUserError;
    } catch (const tpb::app::Interrupted& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return e.exitCode;
    } catch (const tpb::UserError& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tpb::app::kExitUserError;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "internal error: %s\n", e.what());
        return 1;
    }
    return tpb::app::exitCode();
}
