// The CPU reference backend: a GL depth buffer and occlusion queries, tiled and multithreaded
// with oneTBB, deterministic (bit-identical results for any thread count).
//
// References: Govindaraju, Redon, Lin, Manocha, CULLIDE (Graphics Hardware 2003) and the seed
// paper (Sections 3-5, docs/paper.md#section-3 ff.): what a backend must do.
// Mesa llvmpipe (lp_rast, lp_setup): 64x64 tiles, binning, per-tile in-order execution,
// per-thread occlusion counters summed at the end. Rules: cullide/raster/rules.h.
//
// One command list, fast path (this file orchestrates; the steps live in the files named):
//   1. validate (draw ranges inside the geometry, no query left open);
//   2. window coordinates of all vertices (cached per geometry + view);
//   3. set up every triangle drawn by the list once (union of the draw ranges, in triangle order,
//      parallel over chunks): clip, snap, edge functions, depth plane, pixel bbox, tile rect.
//      Records are compacted in triangle order, so a draw [first, first+count) is the record
//      range [recBegin[first], recEnd[first+count-1]) (records.cpp);
//   4. bin the records to tiles (CSR, each tile's list sorted by record index; binning.h);
//   5. turn clears and draws into events carrying the GL state (function, mask, open query) and
//      bin each to the tiles its records touch, a clear to all tiles (binning.cpp);
//   6. one task per tile walks its events in order; for a draw it finds the draw's records in
//      the tile's list by galloping from the previous position (cheap for reducePCS's runs of
//      neighbouring and repeated ranges) and rasterizes them clipped to the tile, recording the
//      fragments; a later draw of the same records in the tile replays them (frag_cache.h). Query
//      counts go to a per-tile sparse list of (query, count), in query order (tile_kernels.cpp);
//   7. sum the per-tile lists into the results (integers: order-free).
// Every pixel is owned by exactly one tile and processed in command order, so the depth buffer
// and the counts do not depend on scheduling.
#include "cullide/raster/cpu_backend.h"

#include "cullide/error.h"
#include "cullide/parallel.h"

#include "binning.h"
#include "conservative.h"
#include "frag_cache.h"
#include "records.h"
#include "reference_path.h"
#include "tile_kernels.h"
#include "triangle_setup.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/task_arena.h>

#include <string>

namespace cullide::raster {

const char* toString(FillRule rule) {
    return rule == FillRule::BottomLeft ? "bottom-left" : "top-left";
}

namespace {

using detail::ConsRec;
using detail::EdgeTri;
using detail::SetupParams;
using detail::SnapVertex;
using detail::TileOut;
using detail::WinVertex;

// Every parallel loop of the backend is one phase whose tasks touch disjoint data; phases
// follow each other. cullide::parallelFor (cullide/parallel.h) annotates the joins for
// ThreadSanitizer.
using cullide::parallelFor;

class CpuBackendImpl final : public CpuBackend {
public:
    explicit CpuBackendImpl(const CpuBackendOptions& options)
        : options_(options), arena_(options.threads > 0 ? options.threads : tbb::task_arena::automatic) {}

    std::string describe() const override {
        std::string s = options_.scalarReference ? "cpu scalar reference" : "cpu reference";
        s += " (" + std::to_string(options_.subpixelBits) + " subpixel bits, " + toString(options_.fillRule) +
            " fill rule";
        if (!options_.scalarReference)
            s += ", " + std::to_string(options_.tileSize) + " px tiles, " +
                (options_.threads > 0 ? std::to_string(options_.threads) : std::string("default")) + " threads";
        return s + ")";
    }

    const CpuBackendOptions& options() const override { return options_; }
    const RasterStats& lastStats() const override { return stats_; }
    bool supportsConservative() const override { return true; }

    IntervalImage readIntervals() override {
        IntervalImage img = imageOfView<IntervalImage>();
        if (!haveView_) return img;
        ensureIntervals();
        img.lo = ilo_;
        img.hi = ihi_;
        return img;
    }

    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override {
        checkGeometry(positions, triangles);
        // New vectors, not assign(): a smaller geometry gives its memory back.
        ownedPositions_ = std::vector<Vec3f>(positions.begin(), positions.end());
        ownedTriangles_ = std::vector<Triangle>(triangles.begin(), triangles.end());
        positions_ = ownedPositions_;
        triangles_ = ownedTriangles_;
        borrowed_ = false;
        windowValid_ = windowAll_ = false;
        magnitude_ = -1;
    }

    bool borrowGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override {
        checkGeometry(positions, triangles);
        std::vector<Vec3f>().swap(ownedPositions_);
        std::vector<Triangle>().swap(ownedTriangles_);
        positions_ = positions;
        triangles_ = triangles;
        borrowed_ = true;
        windowValid_ = windowAll_ = false;
        magnitude_ = -1;
        return true;
    }

    static void checkGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
        const size_t n = positions.size();
        for (size_t t = 0; t < triangles.size(); ++t)
            for (uint32_t v : triangles[t])
                if (v >= n)
                    throw InputError("geometry",
                                     "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                                         " of " + std::to_string(n));
        if (triangles.size() >= size_t(UINT32_MAX))
            throw InputError("geometry", "too many triangles for 32-bit indices");
    }

    void releaseScratch() override {
        if (borrowed_) {  // the lender may free it now
            positions_ = {};
            triangles_ = {};
            borrowed_ = false;
        }
        std::vector<WinVertex>().swap(window_);
        std::vector<SnapVertex>().swap(snapped_);
        std::vector<uint32_t>().swap(stamps_);
        windowValid_ = windowAll_ = false;
        magnitude_ = -1;
        plain_ = {};
        events_ = {};
        for (TileOut& out : tileOut_) std::vector<detail::QueryCount>().swap(out.queries);  // one per tile: kept
        frags_.clear();
        conservative_ = {};
    }

    void setView(const OrthoView& view) override {
        view.validate();
        const bool resize =
            !haveView_ || view.width != view_.width || view.height != view_.height || !(view.depth == view_.depth);
        view_ = view;
        haveView_ = true;
        windowValid_ = windowAll_ = false;
        params_.subpixelBits = options_.subpixelBits;
        params_.fillRule = options_.fillRule;
        params_.width = view.width;
        params_.height = view.height;
        params_.gridX0 = -view.originX, params_.gridX1 = view.fullWidth() - view.originX - 1;
        params_.gridY0 = -view.originY, params_.gridY1 = view.fullHeight() - view.originY - 1;
        if (resize) {
            // A new size starts cleared to 1.0, but lazily (depthPending_): a list that begins with
            // a clear, as every reducePCS does, need not pay for the fill, which with a viewport
            // sized per call (adaptive resolution) was a fifth of the run. Capacity grows by half
            // at least, so that sizes that wander do not reallocate (and page-fault) every call.
            const size_t n = size_t(view.width) * size_t(view.height);
            if (depth_.capacity() < n) {
                const size_t grown = std::max(n, depth_.capacity() + depth_.capacity() / 2);
                std::vector<uint32_t>().swap(depth_);
                depth_.reserve(grown);
            }
            depth_.resize(n);
            depthPending_ = true;
            grid_ = detail::TileGrid::make(view.width, view.height, options_.tileSize);
            // resize, not assign: the tiles kept keep their scratch (runTile resets each one), so
            // that a run whose viewport changes per call (adaptive resolution) does not regrow it.
            tileOut_.resize(grid_.count());
            ilo_.clear();  // the interval buffer is made (empty) on first use
            ihi_.clear();
        }
    }

    std::vector<uint64_t> execute(const CommandList& list) override {
        if (!haveView_) throw InputError("command list", "execute() before setView()");
        if (list.queryOpen()) throw InputError("command list", "a query is left open at the end of the list");
        for (const Command& c : list.commands())
            if ((c.op == Command::Op::Draw || c.op == Command::Op::DrawConservative) &&
                uint64_t(c.first) + c.count > triangles_.size())
                throw InputError("command list",
                                 "draw range [" + std::to_string(c.first) + ", " +
                                     std::to_string(uint64_t(c.first) + c.count) + ") exceeds the geometry's " +
                                     std::to_string(triangles_.size()) + " triangles");
        if (depthPending_) {  // setView's clear, unless the list's first command clears anyway
            if (list.commands().empty() || list.commands().front().op != Command::Op::Clear) fillPendingDepth();
            depthPending_ = false;
        }
        stats_ = RasterStats{};
        std::vector<uint64_t> results;
        inArena([&] {
            updateWindow(list);
            if (list.conservativeCount() > 0) {
                ensureIntervals();
                if (magnitude_ < 0) magnitude_ = detail::positionsMagnitude(positions_);
                consErr_ = detail::windowError(view_, magnitude_);
            }
            if (options_.scalarReference)
                results = detail::executeReference(list, window_, triangles_, params_, view_.depth, state_, depth_,
                                                   stats_, {&ilo_, &ihi_, consErr_});
            else results = executeFast(list);
        });
        return results;
    }

    DepthImage readDepth() override {
        DepthImage img;
        readDepthInto(img);
        return img;
    }

    void readDepthInto(DepthImage& out) override {
        if (depthPending_) {
            fillPendingDepth();
            depthPending_ = false;
        }
        std::vector<uint32_t> values = std::move(out.values);  // its buffer is reused
        out = imageOfView<DepthImage>();
        if (haveView_) values.assign(depth_.begin(), depth_.end());
        else values.clear();
        out.values = std::move(values);
    }

private:
    // An image with the viewport's size and depth format (empty before setView), values not set.
    template <typename Image>
    Image imageOfView() const {
        Image img;
        if (!haveView_) return img;
        img.width = view_.width;
        img.height = view_.height;
        img.format = view_.depth;
        return img;
    }

    void fillPendingDepth() { std::fill(depth_.begin(), depth_.end(), encodeDepth(1.0, view_.depth)); }

    void ensureIntervals() {
        const size_t n = size_t(view_.width) * size_t(view_.height);
        if (ilo_.size() == n) return;
        ilo_.assign(n, kEmptyIntervalLo);
        ihi_.assign(n, kEmptyIntervalHi);
    }

    // Step 2: window coordinates (and snapped positions) of the vertices `list` draws, once per
    // geometry + view. Setup reads only the drawn triangles' vertices. A list that draws few
    // triangles for its geometry (the deep reducePCS calls: a few thousand of a mesh's hundreds of
    // thousands) transforms just theirs, each once per view (stamped); otherwise all of them, in
    // parallel. Either way a vertex gets the same numbers.
    void updateWindow(const CommandList& list) {
        if (windowAll_) return;
        if (!windowValid_) {
            window_.resize(positions_.size());
            snapped_.resize(positions_.size());
            stamps_.resize(positions_.size(), 0);
            if (++stamp_ == 0) {  // wrapped: every stamp is stale
                std::fill(stamps_.begin(), stamps_.end(), 0);
                stamp_ = 1;
            }
            windowValid_ = true;
        }
        uint64_t drawn = 0;  // triangles drawn, a range repeated by the next draw counted once
        const Command* last = nullptr;
        for (const Command& c : list.commands()) {
            if (c.op != Command::Op::Draw && c.op != Command::Op::DrawConservative) continue;
            if (!last || last->first != c.first || last->count != c.count) drawn += c.count;
            last = &c;
        }
        if (3 * drawn >= positions_.size()) {
            parallelFor(0, positions_.size(), 4096, [&](const tbb::blocked_range<size_t>& r) {
                for (size_t v = r.begin(); v != r.end(); ++v) transformVertex(v);
            });
            windowAll_ = true;
            return;
        }
        for (const Command& c : list.commands()) {
            if (c.op != Command::Op::Draw && c.op != Command::Op::DrawConservative) continue;
            for (uint32_t t = c.first; t < c.first + c.count; ++t)
                for (uint32_t v : triangles_[t])
                    if (stamps_[v] != stamp_) {
                        transformVertex(v);
                        stamps_[v] = stamp_;
                    }
        }
    }

    void transformVertex(size_t v) {
        const Vec3d w = view_.toWindow(positions_[v]);
        window_[v] = {w.x(), w.y(), w.z()};
        SnapVertex& s = snapped_[v];
        s.inside = detail::insideClipVolume(window_[v], params_);
        s.x = s.inside ? int32_t(snapToFixed(w.x(), params_.subpixelBits)) : 0;
        s.y = s.inside ? int32_t(snapToFixed(w.y(), params_.subpixelBits)) : 0;
        s.beyond = detail::beyondSides(window_[v], params_);
    }

    // Steps 3-7 (step 1 is execute's, step 2 updateWindow's).
    std::vector<uint64_t> executeFast(const CommandList& list) {
        detail::StateWalker walk(state_, list.queryCount());
        setupRecords(list);
        makeEvents(list, walk);
        runTiles();
        return sumQueries(list, walk);
    }

    // Steps 3 and 4: records of the drawn triangles, binned to tiles.
    void setupRecords(const CommandList& list) {
        const detail::SetupInput in{triangles_, window_, snapped_, params_, grid_, options_.simd};
        detail::setupDrawn(list, in, plain_);
        if (list.conservativeCount() > 0) detail::setupConservativeDrawn(list, in, consErr_, conservative_);
    }

    // Step 5: events with their state, binned to their tiles.
    void makeEvents(const CommandList& list, detail::StateWalker& walk) {
        const detail::RecordIndex plain = plain_.index(), conservative = conservative_.index();
        detail::makeEvents(list, view_.depth, grid_, plain, conservative, walk, stats_, events_);
        detail::binEvents(grid_, plain, conservative, events_);
    }

    // Step 6: one task per tile.
    void runTiles() {
        const bool isFloat = view_.depth.kind == DepthFormat::Kind::Float32;
        const detail::RasterTable table = detail::pickRasterTable(isFloat, options_.simd);
        const detail::TileJob job{events_,      plain_, conservative_, table,       view_.depth, view_.width,
                                  view_.height, grid_,  depth_.data(), ilo_.data(), ihi_.data()};
        parallelFor(0, grid_.count(), 1, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t tile = r.begin(); tile != r.end(); ++tile)
                detail::runTile(job, tile, frags_.local(), tileOut_[tile]);
        });
    }

    // Step 7: sum.
    std::vector<uint64_t> sumQueries(const CommandList& list, const detail::StateWalker& walk) {
        std::vector<uint64_t> results(list.queryCount(), 0);
        for (const TileOut& out : tileOut_) {
            for (const detail::QueryCount& q : out.queries) results[q.query] += q.count;
            stats_.fragments += out.fragments;
            stats_.passed += out.passed;
        }
        walk.finish(results);
        return results;
    }

    // arena_.execute(f), with the hand-over annotated for ThreadSanitizer (cullide/parallel.h).
    template <typename F>
    void inArena(const F& f) {
        executeIn(arena_, f);
    }

    CpuBackendOptions options_;
    tbb::task_arena arena_;
    std::vector<Vec3f> ownedPositions_;  // setGeometry's copy
    std::vector<Triangle> ownedTriangles_;
    std::span<const Vec3f> positions_;  // the copy, or borrowGeometry's arrays
    std::span<const Triangle> triangles_;
    bool borrowed_ = false;
    OrthoView view_;
    bool haveView_ = false;
    SetupParams params_;
    std::vector<WinVertex> window_;
    std::vector<SnapVertex> snapped_;  // window_ snapped once per vertex (fast path)
    // window_ and snapped_ hold the current view's numbers for every vertex (windowAll_), or for
    // those whose stamp is stamp_; windowValid_: sized, stamp_ this view's.
    bool windowValid_ = false, windowAll_ = false;
    std::vector<uint32_t> stamps_;
    uint32_t stamp_ = 0;
    double magnitude_ = -1;  // detail::positionsMagnitude of the geometry (< 0: not yet)
    std::vector<uint32_t> depth_;
    bool depthPending_ = false;  // depth_ reads as 1.0 everywhere, not yet written (setView)
    detail::PipelineState state_;
    RasterStats stats_;

    // Fast-path scratch, reused across lists (capacity kept).
    detail::TileGrid grid_;
    detail::RecordSet<EdgeTri> plain_;
    detail::EventList events_;
    std::vector<TileOut> tileOut_;
    tbb::enumerable_thread_specific<detail::FragCache> frags_;  // per thread

    // Conservative mode: the interval buffer, toWindow's error bound, records.
    std::vector<uint32_t> ilo_, ihi_;
    detail::WindowError consErr_;
    detail::RecordSet<ConsRec> conservative_;
};

}  // namespace

std::unique_ptr<CpuBackend> makeCpuBackend(const CpuBackendOptions& options) {
    if (options.subpixelBits < kMinSubpixelBits || options.subpixelBits > kMaxSubpixelBits)
        throw InputError("cpu backend options",
                         "subpixel bits must be " + std::to_string(kMinSubpixelBits) + ".." +
                             std::to_string(kMaxSubpixelBits) + ", got " + std::to_string(options.subpixelBits));
    if (options.threads < 0 || options.threads > 1024)
        throw InputError("cpu backend options",
                         "threads must be 0 (default) to 1024, got " + std::to_string(options.threads));
    if (options.tileSize < 8 || options.tileSize > 1024)
        throw InputError("cpu backend options",
                         "tile size must be 8..1024 pixels, got " + std::to_string(options.tileSize));
    if (options.fillRule != FillRule::BottomLeft && options.fillRule != FillRule::TopLeft)
        throw InputError("cpu backend options", "unknown fill rule");
    return std::make_unique<CpuBackendImpl>(options);
}

}  // namespace cullide::raster
