// Subcommands of the tpb executable. Each cli_*.cpp / view_*.cpp registers one.
#pragma once
#include <CLI/CLI.hpp>

namespace tpb::app {

void registerRender(CLI::App& app);
void registerInfo(CLI::App& app);
void registerBench(CLI::App& app);
void registerConverge(CLI::App& app);  // app/cli_converge.cpp: converge and reference
void registerView(CLI::App& app);  // app/view_*.cpp (only when built with the viewer)

// Exit codes: 0 success, 1 internal failure, 2 user error (bad scene, bad flag, unwritable output),
// 130 interrupted before anything could be written.
inline constexpr int kExitUserError = 2;

}  // namespace tpb::app

namespace tpb::app {
// Exit code a subcommand asks for (set by its callback; main returns it).
inline int& exitCode() { static int code = 0; return code; }
}  // namespace tpb::app
