// A gate a worker loop waits at between passes: paused, open, or stopped.
//
// Every state change takes the mutex the waiter sleeps under before it notifies. Without that, a
// resume() that lands between the waiter's check of the predicate and its going to sleep is a
// lost wakeup: the waiter sleeps on with the gate open (a resumed render that stays paused).
// `beforeSleep` is a test hook, called under the lock right after the predicate said "wait".
#pragma once
#include <condition_variable>
#include <functional>
#include <mutex>

namespace tpb {

class PauseGate {
public:
    void pause() { update([](bool& p, bool&) { p = true; }); }
    void resume() { update([](bool& p, bool&) { p = false; }); }
    void stop() { update([](bool&, bool& s) { s = true; }); }
    void rearm() { update([](bool&, bool& s) { s = false; }); }  // a new run: not stopped, paused as it was
    bool paused() const {
        std::lock_guard<std::mutex> g(mutex_);
        return paused_;
    }
    bool stopped() const {
        std::lock_guard<std::mutex> g(mutex_);
        return stopped_;
    }
    // Blocks while paused; returns false when stopped (at once if already stopped).
    bool waitUntilOpen(const std::function<void()>& beforeSleep = {}) {
        std::unique_lock<std::mutex> lk(mutex_);
        while (paused_ && !stopped_) {
            if (beforeSleep) beforeSleep();
            cv_.wait(lk);
        }
        return !stopped_;
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
