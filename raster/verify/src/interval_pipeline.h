// The interval evaluator's execute() (cullide/raster/validate.h): its per-list scratch and phases.
// Private to the verification harness.
//
// Bands of rows in parallel. A pixel's state (the exact depth, the interval [lo, hi] and the
// writer) depends only on the sequence of fragments at that pixel, in list order. So the image is
// split into bands of rows, each band walks the whole list on its own (clears fill its rows; each
// triangle is set up only in the bands its pixel range touches) and counts into its thread's
// counters; the per-query counts are integer sums, the same for any split and thread count.
// Phases, each a parallel loop over disjoint data:
//   1. window coordinates and snapped positions of every vertex (windowVertices);
//   2. (serial) the list's clears and draws with their state, and the draws' instance numbering
//      (collectOps; run first, as it throws on bad commands before any state changes);
//   3. per drawn triangle ("instance"): its pixel range and whether it needs clipping (setUpRanges);
//   4. (serial) whether the exact track is trusted after the list, from the clipped flags in list
//      order (trustAfter); the band split (chooseBands);
//   5. binning of the instances to the bands they touch (count, prefix sum, fill: in order;
//      binInstances);
//   6. the bands (runBands, interval_bands.cpp).
#pragma once

#include "cullide/raster/validate.h"

#include "interval_rules.h"

#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace cullide::raster {

namespace intervals {

struct Vert {
    WinV w;
    int64_t sx, sy;  // snapToFixed of w.x, w.y (the same per vertex as per triangle corner)
    bool finite;
};

// A drawn triangle's pixel range (the grown box clamped to the viewport); j0 > j1 when it draws
// nothing (a non-finite vertex, or trivially outside).
struct PixelRange {
    int32_t i0 = 0, i1 = -1, j0 = 0, j1 = -1;
    bool empty() const { return j0 > j1 || i0 > i1; }
};

// A clear, or a draw with the state it runs under; a draw's instances are [base, base + count).
struct Op {
    bool clear = false;
    double clearDepth = 1.0;
    uint32_t first = 0, count = 0;
    uint64_t base = 0;
    DepthFunc func = DepthFunc::Less;
    bool mask = true;
    int64_t query = -1;
};

// One worker's counters (certain, possible, exact per query, interleaved) and row-work histogram,
// valid for the list whose generation it carries.
struct Local {
    uint64_t generation = 0;
    std::vector<uint64_t> counts;
    std::vector<int64_t> rowWork;  // difference array over rows (band balancing only)
};

inline constexpr size_t kBinChunk = size_t(1) << 14;  // instances per binning task

// The constants of one execute(): the viewport, the subpixel grid and the margins (validate.h).
struct ListParams {
    int W = 0, H = 0, S = 0;  // viewport width and height, the reference's subpixel bits
    int64_t one = 0, half = 0;  // a pixel and half a pixel, in units of 2^-S px
    int64_t r = 0;  // how far the other implementation's vertex may lie, per axis, in units of 2^-S px
    DepthFormat fmt;
    double res = 0;  // fmt.resolution()
    double floatUnit = 0;  // 2^-24
    double G = 0;  // the guard band, in pixels
    uint32_t nq = 0;  // queries of the list
    IntervalOptions options;
};

ListParams listParams(const OrthoView& view, const IntervalOptions& options, uint32_t queries);

// The buffers a band updates (QueryIntervals' exactDepth_, lo_, hi_, writer_), width x height.
struct PixelState {
    uint32_t* exactDepth;
    uint32_t* lo;
    uint32_t* hi;
    int64_t* writer;  // the triangle that certainly wrote the stored depth, or -1
};

}  // namespace intervals

struct QueryIntervals::Impl {
    explicit Impl(int threads) : arena(threads > 0 ? threads : tbb::task_arena::automatic) {}
    tbb::task_arena arena;
    uint64_t generation = 0;
    tbb::enumerable_thread_specific<intervals::Local> locals;
    // Per-list scratch, capacity kept across lists.
    std::vector<intervals::Vert> vert;
    std::vector<intervals::Op> ops;
    std::vector<uint64_t> drawBase;  // base of each draw op, ascending
    std::vector<size_t> drawOp;  // its index in ops
    // Per triangle of the geometry (set for the triangles the list draws: a triangle drawn four
    // times is set up once).
    std::vector<intervals::PixelRange> range;
    std::vector<uint8_t> clipped;
    std::vector<std::array<uint32_t, 2>> drawn;  // the union of the draws' ranges, sorted, disjoint
    std::vector<uint64_t> drawnBase;  // per range of `drawn`: its first position in that union
    std::vector<int32_t> bandStart;  // band b: rows [bandStart[b], bandStart[b + 1])
    std::vector<int32_t> bandOfRow;
    std::vector<uint64_t> binPos;  // per (chunk, band): count, then write position
    std::vector<uint64_t> bandBegin;  // band b: binned[bandBegin[b], bandBegin[b + 1])
    std::vector<uint32_t> binned;  // instance numbers per band, ascending

    // Phase 2: the list's clears and draws into ops (walking the state `func`, `mask` on), the
    // draws' instance numbering, and per query whether it only reports any samples. Returns the
    // number of instances. Throws InputError on conservative commands and out-of-range draws.
    uint64_t collectOps(const CommandList& list, size_t triangleCount, DepthFunc& func, bool& mask,
                        std::vector<uint8_t>& anySamples);
    // Phase 1: window coordinates and snapped positions of every vertex (once per list; the view
    // is fixed within it).
    void windowVertices(std::span<const Vec3f> positions, const OrthoView& view, int S);
    // Phase 3: per triangle drawn, its pixel range and clipped flag, and the row-work histogram.
    void setUpRanges(std::span<const Triangle> triangles, const intervals::ListParams& p);
    // Phase 4: whether the exact track is trusted after the list, given whether it was before.
    bool trustAfter(bool trusted) const;
    // Bands of `rows` rows, or, when 0, ~4 per thread of about equal work (the row-work
    // histogram of phase 3), at least kMinBandRows rows each so that few triangles are set up
    // in two bands. Only the speed depends on the split, never the results.
    void chooseBands(int width, int height, int rows);
    // Phase 5: the instances binned to the bands their pixel ranges touch, ascending per band.
    void binInstances(uint64_t instances);
    // Phase 6 (interval_bands.cpp): every band walks the list over its rows.
    void runBands(std::span<const Triangle> triangles, const intervals::ListParams& p,
                  const intervals::PixelState& pixels, CoverageCapture* capture);
    // The per-worker counts summed into intervals per query (and `exact`, the exact track's).
    std::vector<QueryInterval> sumCounts(uint32_t nq, const std::vector<uint8_t>& anySamples,
                                         std::vector<uint64_t>& exact);

    // The draw of instance k (drawBase[d] <= k), and the triangle of instance k, advancing d
    // (instances are visited in increasing order).
    size_t drawOf(uint64_t k) const {
        return size_t(std::upper_bound(drawBase.begin(), drawBase.end(), k) - drawBase.begin()) - 1;
    }
    uint32_t triangleOf(uint64_t k, size_t& d) const {
        while (d + 1 < drawBase.size() && drawBase[d + 1] <= k) ++d;
        const intervals::Op& op = ops[drawOp[d]];
        return op.first + uint32_t(k - op.base);
    }

    intervals::Local& local(size_t queries, int height) {
        intervals::Local& l = locals.local();
        if (l.generation != generation) {
            l.generation = generation;
            l.counts.assign(3 * queries, 0);
            l.rowWork.assign(size_t(height) + 1, 0);
        }
        return l;
    }

private:
    void setUpRange(uint32_t t, const intervals::ListParams& p, const Triangle& tri, intervals::Local& l);
    void runBand(size_t band, std::span<const Triangle> triangles, const intervals::ListParams& p,
                 const intervals::PixelState& pixels, CoverageCapture* capture);
};

}  // namespace cullide::raster
