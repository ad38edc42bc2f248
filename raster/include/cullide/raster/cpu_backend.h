// The CPU reference backend: a deterministic software GL depth buffer with occlusion queries.
//
// Exactly what Cullide asks of a GPU (Govindaraju et al., CULLIDE, Graphics Hardware 2003; the
// self-intersection variant of the seed paper, Sections 3-5, docs/paper.md#section-3 ff.):
// depth-only orthographic rasterization, the eight depth functions, a depth mask, clears and
// SAMPLES_PASSED / ANY_SAMPLES_PASSED queries. The rules (subpixel snapping, fill rule, depth
// interpolation, unorm rounding, clipping) are in cullide/raster/rules.h.
//
// Two execution paths, always built, always giving bit-identical depth buffers and query results:
//   - fast (default): per command list, every drawn triangle is set up once (clipped, snapped,
//     edge functions, depth plane) and binned to square screen tiles; each tile is one oneTBB
//     task that walks, in command order, only the clears and draws touching it, and within a draw
//     only its triangles binned to the tile (found by binary search in the tile's sorted list).
//     Per-tile query counts are kept as sparse (query, count) lists and summed at the end.
//     Nothing depends on scheduling, so results are identical for any thread count. On one
//     thread, or for small triangles, a list that draws each range once skips the tiles
//     (`direct`): each triangle is set up and rasterized over the whole viewport as it comes, with
//     the same setup and pixel loops.
//   - scalar reference (`scalarReference = true`): one thread, commands in order, each triangle
//     tested at every pixel centre of the viewport with edge functions evaluated from scratch.
//     Slow (O(pixels) per triangle) and obviously correct; used by the differential tests.
// Both also implement the conservative mode (supportsConservative(): rules 10-13 of rules.h): the
// fast path sets up and bins conservative records like the others and walks them per tile; the
// reference tests every pixel of the viewport with the separating-axis test from scratch.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/raster/cpu_options.h"
#include "cullide/raster/rules.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace cullide::raster {

// The interval buffer of the conservative mode (depth_backend.h, rules 10-13 of rules.h), for
// tests and pictures: per pixel the stored codes [lo, hi]; row 0 at the bottom. An empty pixel
// holds lo = kEmptyIntervalLo, hi = kEmptyIntervalHi.
struct IntervalImage {
    int width = 0, height = 0;
    DepthFormat format;
    std::vector<uint32_t> lo, hi;

    bool covered(int x, int y) const {
        const size_t k = size_t(y) * size_t(width) + size_t(x);
        return lo[k] <= hi[k];
    }
};

class CpuBackend : public DepthBackend {
public:
    ~CpuBackend() override = default;
    virtual const CpuBackendOptions& options() const = 0;
    // The interval buffer (empty before the first conservative command after a viewport change).
    virtual IntervalImage readIntervals() = 0;
    // Counters of the most recent execute() (zero before the first).
    virtual const RasterStats& lastStats() const = 0;
    // Whether the most recent execute() replayed the fragments captured under its view
    // (CpuBackendOptions::viewCacheBytes) instead of setting up its triangles.
    virtual bool lastReplayedView() const = 0;
    // Whether the most recent execute() took the direct path (CpuBackendOptions::direct).
    virtual bool lastRanDirect() const = 0;
    // Frees the scratch kept across lists (triangle records, bins, events, fragment caches, window
    // coordinates, the direct path's blocks), keeping geometry, view and buffers; the next execute() allocates it again.
    // For a caller that runs something else large between lists (trace recording).
    virtual void releaseScratch() = 0;
    // borrowGeometry (DepthBackend) reads the arrays in place and returns true; releaseScratch
    // forgets them too. Trace recording lends the pipeline's arrays this way, during its run.
};

// Creates a CPU backend. Throws InputError("cpu backend options", ...) on options out of range.
// Before the first setView() the viewport is undefined and execute() throws; after a setView()
// that changes the viewport size or depth format, the buffer holds the far value 1.0 (GL leaves it
// undefined; we make it deterministic).
std::unique_ptr<CpuBackend> makeCpuBackend(const CpuBackendOptions& options = {});

}  // namespace cullide::raster
