// The oracle's broad phase: Embree 3's rtcCollide on user geometry (internal to oracle/).
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <span>
#include <type_traits>
#include <vector>

namespace cullide::oracle::detail {

// A primitive's box, already rounded outward to float.
struct Box {
    float lo[3], hi[3];
};

// An array whose elements start unwritten (default-initialised: trivial ones are left as they
// are; aligned as T asks), so that the parallel loops that fill it touch its fresh pages first,
// not a serial memset. From 2 MiB on it is aligned to 2 MiB and asks for transparent huge pages
// (MADV_HUGEPAGE; this kernel's default is madvise): one page fault per 2 MiB instead of one per
// 4 KiB, which on a 1M-triangle bunny were a fifth of `cullide oracle`'s time (setup 400 ms).
// Only whole 2 MiB pages inside the array are advised: its memory use stays the same.
template <typename T>
class Buffer {
public:
    static_assert(std::is_trivially_destructible_v<T>);
    Buffer() = default;
    explicit Buffer(size_t n) : size_(n) {
        constexpr size_t kHuge = size_t(2) << 20;
        const size_t bytes = std::max<size_t>(n * sizeof(T), 1);
        void* p = nullptr;
        const size_t align = bytes >= kHuge ? kHuge : std::max(alignof(T), sizeof(void*));
        if (posix_memalign(&p, align, bytes) != 0) throw std::bad_alloc();
        data_.reset(static_cast<T*>(p));
        if (bytes >= kHuge) madvise(p, bytes / kHuge * kHuge, MADV_HUGEPAGE);  // advice only: no error
        std::uninitialized_default_construct_n(data_.get(), n);
    }
    T* data() { return data_.get(); }
    const T* data() const { return data_.get(); }
    size_t size() const { return size_; }
    T& operator[](size_t i) { return data_[i]; }
    const T& operator[](size_t i) const { return data_[i]; }
    operator std::span<const T>() const { return {data_.get(), size_}; }

private:
    struct Free {
        void operator()(T* p) const { std::free(p); }
    };
    std::unique_ptr<T[], Free> data_;
    size_t size_ = 0;
};

// The float below / above x (std::nextafter toward -inf / +inf, which is a libm call per corner:
// 1.5% of the oracle on small meshes), for finite x only: -0 and +0 both step to the smallest
// denormal of the side asked for, as nextafter does.
inline float roundDown(float x) {
    const uint32_t b = std::bit_cast<uint32_t>(x);
    if (x == 0) return std::bit_cast<float>(uint32_t(0x80000001));
    return std::bit_cast<float>(x > 0 ? b - 1 : b + 1);
}
inline float roundUp(float x) {
    const uint32_t b = std::bit_cast<uint32_t>(x);
    if (x == 0) return std::bit_cast<float>(uint32_t(0x00000001));
    return std::bit_cast<float>(x > 0 ? b + 1 : b - 1);
}

// One candidate pair: object (Embree geometry) and primitive indices of both sides. Same layout
// as RTCCollision.
struct Candidate {
    uint32_t object0, prim0, object1, prim1;
};

// Receives batches of candidates, concurrently from several threads, in no fixed order.
using CandidateFn = void (*)(void* user, const Candidate* pairs, uint32_t count);

struct BroadPhaseTimes {
    double buildSeconds = 0, collideSeconds = 0;
};

// Every pair of primitives whose boxes overlap, among all objects' boxes (object i is Embree
// geometry i): pairs within an object and between objects. Self collision reports each
// unordered pair in both orders and never (p, p); the callback must filter. Boxes must be
// finite with lo <= hi and |coordinates| < 2^60 (the caller validates). Throws
// std::runtime_error on an Embree error (a bug or out of memory).
BroadPhaseTimes collideAll(std::span<const std::span<const Box>> objects, CandidateFn fn, void* user);

// Sorts v[0, n) by the bits [32, 32 + keyBits) of each value (LSD radix, stable: values equal
// there keep their order), using tmp[0, n) as scratch; returns whichever holds the result.
uint64_t* radixSortHigh(uint64_t* v, uint64_t* tmp, size_t n, int keyBits);

// The same pairs from a uniform grid (broad_phase_grid.cpp), each unordered pair once, as
// (object0, prim0) < (object1, prim1). At most 2^29 boxes in all (std::length_error beyond);
// throws std::bad_alloc otherwise only.
BroadPhaseTimes collideGrid(std::span<const std::span<const Box>> objects, CandidateFn fn, void* user);

}  // namespace cullide::oracle::detail
