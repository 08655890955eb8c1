#include "cli/interrupt.h"

#include "render/driver.h"

#include <csignal>
#include <unistd.h>

namespace tpb::app {

namespace {

std::atomic<bool> gStop{false};
std::atomic<int> gSignal{0};
std::atomic<int> gCount{0};
std::atomic<Driver*> gDriver{nullptr};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free &&
                  std::atomic<Driver*>::is_always_lock_free,
              "the signal handler only touches lock-free atomics");

extern "C" void onSignal(int sig) {
    // Only async-signal-safe work: atomics, sigaction and _exit.
    if (sig == SIGHUP) {
        // The terminal or ssh session is gone: a progress line written to its closed pipe must not
        // kill the process (SIGPIPE ignored: the write fails with EPIPE). A hangup often comes twice
        // (the shell forwards it, the kernel sends it to the foreground group), and it comes after a
        // Ctrl-C as the session closes: it never quits at once, it only starts a stop.
        struct sigaction ignore {};
        ignore.sa_handler = SIG_IGN;
        sigaction(SIGPIPE, &ignore, nullptr);
        int none = 0;
        if (!gCount.compare_exchange_strong(none, 1)) return;
    } else if (gCount.fetch_add(1) >= 1) {
        _exit(128 + sig);
    }
    gSignal.store(sig);
    gStop.store(true);
    if (Driver* d = gDriver.load()) d->requestStop();
}

// The signals a scope handles, and SIGPIPE (ignored by the handler after a hangup).
constexpr int kHandled[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
struct sigaction gPrevious[4];

}  // namespace

InterruptScope::InterruptScope() {
    gStop = false;
    gSignal = 0;
    gCount = 0;
    gDriver = nullptr;
    struct sigaction sa {};
    sa.sa_handler = onSignal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: a blocking read/sleep returns EINTR and the loop polls the flag
    for (int i = 0; i < 4; ++i) sigaction(kHandled[i], nullptr, &gPrevious[i]);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    // Under nohup the hangup is ignored on purpose: it stays ignored.
    if (gPrevious[2].sa_handler != SIG_IGN) sigaction(SIGHUP, &sa, nullptr);
}

InterruptScope::~InterruptScope() {
    for (int i = 0; i < 4; ++i) sigaction(kHandled[i], &gPrevious[i], nullptr);
    gDriver = nullptr;
}

const std::atomic<bool>& interruptFlag() { return gStop; }
int interruptSignal() { return gSignal.load(); }
std::string interruptName() {
    const int sig = gSignal.load();
    return sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP (the terminal was closed)" : "Ctrl-C (SIGINT)";
}
int exitCodeAfterInterrupt() {
    const int sig = gSignal.load();
    return sig == SIGTERM || sig == SIGHUP ? 128 + sig : 0;
}
void setInterruptDriver(Driver* driver) {
    gDriver = driver;
    if (driver && gStop.load()) driver->requestStop();  // the signal came before the driver existed
}

Interrupted::Interrupted(const std::string& what)
    : std::runtime_error(what), exitCode(128 + (gSignal.load() ? gSignal.load() : SIGINT)) {}

void throwIfInterrupted(const std::string& during) {
    if (gStop.load()) throw Interrupted("interrupted by " + interruptName() + " " + during + "; nothing was written");
}

}  // namespace tpb::app
