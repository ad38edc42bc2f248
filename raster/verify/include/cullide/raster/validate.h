// Validating a backend against the reference: per-query intervals [certain, certain + ambiguous]
// and a tee that runs one Cullide workload on the reference, another backend (GL) and the
// interval evaluator at once, comparing every query. `cullide validate` is built on it.
//
// The approach is the conformance suite's (dEQP, see docs/gl-rules.md#deqp): a fragment
// is *certain* when it passes in the reference under every allowed implementation freedom, and
// *ambiguous* when it might go either way:
//   - coverage: the pixel centre lies within a few subpixels of an edge under any snapping of the
//     vertices to a neighbouring grid point (floor or ceil, at the reference's or the GL's subpixel
//     bits, plus float rounding of the window coordinates), or of either fill-rule tie;
//   - depth: the incoming depth is known only up to a margin of a few LSB (unorm) or of a few
//     2^-24 (float), plus the slope of the triangle times the float error of its window
//     coordinates (GL interpolates z in float from float vertices). Stored depths are tracked as
//     intervals, so uncertainty propagates through depth writes.
// A GL count outside [certain, certain + ambiguous] is a real disagreement; inside, an
// implementation freedom.
//
// Bounds used (S = reference subpixel bits, all in units of 2^-S px). A vertex of the other
// implementation lies within r units per axis of the reference's snapped vertex, r = 2 when its
// subpixel bits are >= S, else 2^(S - S_gl) + 1. For an edge a -> b, d = b - a, moving a and b by
// at most r per axis changes E(p) = d x (p - a) by at most r*|d|_1 + 2r*min(|p-a|_1, |p-b|_1) + 4r^2
// (|u x v| <= |u|_1 |v|_inf). So E > that margin on every edge: certainly covered; E >= -margin on
// every edge (for either orientation): possibly covered.
#pragma once

#include "cullide/cullide.h"
#include "cullide/depth_backend.h"
#include "cullide/raster/rules.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace cullide::raster {

struct QueryInterval {
    uint64_t certain = 0;  // fragments that pass under every allowed freedom
    uint64_t possible = 0;  // certain + ambiguous
    bool contains(uint64_t v) const { return certain <= v && v <= possible; }
};

struct IntervalOptions {
    int subpixelBits = kDefaultSubpixelBits;  // the reference's (snapping grid of the margins)
    FillRule fillRule = FillRule::BottomLeft;  // the reference's (for its exact track)
    int otherSubpixelBits = kDefaultSubpixelBits;  // the other implementation's GL_SUBPIXEL_BITS
    double depthLsb = 2.0;  // constant depth margin, in units of DepthFormat::resolution()
    double depthFloatUlps = 4.0;  // slope term: this many 2^-24 * (1 + (|dz/dx| + |dz/dy|) * (W + H))
    // Worker threads of execute() (0: oneTBB's default; else a task_arena of this size, 1 to 1024),
    // as CpuBackendOptions::threads. Results are identical for every value.
    int threads = 0;
    // Rows per band of execute()'s parallel split (0: chosen from the work and the thread count).
    // Results are identical for every value; tests force 1-row and single-band splits with it.
    int bandRows = 0;
};

// Per-pixel classes of one query's fragments, for difference pictures (row 0 at the bottom):
// bit 0: some fragment certainly passed; bit 1: some fragment possibly passed; bit 2: the
// reference's own (exact) fragment passed.
struct CoverageCapture {
    uint32_t query = 0;  // which query of the next execute()
    std::vector<uint8_t> classes;  // width x height, filled by execute()
};

// The interval evaluator: a stateful backend-like object that follows the same calls as a
// backend (geometry, view, command lists; state persists across lists, as in GL) and returns
// an interval per query. It also keeps the reference's exact result ("exact track", the CPU
// reference's rules re-derived from rules.h) as a self-check while no triangle needed clipping.
// execute() is multithreaded and deterministic: a pixel's state depends only on the fragments at
// that pixel, so bands of rows run in parallel, each walking the whole list, and the per-query
// counts (integers) are summed; results are bit-identical for any thread count and band split.
class QueryIntervals {
public:
    explicit QueryIntervals(const IntervalOptions& options = {});
    ~QueryIntervals();
    QueryIntervals(QueryIntervals&&) noexcept;
    QueryIntervals& operator=(QueryIntervals&&) noexcept;
    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles);
    // The same, taking the arrays over instead of copying them.
    void setGeometry(std::vector<Vec3f>&& positions, std::vector<Triangle>&& triangles);
    void setView(const OrthoView& view);
    // Intervals per query. `exact` (optional) receives the exact track's counts; `exactValid`
    // says whether they are trustworthy (no clipped triangle since the last full clear).
    std::vector<QueryInterval> execute(const CommandList& list, std::vector<uint64_t>* exact = nullptr,
                                       bool* exactValid = nullptr, CoverageCapture* capture = nullptr);
    // Frees the per-list scratch (per-vertex, per-drawn-triangle and per-band arrays), keeping the
    // geometry, the view and the buffers' state; the next execute() allocates it again.
    void releaseScratch();

private:
    struct Impl;  // the thread arena and per-list scratch and phases (verify/src/interval_pipeline.h)
    IntervalOptions options_;
    std::unique_ptr<Impl> impl_;
    std::vector<Vec3f> positions_;
    std::vector<Triangle> triangles_;
    OrthoView view_;
    bool haveView_ = false;
    DepthFunc func_ = DepthFunc::Less;
    bool mask_ = true;
    bool exactTrusted_ = true;
    std::vector<uint32_t> exactDepth_, lo_, hi_;
    std::vector<int64_t> writer_;  // the triangle that certainly wrote the stored depth, or -1
};

// One query compared.
struct QueryComparison {
    uint32_t frame = 0;
    uint32_t list = 0;  // execute() call number within the frame's run
    uint32_t query = 0;  // query number within the list
    QueryKind kind = QueryKind::SamplesPassed;
    uint64_t reference = 0, other = 0;
    QueryInterval interval;
    bool exact() const { return reference == other; }
    bool inInterval() const { return interval.contains(other); }
    // How far outside the interval (0 when inside).
    uint64_t outside() const {
        return other < interval.certain ? interval.certain - other
            : other > interval.possible ? other - interval.possible
                                        : 0;
    }
};

// A DepthBackend that forwards every call to the reference, the other backend and an interval
// evaluator, compares every query, and returns the reference's results (so the workload is the
// reference's). `onCapture` (optional) selects queries to capture: called per execute() with
// (frame, list) and returning the query number to capture, or -1.
class TeeBackend : public DepthBackend {
public:
    TeeBackend(DepthBackend& reference, DepthBackend& other, const IntervalOptions& options);
    std::string describe() const override;
    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override;
    void setView(const OrthoView& view) override;
    std::vector<uint64_t> execute(const CommandList& list) override;
    // The smaller of the two backends' limits: a larger view is drawn in tiles both can draw.
    int maxViewportSide() const override { return std::min(reference_.maxViewportSide(), other_.maxViewportSide()); }
    DepthImage readDepth() override;
    void readDepthInto(DepthImage& out) override;

    void setFrame(uint32_t frame) { frame_ = frame, list_ = 0; }
    const std::vector<QueryComparison>& comparisons() const { return comparisons_; }
    // Queries where the exact track disagreed with the reference backend (a bug in one of them).
    uint64_t selfCheckMismatches() const { return selfCheckMismatches_; }
    uint64_t selfCheckedQueries() const { return selfChecked_; }

    std::function<int64_t(uint32_t frame, uint32_t list)> onCapture;
    std::function<void(const QueryComparison&, const CoverageCapture&, const OrthoView&)> captured;

private:
    DepthBackend& reference_;
    DepthBackend& other_;
    QueryIntervals intervals_;
    OrthoView view_;
    uint32_t frame_ = 0, list_ = 0;
    std::vector<QueryComparison> comparisons_;
    uint64_t selfCheckMismatches_ = 0, selfChecked_ = 0;
};

}  // namespace cullide::raster
