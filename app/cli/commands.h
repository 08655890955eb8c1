// Subcommands of the tpb executable. Each command's file in app/cli/ (render.cpp, info.cpp, bench.cpp,
// converge.cpp, reference.cpp, view_command.cpp) registers one.
#pragma once

namespace CLI {
class App;  // (CLI11: included by the .cpp files that register, through cli/flags.h)
}

namespace tpb::app {

void registerRender(CLI::App& app);
void registerInfo(CLI::App& app);
void registerBench(CLI::App& app);
void registerConverge(CLI::App& app);
void registerReference(CLI::App& app);
void registerView(CLI::App& app);  // app/cli/view_command.cpp (only when built with the viewer)

// Exit codes: 0 success, 1 internal failure, 2 user error (bad scene, bad flag, unwritable or locked
// output, an all-black film), 128 + the signal (130 Ctrl-C, 143 SIGTERM) when interrupted before
// anything could be written or by a second signal, 143 after a first SIGTERM whose finished work was
// written (cli_interrupt.h).
inline constexpr int kExitUserError = 2;

}  // namespace tpb::app

namespace tpb::app {
// Exit code a subcommand asks for (set by its callback; main returns it).
inline int& exitCode() {
    static int code = 0;
    return code;
}
}  // namespace tpb::app
