// The scalar reference path: obviously correct, one thread, no tiling, no bounding boxes.
// It shares triangle setup (clipping, snapping, depth plane: triangle_setup.cpp) and the rules of
// cullide/raster/rules.h with the fast path, and nothing else: coverage is decided here from the
// snapped vertices directly, E_k(p) = (v[k+1] - v[k]) x (p - v[k]) at every pixel centre p.
#include "reference/reference_path.h"

#include <algorithm>

namespace cullide::raster::detail {

namespace {

bool covers(const SnappedTri& t, int64_t px, int64_t py, FillRule rule) {
    for (int k = 0; k < 3; ++k) {
        const int n = (k + 1) % 3;
        const int64_t dx = t.x[n] - t.x[k], dy = t.y[n] - t.y[k];
        const int64_t e = dx * (py - t.y[k]) - dy * (px - t.x[k]);
        if (e < 0 || (e == 0 && !isInclusiveEdge(rule, dx, dy))) return false;
    }
    return true;
}

}  // namespace

std::vector<uint64_t> executeReference(const CommandList& list, std::span<const WinVertex> window,
                                       std::span<const Triangle> triangles, const SetupParams& params,
                                       const DepthFormat& format, PipelineState& state, std::vector<uint32_t>& depth,
                                       RasterStats& stats, const IntervalState& intervals) {
    std::vector<uint64_t> results(list.queryCount(), 0);
    StateWalker walk(state, list.queryCount());
    const int W = params.width, H = params.height, S = params.subpixelBits;
    const int64_t one = int64_t(1) << S, half = one >> 1;
    auto passed = [&] {
        ++stats.passed;
        if (walk.query() >= 0) ++results[size_t(walk.query())];
    };
    // One conservative triangle over the whole viewport: test and/or merge intervals.
    auto drawConservative = [&](const Command& c, const WinVertex& v0, const WinVertex& v1, const WinVertex& v2) {
        ConsTri ct;
        if (!setupConservative(v0, v1, v2, params, intervals.error, ct)) {
            ++stats.rejected;
            return;
        }
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                if (!consCoversReference(ct, i, j, S)) continue;
                ++stats.fragments;
                uint32_t lo, hi;
                consInterval(ct, i, j, format, lo, hi);
                uint32_t& slo = (*intervals.lo)[size_t(j) * size_t(W) + size_t(i)];
                uint32_t& shi = (*intervals.hi)[size_t(j) * size_t(W) + size_t(i)];
                if (c.test && intervalConflicts(lo, hi, slo, shi)) passed();
                if (c.write) {
                    slo = std::min(slo, lo);
                    shi = std::max(shi, hi);
                }
            }
    };
    // One triangle over the whole viewport: its sub-triangles, depth-tested in order.
    SnappedTri sub[kMaxSubTriangles];
    auto draw = [&](const WinVertex& v0, const WinVertex& v1, const WinVertex& v2) {
        int n = 0;
        const uint8_t flags = setupTriangle(v0, v1, v2, params, sub, n);
        stats.rejected += (flags & kRejected) ? 1 : 0;
        stats.clipped += (flags & kClipped) ? 1 : 0;
        stats.zeroArea += (flags & kZeroArea) ? 1 : 0;
        for (int s = 0; s < n; ++s) {
            for (int j = 0; j < H; ++j) {
                const double row = sub[s].plane.row(j);
                for (int i = 0; i < W; ++i) {
                    if (!covers(sub[s], int64_t(i) * one + half, int64_t(j) * one + half, params.fillRule)) continue;
                    ++stats.fragments;
                    const uint32_t incoming = encodeDepth(sub[s].plane.at(row, i), format);
                    uint32_t& stored = depth[size_t(j) * size_t(W) + size_t(i)];
                    if (!depthTest(state.func, incoming, stored)) continue;
                    passed();
                    if (state.mask) stored = incoming;
                }
            }
        }
    };
    for (const Command& c : list.commands()) {
        if (walk.apply(c)) continue;
        switch (c.op) {
            case Command::Op::Clear: std::fill(depth.begin(), depth.end(), encodeDepth(c.clearDepth, format)); break;
            case Command::Op::ClearIntervals:
                std::fill(intervals.lo->begin(), intervals.lo->end(), kEmptyIntervalLo);
                std::fill(intervals.hi->begin(), intervals.hi->end(), kEmptyIntervalHi);
                break;
            case Command::Op::Draw:
            case Command::Op::DrawConservative:
                ++stats.draws;
                stats.triangles += c.count;
                for (uint32_t t = c.first; t < c.first + c.count; ++t) {
                    const Triangle& tri = triangles[t];
                    if (c.op == Command::Op::Draw) draw(window[tri[0]], window[tri[1]], window[tri[2]]);
                    else drawConservative(c, window[tri[0]], window[tri[1]], window[tri[2]]);
                }
                break;
            default: break;  // state commands: walk.apply
        }
    }
    walk.finish(results);
    return results;
}

}  // namespace cullide::raster::detail
