// Minimal fork-join parallelism: work items [0, n) handed out in chunks through an atomic counter.
// Results must not depend on which thread runs an item (callers key RNG streams by item index).
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace tpb {

// Worker threads beyond this are pointless (the workers never wait on I/O: more threads than cores
// only add memory and contention; 1000 threads on 2 cores ran a thread per tile): 4 x the cores
// std::thread reports. render.threads and --threads above it are capped, with a warning.
inline constexpr int kThreadsPerCoreCap = 4;
inline int maxUsefulThreads() {
    const unsigned cores = std::thread::hardware_concurrency();
    return kThreadsPerCoreCap * static_cast<int>(std::max(1u, cores));
}

inline int resolveThreads(int requested) {
    if (requested > 0) return requested;
    const unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? static_cast<int>(hw) : 1;
}

// Calls fn(item, threadIndex) for every item; stops handing out items once `abort` is set.
// An exception thrown by fn on any thread stops the handing out of items and is rethrown on the
// calling thread once every worker has finished (the first one wins; never std::terminate).
inline void parallelFor(int64_t n, int threads, const std::function<void(int64_t, int)>& fn,
                        const std::atomic<bool>* abort = nullptr) {
    threads = std::max(1, std::min<int>(threads, static_cast<int>(std::max<int64_t>(n, 1))));
    std::atomic<int64_t> next{0};
    std::atomic<bool> failed{false};
    std::exception_ptr failure;
    std::mutex failureMutex;
    auto worker = [&](int t) {
        try {
            for (;;) {
                if (failed.load(std::memory_order_relaxed)) return;
                if (abort && abort->load(std::memory_order_relaxed)) return;
                const int64_t i = next.fetch_add(1, std::memory_order_relaxed);
                if (i >= n) return;
                fn(i, t);
            }
        } catch (...) {
            std::lock_guard<std::mutex> g(failureMutex);
            if (!failure) failure = std::current_exception();
            failed = true;
        }
    };
    if (threads == 1) {
        worker(0);
    } else {
        std::vector<std::thread> pool;
        for (int t = 1; t < threads; ++t) pool.emplace_back(worker, t);
        worker(0);
        for (auto& th : pool) th.join();
    }
    if (failure) std::rethrow_exception(failure);
}

// f(begin, end) over [0, n) in chunks of `chunk` items, on up to `threads` threads (on the calling
// thread alone when there is one chunk or one thread): for loops whose items are independent.
template <class F>
void parallelChunks(size_t n, int threads, size_t chunk, const F& f) {
    const size_t chunks = (n + chunk - 1) / chunk;
    if (threads <= 1 || chunks <= 1) {
        f(size_t(0), n);
        return;
    }
    parallelFor(static_cast<int64_t>(chunks), threads, [&](int64_t c, int) {
        f(static_cast<size_t>(c) * chunk, std::min(n, static_cast<size_t>(c + 1) * chunk));
    });
}

}  // namespace tpb
