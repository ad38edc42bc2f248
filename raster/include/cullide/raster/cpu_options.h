// The CPU backend's options (CpuBackendOptions) and counters (RasterStats): what makeCpuBackend
// (cullide/raster/cpu_backend.h) is configured with and reports, in a header of their own so that the
// rasterizer's private modules can use them without the backend's interface.
#pragma once

#include "cullide/raster/rules.h"

#include <cstddef>
#include <cstdint>

namespace cullide::raster {

struct CpuBackendOptions {
    int subpixelBits = kDefaultSubpixelBits;  // S, kMinSubpixelBits..kMaxSubpixelBits
    FillRule fillRule = FillRule::BottomLeft;
    int threads = 0;  // 0: oneTBB's default; else a task_arena of this size
    int tileSize = kDefaultTileSize;  // fast path tile edge in pixels, 8..1024
    bool scalarReference = false;  // use the scalar reference path instead
    bool simd = true;  // fast path: AVX2 pixel loop and triangle setup where the CPU has it
                       // (the same results bit for bit; false: scalar)
    // Fast path: run a list that draws each range once straight through, each triangle set up and
    // rasterized over the whole viewport in command order, without records, bins or tiles (the
    // same results bit for bit; raster/src/fast/direct_path.h). On one thread always; on several when
    // most of its triangles are under two pixels wide (blocks set up in parallel, rasterized in
    // order by the calling thread). false: always tiles.
    bool direct = true;
    // Fast path: memory for the fragments of the whole geometry under the views of lists that drew
    // every triangle (8 bytes per fragment, ~2.1 MB per 500 x 500 view), so that later lists
    // under one of those views replay them instead of setting up and rasterizing (Cullide's first
    // levels; the same results bit for bit; raster/src/fast/view_cache.h). 0: none kept. Emptied when
    // the geometry changes.
    size_t viewCacheBytes = size_t(32) << 20;
};

// What the last execute() did, counted per drawn triangle instance (a triangle drawn twice counts
// twice). Identical for the fast and the reference path and for any thread count.
struct RasterStats {
    uint64_t draws = 0;  // draw commands
    uint64_t triangles = 0;  // triangles submitted by draws
    uint64_t rejected = 0;  // entirely outside the viewport or the depth range
    uint64_t clipped = 0;  // crossing the depth range or the guard band (clipped, then drawn)
    uint64_t zeroArea = 0;  // not rejected, but every snapped (sub-)triangle has zero area:
                            // edge-on in this view, produce no fragment (paper Section 5)
    uint64_t fragments = 0;  // covered pixel centres (fragments reaching the depth test)
    uint64_t passed = 0;  // fragments that passed the depth test
    friend bool operator==(const RasterStats&, const RasterStats&) = default;
};

}  // namespace cullide::raster
