// Minimal fork-join parallelism: work items [0, n) handed out in chunks through an atomic counter.
// Results must not depend on which thread runs an item (callers key RNG streams by item index).
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <thread>
#include <vector>

namespace tpb {

inline int resolveThreads(int requested) {
    if (requested > 0) return requested;
    const unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? static_cast<int>(hw) : 1;
}

// Calls fn(item, threadIndex) for every item; stops handing out items once `abort` is set.
inline void parallelFor(int64_t n, int threads, const std::function<void(int64_t, int)>& fn,
                        const std::atomic<bool>* abort = nullptr) {
    threads = std::max(1, std::min<int>(threads, static_cast<int>(std::max<int64_t>(n, 1))));
    std::atomic<int64_t> next{0};
    auto worker = [&](int t) {
        for (;;) {
            if (abort && abort->load(std::memory_order_relaxed)) return;
            const int64_t i = next.fetch_add(1, std::memory_order_relaxed);
            if (i >= n) return;
            fn(i, t);
        }
    };
    if (threads == 1) { worker(0); return; }
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker, t);
    worker(0);
    for (auto& th : pool) th.join();
}

}  // namespace tpb
