// PauseGate (core/base/pause_gate.h): the driver's pause/resume between passes.
#include "base/pause_gate.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>

using namespace tpb;
using namespace std::chrono_literals;

// The lost wakeup of issue 12 (item 16): resume() landing after the waiter saw "paused" and before
// it went to sleep. The hook forces exactly that interleaving: the waiter, holding the lock after its
// check, starts a thread that resumes and gives it 200 ms to finish. A resume that notifies without
// the lock finishes inside that window and its notification is lost (the waiter then sleeps for
// good); one that takes the lock has to wait until the waiter sleeps, and its notification wakes it.
TEST(PauseGate, ResumeBetweenCheckAndSleepIsNotLost) {
    PauseGate gate;
    gate.pause();
    std::thread resumer;
    std::promise<bool> result;
    std::thread waiter([&] {
        bool first = true;
        const bool open = gate.waitUntilOpen(nullptr, [&] {
            if (!first) return;
            first = false;
            std::promise<void> done;
            std::future<void> f = done.get_future();
            resumer = std::thread([&gate, d = std::move(done)]() mutable {
                gate.resume();
                d.set_value();
            });
            f.wait_for(200ms);
        });
        result.set_value(open);
    });
    std::future<bool> woke = result.get_future();
    const bool inTime = woke.wait_for(5s) == std::future_status::ready;
    if (!inTime) gate.stop();  // release the waiter so the test can end
    waiter.join();
    resumer.join();
    EXPECT_TRUE(inTime) << "resume() was lost: the waiter slept on with the gate open";
    if (inTime) {
        EXPECT_TRUE(woke.get());
    }
    EXPECT_FALSE(gate.paused());
}

// A stop flag set without the lock (the CLI's signal handler may not take a mutex) is seen.
TEST(PauseGate, AFlagSetWithoutTheLockEndsTheWait) {
    PauseGate gate;
    gate.pause();
    std::atomic<bool> flag{false};
    std::promise<bool> result;
    std::thread waiter([&] { result.set_value(gate.waitUntilOpen(&flag)); });
    std::future<bool> r = result.get_future();
    EXPECT_EQ(r.wait_for(50ms), std::future_status::timeout);
    flag = true;  // no notify, no lock
    ASSERT_EQ(r.wait_for(5s), std::future_status::ready);
    EXPECT_FALSE(r.get());
    waiter.join();
}

TEST(PauseGate, StopWakesAPausedWaiterAndRearmKeepsThePause) {
    PauseGate gate;
    EXPECT_TRUE(gate.waitUntilOpen());  // open: returns at once
    gate.pause();
    std::promise<bool> result;
    std::thread waiter([&] { result.set_value(gate.waitUntilOpen()); });
    std::future<bool> r = result.get_future();
    EXPECT_EQ(r.wait_for(50ms), std::future_status::timeout);  // paused: still waiting
    gate.stop();
    ASSERT_EQ(r.wait_for(5s), std::future_status::ready);
    EXPECT_FALSE(r.get());  // woken by stop: the loop must end
    waiter.join();
    EXPECT_FALSE(gate.waitUntilOpen());  // stopped stays stopped
    gate.rearm();
    EXPECT_TRUE(gate.paused());  // a new run starts paused if the old one was
    gate.resume();
    EXPECT_TRUE(gate.waitUntilOpen());
}
