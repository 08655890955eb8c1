// A gate a worker loop waits at between passes: paused, open, or stopped.
//
// Every state change takes the mutex the waiter sleeps under before it notifies. Without that, a
// resume() that lands between the waiter's check of the predicate and its going to sleep is a
// lost wakeup: the waiter sleeps on with the gate open (a resumed render that stays paused).
// `beforeSleep` is a test hook, called under the lock right after the predicate said "wait".
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>

namespace tpb {

class PauseGate {
public:
    void pause() {
        update([](bool& p, bool&) { p = true; });
    }
    void resume() {
        update([](bool& p, bool&) { p = false; });
    }
    void stop() {
        update([](bool&, bool& s) { s = true; });
    }
    void rearm() {
        update([](bool&, bool& s) { s = false; });
    }  // a new run: not stopped, paused as it was
    bool paused() const {
        std::lock_guard<std::mutex> g(mutex_);
        return paused_;
    }
    bool stopped() const {
        std::lock_guard<std::mutex> g(mutex_);
        return stopped_;
    }
    // Blocks while paused; returns false when stopped (at once if already stopped). `alsoStop` is a
    // flag that may be set without the lock, e.g. from a signal handler (which must not take a
    // mutex): while one is given, the wait wakes every 20 ms to look at it.
    bool waitUntilOpen(const std::atomic<bool>* alsoStop = nullptr, const std::function<void()>& beforeSleep = {}) {
        std::unique_lock<std::mutex> lk(mutex_);
        const auto stop = [&] { return stopped_ || (alsoStop && alsoStop->load()); };
        while (paused_ && !stop()) {
            if (beforeSleep) beforeSleep();
            if (alsoStop)
                cv_.wait_for(lk, std::chrono::milliseconds(20));
            else
                cv_.wait(lk);
        }
        return !stop();
    }

private:
    template <class F>
    void update(F&& change) {
        {
            std::lock_guard<std::mutex> g(mutex_);
            change(paused_, stopped_);
        }
        cv_.notify_all();
    }
    mutable std::mutex mutex_;
    std::condition_variable cv_;
    bool paused_ = false, stopped_ = false;
};

}  // namespace tpb
