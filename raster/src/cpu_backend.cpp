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
// A list that draws every triangle also captures its fragments per tile; a later list under the
// same view (Cullide's first levels) replays them in steps 5-6 instead of steps 2-4 and the
// rasterization (view_cache.h).
// Every pixel is owned by exactly one tile and processed in command order, so the depth buffer
// and the counts do not depend on scheduling.
#include "cullide/raster/cpu_backend.h"

#include "cullide/error.h"
#include "cullide/parallel.h"

#include "fast/binning.h"
#include "fast/direct_path.h"
#include "fast/frag_cache.h"
#include "fast/records.h"
#include "fast/tile_kernels.h"
#include "fast/view_cache.h"
#include "reference/reference_path.h"
#include "setup/conservative.h"
#include "setup/triangle_setup.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/task_arena.h>

#include <string>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cullide::raster {

const char* toString(FillRule rule) {
    return rule == FillRule::BottomLeft ? "bottom-left" : "top-left";
}

std::optional<FillRule> parseFillRule(std::string_view name) {
    for (FillRule rule : {FillRule::BottomLeft, FillRule::TopLeft})
        if (name == toString(rule)) return rule;
    return std::nullopt;
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

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CULLIDE_WINDOW_AVX2 1

// (a.x*x + a.y*y) + a.z*z on four lanes, as OrthoView::toWindow's dot3.
__attribute__((target("avx2"))) inline __m256d dot4(const Vec3d& a, __m256d x, __m256d y, __m256d z) {
    return _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(a.x()), x), _mm256_mul_pd(_mm256_set1_pd(a.y()), y)),
        _mm256_mul_pd(_mm256_set1_pd(a.z()), z));
}

// (v - lo) / (hi - lo) * size - origin on four lanes, as toWindow.
__attribute__((target("avx2"))) inline __m256d scale4(__m256d v, double lo, double hi, double size, double origin) {
    const __m256d unit = _mm256_div_pd(_mm256_sub_pd(v, _mm256_set1_pd(lo)), _mm256_set1_pd(hi - lo));
    return _mm256_sub_pd(_mm256_mul_pd(unit, _mm256_set1_pd(size)), _mm256_set1_pd(origin));
}

// snapToFixed on four lanes (`fixed` = 2^S), 0 where not `inside`. Its floor is _mm256_floor_pd:
// for an inside vertex |v * 2^S| <= 2^29, where truncate-and-step and floor agree.
__attribute__((target("avx2"))) inline __m128i snap4(__m256d v, __m256d fixed, __m256d inside) {
    const __m256d s = _mm256_mul_pd(v, fixed);
    const __m256d f = _mm256_floor_pd(s);
    const __m256d up =
        _mm256_and_pd(_mm256_cmp_pd(_mm256_sub_pd(s, f), _mm256_set1_pd(0.5), _CMP_GE_OQ), _mm256_set1_pd(1.0));
    return _mm256_cvttpd_epi32(_mm256_and_pd(_mm256_add_pd(f, up), inside));
}

// transformVertex on the four vertices p[0..4) at once with AVX2: OrthoView::toWindow, then
// insideClipVolume, snapToFixed and beyondSides, with the same double operations in the same
// order (no FMA), so the same numbers bit for bit. (The scalar reference path transforms one by
// one, so the Differential tests compare the two.)
__attribute__((target("avx2"))) void transformVertices4(const Vec3f* p, const OrthoView& view,
                                                        const SetupParams& params, WinVertex* window,
                                                        SnapVertex* snapped) {
    const __m256d px = _mm256_setr_pd(p[0].x(), p[1].x(), p[2].x(), p[3].x());
    const __m256d py = _mm256_setr_pd(p[0].y(), p[1].y(), p[2].y(), p[3].y());
    const __m256d pz = _mm256_setr_pd(p[0].z(), p[1].z(), p[2].z(), p[3].z());
    const __m256d x =
        scale4(dot4(view.right, px, py, pz), view.xmin, view.xmax, double(view.fullWidth()), double(view.originX));
    const __m256d y =
        scale4(dot4(view.up, px, py, pz), view.ymin, view.ymax, double(view.fullHeight()), double(view.originY));
    const __m256d z = _mm256_div_pd(_mm256_sub_pd(dot4(view.dir, px, py, pz), _mm256_set1_pd(view.znear)),
                                    _mm256_set1_pd(view.zfar - view.znear));
    // insideClipVolume (ordered comparisons: NaN is outside).
    const double g = guardBandPixels(params.subpixelBits);
    const __m256d zero = _mm256_setzero_pd(), G = _mm256_set1_pd(g), minusG = _mm256_set1_pd(-g);
    const __m256d inside = _mm256_and_pd(
        _mm256_and_pd(
            _mm256_and_pd(_mm256_cmp_pd(z, zero, _CMP_GE_OQ), _mm256_cmp_pd(z, _mm256_set1_pd(1.0), _CMP_LE_OQ)),
            _mm256_and_pd(_mm256_cmp_pd(x, minusG, _CMP_GE_OQ), _mm256_cmp_pd(x, G, _CMP_LE_OQ))),
        _mm256_and_pd(_mm256_cmp_pd(y, minusG, _CMP_GE_OQ), _mm256_cmp_pd(y, G, _CMP_LE_OQ)));
    const __m256d fixed = _mm256_set1_pd(double(int64_t(1) << params.subpixelBits));
    alignas(16) int32_t sx[4], sy[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(sx), snap4(x, fixed, inside));
    _mm_store_si128(reinterpret_cast<__m128i*>(sy), snap4(y, fixed, inside));
    const int in = _mm256_movemask_pd(inside);
    const int left = _mm256_movemask_pd(_mm256_cmp_pd(x, zero, _CMP_LT_OQ));
    const int right = _mm256_movemask_pd(_mm256_cmp_pd(x, _mm256_set1_pd(double(params.width)), _CMP_GT_OQ));
    const int bottom = _mm256_movemask_pd(_mm256_cmp_pd(y, zero, _CMP_LT_OQ));
    const int top = _mm256_movemask_pd(_mm256_cmp_pd(y, _mm256_set1_pd(double(params.height)), _CMP_GT_OQ));
    alignas(32) double wx[4], wy[4], wz[4];
    _mm256_store_pd(wx, x);
    _mm256_store_pd(wy, y);
    _mm256_store_pd(wz, z);
    for (int l = 0; l < 4; ++l) {
        window[l] = {wx[l], wy[l], wz[l]};
        SnapVertex& s = snapped[l];
        s.inside = (in >> l & 1) != 0;
        s.x = sx[l];
        s.y = sy[l];
        s.beyond = uint8_t(((left >> l & 1) ? detail::kBeyondLeft : 0) | ((right >> l & 1) ? detail::kBeyondRight : 0) |
                           ((bottom >> l & 1) ? detail::kBeyondBottom : 0) | ((top >> l & 1) ? detail::kBeyondTop : 0));
    }
}
#endif

class CpuBackendImpl final : public CpuBackend {
public:
    explicit CpuBackendImpl(const CpuBackendOptions& options)
        : options_(options),
          arena_(options.threads > 0 ? options.threads : tbb::task_arena::automatic),
          views_(options.viewCacheBytes) {}

    std::string describe() const override {
        std::string s = options_.scalarReference ? "cpu scalar reference" : "cpu reference";
        s += " (" + std::to_string(options_.subpixelBits) + " subpixel bits, " + toString(options_.fillRule) +
            " fill rule";
        if (!options_.scalarReference)
            s += ", " + std::to_string(options_.tileSize) + " px tiles, " +
                (options_.threads == 1      ? std::string("1 thread")
                     : options_.threads > 0 ? std::to_string(options_.threads) + " threads"
                                            : std::string("default threads"));
        return s + ")";
    }

    const CpuBackendOptions& options() const override { return options_; }
    const RasterStats& lastStats() const override { return stats_; }
    bool lastReplayedView() const override { return replayedView_; }
    bool lastRanDirect() const override { return directRan_; }
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
        dropViews();
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
        dropViews();
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
        direct_ = {};
        conservative_ = {};
        dropViews();
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
        replayedView_ = directRan_ = false;
        std::vector<uint64_t> results;
        inArena([&] {
            if (!options_.scalarReference)
                if (const detail::ViewFragments* v = cachedView(list)) {
                    results = executeFromView(list, *v);
                    replayedView_ = true;
                    return;
                }
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
            const bool batched = windowBatched();
            parallelFor(0, positions_.size(), 4096, [&](const tbb::blocked_range<size_t>& r) {
                size_t v = r.begin();
#ifdef CULLIDE_WINDOW_AVX2
                if (batched)
                    for (; v + 4 <= r.end(); v += 4)
                        transformVertices4(&positions_[v], view_, params_, &window_[v], &snapped_[v]);
#endif
                for (; v != r.end(); ++v) transformVertex(v);
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

    // Whether updateWindow transforms four vertices at a time (the fast path with simd, on a CPU with
    // AVX2): the scalar reference path keeps transformVertex, so the Differential tests compare the two.
    bool windowBatched() const {
#ifdef CULLIDE_WINDOW_AVX2
        return options_.simd && !options_.scalarReference && __builtin_cpu_supports("avx2");
#else
        return false;
#endif
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

    // Steps 3-7 (step 1 is execute's, step 2 updateWindow's), or the direct path; a list that
    // draws every triangle through the tiles also captures its fragments for later lists under
    // this view (view_cache.h).
    std::vector<uint64_t> executeFast(const CommandList& list) {
        // A list that draws each range once goes straight through (direct_path.h) on one thread,
        // and on several when its triangles are small; not captured (a capture of such a list
        // rasterizes every tile again: view_cache.h).
        const int threads = arena_.max_concurrency();
        directRan_ = options_.direct && detail::directEligible(list) &&
            (threads == 1 || detail::smallTriangles(list, triangles_, snapped_.data(), params_.subpixelBits));
        if (directRan_) {
            const detail::SetupInput in{triangles_, window_, snapped_, params_, grid_, options_.simd};
            return detail::executeDirect(list, in, rasterTable(), view_.depth, state_, depth_.data(), stats_, threads,
                                         &direct_);
        }
        detail::StateWalker walk(state_, list.queryCount());
        setupRecords(list);
        makeEvents(list, walk);
        const detail::FragLayout layout =
            detail::FragLayout::of(triangles_.size(), options_.tileSize, view_.width, view_.height, view_.depth);
        const bool capture = views_.accepting() && layout.placeBits > 0 &&
            detail::replayable(list) && detail::drawsEverything(plain_, triangles_.size());
        detail::ViewFragments v;
        if (capture) {
            v.view = view_;
            v.layout = layout;
            v.tiles.resize(grid_.count());
        }
        runTiles(capture ? &v : nullptr);
        if (capture) {
            detail::captureFlags(plain_, triangles_.size(), v);
            views_.add(std::move(v));
        }
        return sumQueries(list, walk);
    }

    // The captured fragments for the current view, when `list` may replay them.
    const detail::ViewFragments* cachedView(const CommandList& list) const {
        if (views_.empty() || !detail::replayable(list)) return nullptr;
        return views_.find(view_);
    }

    // Steps 5-7 from captured fragments: no setup, no records.
    std::vector<uint64_t> executeFromView(const CommandList& list, const detail::ViewFragments& v) {
        detail::StateWalker walk(state_, list.queryCount());
        detail::runFromView(list, v, grid_, view_.depth, walk, stats_, depth_.data(), view_.width, view_.height,
                            tileOut_);
        return sumQueries(list, walk);
    }

    void dropViews() { views_.clear(); }

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

    // The pixel loops for this view's depth format (tile_kernels.h).
    detail::RasterTable rasterTable() const {
        return detail::pickRasterTable(view_.depth.kind == DepthFormat::Kind::Float32, options_.simd);
    }

    // Step 6: one task per tile; with `capture`, each tile's fragments into it too.
    void runTiles(detail::ViewFragments* capture) {
        const detail::RasterTable table = rasterTable();
        const detail::TileJob job{events_,      plain_, conservative_, table,       view_.depth, view_.width,
                                  view_.height, grid_,  depth_.data(), ilo_.data(), ihi_.data()};
        parallelFor(0, grid_.count(), 1, [&](const tbb::blocked_range<size_t>& r) {
            detail::TileCapture notes;
            std::vector<detail::FragGroup> scratch;
            for (size_t tile = r.begin(); tile != r.end(); ++tile) {
                detail::FragCache& cache = frags_.local();
                if (!capture) {
                    detail::runTile(job, tile, cache, tileOut_[tile]);
                    continue;
                }
                notes.groupBegin.clear(), notes.groupEnd.clear(), notes.ok = true;
                detail::runTile(job, tile, cache, tileOut_[tile], &notes);
                // Before this thread's cache moves on to another tile.
                detail::captureTile(plain_, triangles_.size(), grid_, tile, view_.width, view_.height, cache, notes,
                                    table, depth_.data(), view_.depth.bits, capture->layout, scratch,
                                    capture->tiles[tile]);
            }
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
    // Captured fragments of the whole geometry per view (view_cache.h), within options_.viewCacheBytes.
    detail::ViewCache views_;
    bool replayedView_ = false;  // by the last execute()
    bool directRan_ = false;  // the last execute() took the direct path
    detail::DirectScratch direct_;
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
