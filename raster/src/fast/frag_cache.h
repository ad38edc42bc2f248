// Fragment replay for the fast path of the CPU backend (cpu_backend.cpp, step 6). Private to raster/.
//
// Fragments recorded by a draw, for later draws of the same records in the same tile (reducePCS
// draws each object four times: to write and to test, in both passes). A draw's fragments and
// their incoming depths depend only on its records and the tile, not on the GL state, so a later
// draw replays them in the same order instead of rasterizing again: same counts, same buffer.
#pragma once

#include "cullide/depth_backend.h"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace cullide::raster::detail {

// A group is up to four consecutive pixels of one row.
struct FragGroup {
    uint32_t pixel;  // depth-buffer index of lane 0 (viewports have at most kMaxViewportSide^2 = 2^28 pixels)
    uint32_t lanes;  // bit l set: pixel + l is a fragment (kGroupLanes); kWholeGroup: see below
    uint32_t z[4];  // incoming depth codes, per lane
};
// FragGroup::lanes: the four lane bits, and a flag set when all four pixels lie in the tile the
// group was recorded in (the pixels of the thread that replays it: the AVX2 replay then reads and
// writes them whole, the uncovered ones unchanged).
inline constexpr uint32_t kGroupLanes = 15, kWholeGroup = 16;
static_assert(uint64_t(kMaxViewportSide) * uint64_t(kMaxViewportSide) <= uint64_t(UINT32_MAX),
              "FragGroup::pixel holds a depth-buffer index");
inline constexpr size_t kFragCap = size_t(1) << 16;  // groups per thread and tile; draws beyond are not recorded

// Per thread: the groups recorded in the current tile and an open-addressing table from a draw's
// record range to its groups.
struct FragCache {
    struct Entry {
        uint32_t recBegin = UINT32_MAX, recEnd = 0;  // empty: begin > end, which no draw has
        uint32_t start = 0, stop = 0;  // groups[start, stop)
    };
    std::vector<FragGroup> groups;
    std::vector<Entry> table;
    size_t used = 0;

    void reset(size_t draws) {  // a new tile with up to `draws` draws
        if (groups.size() < kFragCap) groups.resize(kFragCap);
        const size_t cap = std::bit_ceil(std::max<size_t>(16, 2 * draws));
        table.assign(cap, Entry{});
        used = 0;
    }
    static size_t hash(uint32_t b, uint32_t e) { return size_t((uint64_t(b) << 32 | e) * 0x9E3779B97F4A7C15ull >> 40); }
    // The entry of [b, e), or the empty slot where it would go.
    Entry& find(uint32_t b, uint32_t e) {
        const size_t mask = table.size() - 1;
        for (size_t i = hash(b, e) & mask;; i = (i + 1) & mask) {
            Entry& x = table[i];
            if ((x.recBegin == b && x.recEnd == e) || x.recBegin > x.recEnd) return x;
        }
    }
};

}  // namespace cullide::raster::detail
