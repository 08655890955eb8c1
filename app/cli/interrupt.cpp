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
    // Only async-signal-safe work: atomics and _exit.
    if (gCount.fetch_add(1) >= 1) _exit(128 + sig);
    gSignal.store(sig);
    gStop.store(true);
    if (Driver* d = gDriver.load()) d->requestStop();
}

void install(void (*handler)(int)) {
    struct sigaction sa {};
    sa.sa_handler = handler;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: a blocking read/sleep returns EINTR and the loop polls the flag
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
}

}  // namespace

InterruptScope::InterruptScope() {
    gStop = false;
    gSignal = 0;
    gCount = 0;
    gDriver = nullptr;
    install(onSignal);
}

InterruptScope::~InterruptScope() {
    install(SIG_DFL);
    gDriver = nullptr;
}

const std::atomic<bool>& interruptFlag() { return gStop; }
int interruptSignal() { return gSignal.load(); }
std::string interruptName() { return gSignal.load() == SIGTERM ? "SIGTERM" : "Ctrl-C (SIGINT)"; }
int exitCodeAfterInterrupt() { return gSignal.load() == SIGTERM ? 128 + SIGTERM : 0; }
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
