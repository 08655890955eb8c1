// One interrupt policy for every subcommand that runs long (render, reference, converge, bench,
// info's pilot): SIGINT (Ctrl-C), SIGTERM (what `timeout`, a job scheduler or `docker stop` send)
// and SIGHUP (a closed terminal or ssh session) are handled alike. The first one sets a flag that
// every long loop polls (the automatic range's pilot, the photon-beam passes, the path tracer, the
// reference, the frame export): the render finishes the pass in progress (the path tracer abandons
// it), writes what has accumulated and exits (0 after Ctrl-C; 128 + 15 = 143 after SIGTERM and
// 128 + 1 = 129 after SIGHUP, so that a script sees it was cut short). A second SIGINT or SIGTERM
// quits at once with 128 + its number (130, 143); a SIGHUP never does (a hangup is often sent twice,
// and after a Ctrl-C as the session closes), and after one SIGPIPE is ignored (the closed terminal's
// pipe). Under nohup (SIGHUP ignored at start) a hangup stays ignored. Before anything could be
// written (during the scene load and the pilot), the command throws Interrupted and exits the same way.
#pragma once
#include <atomic>
#include <stdexcept>
#include <string>

namespace tpb {
class Driver;
}

namespace tpb::app {

// Installs the handlers for its lifetime (one scope at a time, per command run); restores the
// default disposition afterwards. The flag and the signal number are reset when it is created.
class InterruptScope {
public:
    InterruptScope();
    ~InterruptScope();
    InterruptScope(const InterruptScope&) = delete;
    InterruptScope& operator=(const InterruptScope&) = delete;
};

// Set by the first SIGINT/SIGTERM/SIGHUP; pass it to loops that take an abort flag.
const std::atomic<bool>& interruptFlag();
inline bool interrupted() { return interruptFlag().load(); }
// The signal that set the flag (SIGINT, SIGTERM or SIGHUP), 0 when none.
int interruptSignal();
// "Ctrl-C (SIGINT)", "SIGTERM" or "SIGHUP (the terminal was closed)".
std::string interruptName();
// Exit code of a run that was stopped by a signal and still wrote its results: 0 after Ctrl-C (the
// way to end an open-ended render), 128 + 15 after SIGTERM, 128 + 1 after SIGHUP.
int exitCodeAfterInterrupt();

// While set, the first signal also asks this driver to stop after its pass (Driver::requestStop,
// an atomic store: safe in a signal handler). nullptr to clear.
void setInterruptDriver(Driver* driver);

// Thrown when a signal arrives before anything was written; main prints the message and exits
// with `exitCode` (128 + the signal).
class Interrupted : public std::runtime_error {
public:
    explicit Interrupted(const std::string& what);
    int exitCode;
};
// Throws Interrupted("interrupted by <signal> <during>; nothing was written") if the flag is set.
void throwIfInterrupted(const std::string& during);

}  // namespace tpb::app
