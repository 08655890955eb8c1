// tpb: Transient Photon Beams. `tpb --help` lists the subcommands; `tpb <cmd> --help` each one's flags.
#include "cli/interrupt.h"
#include <CLI/CLI.hpp>
#include "cli/commands.h"
#include "base/error.h"
#include "base/text.h"

#include <cstdio>
#include <string>
#include <vector>

#ifndef TPB_VERSION
#define TPB_VERSION "unknown"
#endif
#ifndef TPB_GIT_COMMIT
#define TPB_GIT_COMMIT "unknown"
#endif
#ifndef TPB_BUILD_TYPE
#define TPB_BUILD_TYPE "unknown"
#endif

namespace {

// `tpb --version`: the release, the commit and build type it was configured from (CMakeLists.txt).
std::string versionText() {
    return std::string("tpb ") + TPB_VERSION + " (commit " + TPB_GIT_COMMIT + ", " + TPB_BUILD_TYPE + " build)";
}

// CLI11 names an unknown flag or subcommand but suggests nothing: "did you mean" lines for each
// unexpected argument that is close to a flag of the subcommand given (or to a subcommand).
std::string didYouMean(const CLI::App& app) {
    std::string out;
    const auto suggest = [&](const std::vector<std::string>& extras, const std::vector<std::string>& names) {
        for (const std::string& extra : extras) {
            const std::string word = extra.substr(0, extra.find('='));
            const std::string best = tpb::closestName(word, names);
            if (!best.empty()) out += tpb::clipped(word) + ": did you mean " + best + "?\n";
        }
    };
    const std::vector<CLI::App*> given = app.get_subcommands();
    if (given.empty()) {
        std::vector<std::string> commands;
        for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
            commands.push_back(sub->get_name());
        suggest(app.remaining(), commands);
        return out;
    }
    for (const CLI::App* sub : given) {
        std::vector<std::string> flags;
        for (const CLI::Option* o : sub->get_options())
            for (const std::string& n : o->get_lnames()) flags.push_back("--" + n);
        std::vector<std::string> extras;
        for (const std::string& r : sub->remaining())
            if (r.rfind("-", 0) == 0) extras.push_back(r);
        suggest(extras, flags);
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "tpb: progressive transient photon beams (Marco et al. 2017) - render, inspect and view "
        "time-resolved light transport in participating media"};
    app.require_subcommand(1);
    app.set_version_flag("--version", versionText(), "Print the version, the git commit and build type, and exit");
    tpb::app::registerRender(app);
    tpb::app::registerInfo(app);
    tpb::app::registerBench(app);
    tpb::app::registerReference(app);
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
        std::fprintf(stderr, "error: %s\n%sRun with --help for the flags and their ranges.\n", e.what(),
                     didYouMean(app).c_str());
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
