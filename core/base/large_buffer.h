// An allocator for large, long-lived numeric buffers (the film's per-bin sums): allocations of at
// least 2 MiB are aligned to 2 MiB and, on Linux, marked for transparent huge pages
// (madvise(MADV_HUGEPAGE)) before they are first touched. Writes into the film go down a tile's bins
// with a stride of a tile's pixels x RGB (6 KiB at 16x16 px): with 4 KiB pages every bin is a
// TLB miss, with 2 MiB pages a tile of 1024 bins spans three pages. Where the kernel does not
// give huge pages ("never" in /sys/kernel/mm/transparent_hugepage/enabled) this is an ordinary
// aligned allocation. The OS call lives in this file only.
#pragma once
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace tpb {

template <class T>
struct LargeBufferAllocator {
    using value_type = T;
    static constexpr size_t kHugePage = size_t(2) << 20;

    LargeBufferAllocator() = default;
    template <class U>
    LargeBufferAllocator(const LargeBufferAllocator<U>&) {}

    T* allocate(size_t n) {
        if (n > static_cast<size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
        const size_t bytes = n * sizeof(T);
        if (bytes < kHugePage) {
            if (void* p = std::malloc(bytes == 0 ? 1 : bytes)) return static_cast<T*>(p);
            throw std::bad_alloc();
        }
        const size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
        void* p = std::aligned_alloc(kHugePage, rounded);
        if (!p) throw std::bad_alloc();
#if defined(MADV_HUGEPAGE)
        madvise(p, rounded, MADV_HUGEPAGE);  // advice only: failure leaves ordinary pages
#endif
        return static_cast<T*>(p);
    }
    void deallocate(T* p, size_t) noexcept { std::free(p); }

    template <class U>
    bool operator==(const LargeBufferAllocator<U>&) const {
        return true;
    }
    template <class U>
    bool operator!=(const LargeBufferAllocator<U>&) const {
        return false;
    }
};

}  // namespace tpb
