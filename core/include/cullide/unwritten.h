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
// From 2 MiB on, an array is 2 MiB aligned and asks for transparent huge pages (MADV_HUGEPAGE,
// advice only: no error if refused): one page fault per 2 MiB instead of one per 4 KiB when it is
// first written (4 KiB faults were a fifth of the 1M oracle's time). From malloc, only whole 2 MiB
// pages inside the array are advised, so its memory use stays the same. An array with pages of its
// own (below) maps and advises whole 2 MiB pages to its end: the last one may hold up to 2 MiB
// that the array does not use, but its tail is no longer hundreds of 4 KiB faults (a 1M
// hierarchy build's two arrays of 3.8 and two of 11.4 MiB had 1.8 and 1.4 MiB in 4 KiB pages
// each: about 1,700 faults; with whole huge pages its BM_Hierarchy time fell from 160-183 to
// 137-146 ms, and the 1M prune's peak memory rose by 0.3 MB).
//
// An array may also map its own pages from 256 KiB on (kOwnPages), which go back to the system
// when it is freed, whatever malloc's heuristics: an array of a few MiB freed from malloc's heap
// raises glibc's mmap threshold, and later ones then stay resident in the heap after they are
// freed (the parallel hierarchy build, whose subtrees free their scratch, raised `prune`'s 1M
// peak by 20 MB that way).
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace cullide {

// kOwnPages: from 256 KiB on, the array maps its own pages (see above). Without it, a large array
// comes from malloc like any other, whose freed memory serves the next call at once: the right
// choice for arrays that a loop allocates again and again (the oracle's, called per mesh: mapping
// them anew each call made its setup 10x slower on 5k-50k meshes).
template <typename T, bool kOwnPages = false>
struct UnwrittenAllocator {
private:
    // An own mapping of 2 MiB or more ends on a whole huge page (see allocate()).
    static size_t mappedBytes(size_t bytes) {
        const size_t page = bytes >= kHuge ? kHuge : 4096;
        return (bytes + page - 1) & ~(page - 1);
    }

public:
    static_assert(std::is_trivially_destructible_v<T>, "elements are never destroyed one by one");
    using value_type = T;
    static constexpr size_t kHuge = size_t(2) << 20;
#if defined(__SANITIZE_ADDRESS__)
    // Under AddressSanitizer every array comes from its heap, whose redzones catch an overrun.
    static constexpr size_t kMapped = std::numeric_limits<size_t>::max();
#else
    static constexpr size_t kMapped = kOwnPages ? size_t(256) << 10 : std::numeric_limits<size_t>::max();
#endif
    template <typename U>
    struct rebind {
        using other = UnwrittenAllocator<U, kOwnPages>;
    };

    UnwrittenAllocator() = default;
    template <typename U>
    UnwrittenAllocator(const UnwrittenAllocator<U, kOwnPages>&) noexcept {}

    T* allocate(size_t n) {
        if (n > max_size()) throw std::bad_array_new_length();
        const size_t bytes = n * sizeof(T);
        if (bytes < kMapped) {
            if (bytes < kHuge) return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
            void* p = ::operator new(bytes, std::align_val_t(kHuge));
            madvise(p, bytes / kHuge * kHuge, MADV_HUGEPAGE);
            return static_cast<T*>(p);
        }
        // Mapped here; from 2 MiB on 2 MiB aligned: the head and tail of a mapping one huge page
        // longer are unmapped again (an unmapped range costs no memory).
        const size_t len = mappedBytes(bytes), extra = bytes >= kHuge ? kHuge : 0;
        void* p = mmap(nullptr, len + extra, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED) throw std::bad_alloc();
        if (extra == 0) return static_cast<T*>(p);
        const uintptr_t start = reinterpret_cast<uintptr_t>(p);
        const uintptr_t aligned = (start + kHuge - 1) & ~uintptr_t(kHuge - 1);
        if (aligned > start) munmap(p, aligned - start);
        if (const size_t tail = start + extra - aligned) munmap(reinterpret_cast<void*>(aligned + len), tail);
        madvise(reinterpret_cast<void*>(aligned), len, MADV_HUGEPAGE);
        return reinterpret_cast<T*>(aligned);
    }
    void deallocate(T* p, size_t n) noexcept {
        const size_t bytes = n * sizeof(T);
        if (bytes < kMapped) ::operator delete(p, std::align_val_t(bytes < kHuge ? alignof(T) : kHuge));
        else munmap(p, mappedBytes(bytes));
    }
    static constexpr size_t max_size() noexcept {
        return (std::numeric_limits<size_t>::max() - kHuge) / sizeof(T);
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
    bool operator==(const UnwrittenAllocator<U, kOwnPages>&) const noexcept {
        return true;
    }
};

template <typename T, bool kOwnPages = false>
using UnwrittenVector = std::vector<T, UnwrittenAllocator<T, kOwnPages>>;

// Memory for the arrays of one call, on transparent huge pages, given back when the call ends
// (the oracle's arrays when its caller keeps no oracle::Workspace).
//
// Why: such a call's arrays of 64 KiB to 2 MiB come from malloc, whose memory is warm only if
// the previous call left it there. Between calls of another library (CGAL's, in BM_OracleInterleaved)
// glibc had given it back, and every 4 KiB page was a fault again when first written (on a
// virtual machine, where a fault costs about 13 us, a 23k-triangle oracle call took twice its
// time). A 2 MiB huge page costs one fault and 2 MiB of zeroing, whether the memory is warm or
// not: far less than 512 faults of 4 KiB.
//
// How: by size, so that deallocate() knows without a lookup where an array came from.
//   - below 64 KiB: malloc (its small chunks are warm);
//   - 2 MiB or more: pages of its own (UnwrittenAllocator<T, true>: whole huge pages), unmapped
//     when freed, so that a large call's peak is as without the arena;
//   - between: handed out in order from 2 MiB chunks mapped on huge pages; freeing the latest
//     one takes it back (a temporary), any other waits for the arena's end (a vector's regrowth
//     frees the old array after making the new one). A chunk's tail that the next array does not
//     fit in stays unused.
// One thread allocates from an arena at a time (the call's own); the memory may be written by
// any. Without transparent huge pages (disabled, or not Linux's), available() is false: a 4 KiB
// fault per page of every call would cost more than malloc's reuse.
class PageArena {
public:
    static constexpr size_t kMinBytes = size_t(64) << 10;  // smaller: malloc
    static constexpr size_t kChunk = UnwrittenAllocator<std::byte>::kHuge;

    // Transparent huge pages can be asked for ("always" or "madvise" in
    // /sys/kernel/mm/transparent_hugepage/enabled, read once), and no AddressSanitizer (whose
    // redzones need every array from its heap).
    static bool available();

    // An ended arena's chunks wait for the next arena, up to kPooled of them (8 MiB, mapped and
    // resident): a call then starts on written pages, as with malloc's reused memory, without a
    // fault or 2 MiB of zeroing per chunk (0.2 ms of the cow's 1.8 ms oracle call). releasePool() gives
    // them back to the system; pooled() counts them.
    static constexpr size_t kPooled = 4;
    static void releasePool();
    static size_t pooled();

    PageArena() = default;
    PageArena(const PageArena&) = delete;
    PageArena& operator=(const PageArena&) = delete;
    ~PageArena();

    void* allocate(size_t bytes, size_t align);
    void deallocate(void* p, size_t bytes, size_t align) noexcept;
    size_t chunks() const { return chunks_.size(); }  // 2 MiB chunks taken so far (mapped or pooled)

private:
    std::vector<std::byte*> chunks_;
    std::byte* next_ = nullptr;  // the current chunk's first free byte
    std::byte* end_ = nullptr;
};

// UnwrittenAllocator's arrays from a PageArena when one is given (null: as UnwrittenAllocator).
// Stateful: containers move, swap and assign their allocator with their storage, so an array
// from the arena is always freed through it.
template <typename T>
struct ArenaAllocator : UnwrittenAllocator<T> {
    using propagate_on_container_copy_assignment = std::true_type;
    using propagate_on_container_move_assignment = std::true_type;
    using propagate_on_container_swap = std::true_type;
    template <typename U>
    struct rebind {
        using other = ArenaAllocator<U>;
    };

    PageArena* arena = nullptr;

    ArenaAllocator() = default;
    explicit ArenaAllocator(PageArena* a) noexcept : arena(a) {}
    template <typename U>
    ArenaAllocator(const ArenaAllocator<U>& other) noexcept : arena(other.arena) {}

    T* allocate(size_t n) {
        if (!arena) return UnwrittenAllocator<T>::allocate(n);
        if (n > UnwrittenAllocator<T>::max_size()) throw std::bad_array_new_length();
        return static_cast<T*>(arena->allocate(n * sizeof(T), alignof(T)));
    }
    void deallocate(T* p, size_t n) noexcept {
        if (!arena) UnwrittenAllocator<T>::deallocate(p, n);
        else arena->deallocate(p, n * sizeof(T), alignof(T));
    }
    template <typename U>
    bool operator==(const ArenaAllocator<U>& other) const noexcept {
        return arena == other.arena;
    }
};

template <typename T>
using ArenaVector = std::vector<T, ArenaAllocator<T>>;

}  // namespace cullide
