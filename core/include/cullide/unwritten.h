// Arrays whose new elements start unwritten, for the large scratch arrays that a pass fills
// completely before anything reads them (the rasterizer's triangle records, the oracle's boxes
// and keys, the hierarchy's adjacency rows).
//
// A value-initialising std::vector<T>(n) or resize(n) writes every element once with zeros: a
// serial memset, plus the page faults of first touch on the thread that does it (~5% of a 270k
// prune's profile for the records, 12% of a 1M hierarchy build). Here growing writes nothing (see
// construct() below), so the loop that fills the array touches its fresh pages first, in parallel
// where it is parallel.
//
// From 2 MiB on, an array is aligned to 2 MiB and asks for transparent huge pages (MADV_HUGEPAGE,
// advice only: no error if refused): one page fault per 2 MiB instead of one per 4 KiB when it is
// first written (4 KiB faults were a fifth of the 1M oracle's time). Only whole 2 MiB pages
// inside the array are advised, so its memory use stays the same.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace cullide {

template <typename T>
struct UnwrittenAllocator {
    static_assert(std::is_trivially_destructible_v<T>, "elements are never destroyed one by one");
    using value_type = T;
    static constexpr size_t kHuge = size_t(2) << 20;

    UnwrittenAllocator() = default;
    template <typename U>
    UnwrittenAllocator(const UnwrittenAllocator<U>&) noexcept {}

    T* allocate(size_t n) {
        const size_t bytes = n * sizeof(T);
        if (bytes < kHuge) return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
        void* p = ::operator new(bytes, std::align_val_t(kHuge));
        madvise(p, bytes / kHuge * kHuge, MADV_HUGEPAGE);
        return static_cast<T*>(p);
    }
    void deallocate(T* p, size_t n) noexcept {
        ::operator delete(p, std::align_val_t(n * sizeof(T) < kHuge ? alignof(T) : kHuge));
    }
    // resize(n) and vector(n): nothing written. An implicit-lifetime aggregate or scalar (trivially
    // copyable and destructible) lives in the storage without a constructor call, so its default
    // member initialisers, if any, are skipped too; any other type is default-initialised (Eigen's
    // vectors: their empty constructor).
    template <typename U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        if constexpr (!(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U> &&
                        (std::is_aggregate_v<U> || std::is_scalar_v<U>)))
            ::new (static_cast<void*>(p)) U;
    }
    // Anything else (push_back, resize(n, value)) as std::allocator does, braces for aggregates.
    template <typename U, typename... Args>
    void construct(U* p, Args&&... args) {
        if constexpr (std::is_constructible_v<U, Args...>) ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
        else ::new (static_cast<void*>(p)) U{std::forward<Args>(args)...};
    }
    template <typename U>
    bool operator==(const UnwrittenAllocator<U>&) const noexcept {
        return true;
    }
};

template <typename T>
using UnwrittenVector = std::vector<T, UnwrittenAllocator<T>>;

}  // namespace cullide
