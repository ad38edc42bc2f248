// The oracle's broad phase: Embree 3's rtcCollide on user geometry (internal to oracle/).
#pragma once

#include "cullide/unwritten.h"

#include <bit>
#include <cstdint>
#include <span>
#include <vector>

namespace cullide::oracle::detail {

// A primitive's box, already rounded outward to float.
struct Box {
    float lo[3], hi[3];
};

// The oracle's large arrays are filled by parallel loops before they are read: they start
// unwritten, so those loops touch their fresh pages first, not a serial memset, and from 2 MiB on
// they ask for huge pages (cullide/unwritten.h). A call without a Workspace takes them from its
// own PageArena where one is available (fresh memory on huge pages, whatever malloc kept).
template <typename T>
using Buffer = ArenaVector<T>;

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

// The grid's arrays. With `keep` (a caller's oracle::Workspace) they stay allocated for the next
// call, which reuses them; without, each goes as soon as it is no longer needed (the peak of one
// call counts more than the next call's page faults).
// `arena`: where the arrays come from (null: malloc).
struct GridScratch {
    GridScratch() = default;
    explicit GridScratch(PageArena* arena)
        : extent(ArenaAllocator<float>(arena)),
          raw(ArenaAllocator<uint64_t>(arena)),
          start(ArenaAllocator<uint32_t>(arena)),
          entries(ArenaAllocator<uint64_t>(arena)) {}

    bool keep = false;
    Buffer<float> extent;  // per box: its largest extent (the cell size's median)
    Buffer<uint64_t> raw;  // the entries in box order, before the counting sort (few cells)
    Buffer<uint32_t> start;  // per cell: its first entry (few cells)
    Buffer<uint64_t> entries;  // (cell, axes, box), sorted by cell
};

// The same pairs from a uniform grid (broad_phase_grid.cpp), each unordered pair once, as
// (object0, prim0) < (object1, prim1), its arrays in `scratch`. At most 2^29 boxes in all
// (std::length_error beyond); throws std::bad_alloc otherwise only.
BroadPhaseTimes collideGrid(std::span<const std::span<const Box>> objects, CandidateFn fn, void* user,
                            GridScratch& scratch);

}  // namespace cullide::oracle::detail
