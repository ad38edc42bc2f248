// The interval evaluator (cullide/raster/validate.h): its state across lists, and execute()'s
// phases 1 to 5 and the sums (interval_pipeline.h); phase 6, the bands, is interval_bands.cpp.
//
// The reference's rules are re-derived here from cullide/raster/rules.h (snapping, fill rule,
// depth plane, storage), for triangles that need no clipping; a triangle that needs clipping is
// treated as ambiguous over its bounding box (Cullide's fitted views never clip). References:
// the dEQP rasterization verifier (FULL / PARTIAL / NONE pixels, floor/ceil snapping of every
// vertex), docs/gl-rules.md#deqp.
#include "cullide/raster/validate.h"

#include "interval_pipeline.h"

#include "command_state.h"
#include "cullide/error.h"
#include "cullide/parallel.h"

#include <oneapi/tbb/blocked_range.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace cullide::raster {

using namespace intervals;

namespace intervals {

ListParams listParams(const OrthoView& view, const IntervalOptions& options, uint32_t queries) {
    ListParams p;
    p.W = view.width, p.H = view.height, p.S = options.subpixelBits;
    p.one = int64_t(1) << p.S, p.half = p.one >> 1;
    p.r = options.otherSubpixelBits >= p.S ? 2 : (int64_t(1) << (p.S - options.otherSubpixelBits)) + 1;
    p.fmt = view.depth;
    p.res = p.fmt.resolution();
    p.floatUnit = std::ldexp(1.0, -24);
    p.G = guardBandPixels(p.S);
    p.nq = queries;
    p.options = options;
    return p;
}

}  // namespace intervals

namespace {

// Whether a window vertex needs no clipping: within the depth range and the guard band.
bool insideGuardBand(const WinV& v, double G) {
    return v.z >= 0 && v.z <= 1 && v.x >= -G && v.x <= G && v.y >= -G && v.y <= G;
}

}  // namespace

QueryIntervals::~QueryIntervals() = default;
QueryIntervals::QueryIntervals(QueryIntervals&&) noexcept = default;
QueryIntervals& QueryIntervals::operator=(QueryIntervals&&) noexcept = default;

QueryIntervals::QueryIntervals(const IntervalOptions& options) : options_(options) {
    if (options.subpixelBits < kMinSubpixelBits || options.subpixelBits > kMaxSubpixelBits ||
        options.otherSubpixelBits < 1 || !(options.depthLsb >= 0) || !(options.depthFloatUlps >= 0))
        throw InputError("interval options", "subpixel bits or depth margins out of range");
    if (options.threads < 0 || options.threads > 1024)
        throw InputError("interval options",
                         "threads must be 0 (default) to 1024, got " + std::to_string(options.threads));
    if (options.bandRows < 0) throw InputError("interval options", "band rows must be 0 (automatic) or positive");
    impl_ = std::make_unique<Impl>(options.threads);
}

void QueryIntervals::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    // New vectors, not assign(): a smaller geometry (the empty one a recorder sets between
    // frames) gives its memory back.
    positions_ = std::vector<Vec3f>(positions.begin(), positions.end());
    triangles_ = std::vector<Triangle>(triangles.begin(), triangles.end());
}

void QueryIntervals::setGeometry(std::vector<Vec3f>&& positions, std::vector<Triangle>&& triangles) {
    positions_ = std::move(positions);
    triangles_ = std::move(triangles);
}

void QueryIntervals::setView(const OrthoView& view) {
    view.validate();
    if (!haveView_ || view.width != view_.width || view.height != view_.height || !(view.depth == view_.depth)) {
        const size_t n = size_t(view.width) * size_t(view.height);
        const uint32_t far = enc(1.0, view.depth);
        exactDepth_.assign(n, far);
        lo_.assign(n, far);
        hi_.assign(n, far);
        writer_.assign(n, -1);
        exactTrusted_ = true;
    }
    view_ = view;
    haveView_ = true;
}

void QueryIntervals::releaseScratch() {
    Impl& im = *impl_;
    im.locals.clear();
    std::vector<Vert>().swap(im.vert);
    std::vector<Op>().swap(im.ops);
    std::vector<uint64_t>().swap(im.drawBase);
    std::vector<size_t>().swap(im.drawOp);
    std::vector<PixelRange>().swap(im.range);
    std::vector<uint8_t>().swap(im.clipped);
    std::vector<std::array<uint32_t, 2>>().swap(im.drawn);
    std::vector<uint64_t>().swap(im.drawnBase);
    std::vector<uint64_t>().swap(im.binPos);
    std::vector<uint64_t>().swap(im.bandBegin);
    std::vector<uint32_t>().swap(im.binned);
}

std::vector<QueryInterval> QueryIntervals::execute(const CommandList& list, std::vector<uint64_t>* exact,
                                                   bool* exactValid, CoverageCapture* capture) {
    if (!haveView_) throw InputError("command list", "execute() before setView()");
    Impl& im = *impl_;
    const ListParams p = listParams(view_, options_, list.queryCount());
    if (capture) capture->classes.assign(size_t(p.W) * size_t(p.H), 0);
    ++im.generation;

    // Phase 2 first (serial, cheap): it throws on bad commands before any state changes.
    std::vector<uint8_t> anySamples(p.nq);  // their counts become 0/1 at the end
    const uint64_t instances = im.collectOps(list, triangles_.size(), func_, mask_, anySamples);
    executeIn(im.arena, [&] {
        im.windowVertices(positions_, view_, p.S);
        im.setUpRanges(triangles_, p);
    });
    exactTrusted_ = im.trustAfter(exactTrusted_);
    im.chooseBands(p.W, p.H, options_.bandRows);
    const PixelState pixels{exactDepth_.data(), lo_.data(), hi_.data(), writer_.data()};
    executeIn(im.arena, [&] {
        im.binInstances(instances);
        im.runBands(triangles_, p, pixels, capture);
    });

    std::vector<uint64_t> ex;
    std::vector<QueryInterval> out = im.sumCounts(p.nq, anySamples, ex);
    if (exact) *exact = std::move(ex);
    if (exactValid) *exactValid = exactTrusted_;
    return out;
}

uint64_t QueryIntervals::Impl::collectOps(const CommandList& list, size_t triangleCount, DepthFunc& func, bool& mask,
                                          std::vector<uint8_t>& anySamples) {
    ops.clear();
    drawBase.clear();
    drawOp.clear();
    uint64_t instances = 0;
    detail::StateWalker walk(func, mask, anySamples.size());
    for (const Command& c : list.commands()) {
        if (walk.apply(c)) continue;
        switch (c.op) {
            case Command::Op::Clear: {
                Op op;
                op.clear = true;
                op.clearDepth = c.clearDepth;
                ops.push_back(op);
                break;
            }
            case Command::Op::ClearIntervals:
            case Command::Op::DrawConservative:
                throw InputError("command list", "validation covers the GL-like commands only, not conservative ones");
            case Command::Op::Draw: {
                if (uint64_t(c.first) + c.count > triangleCount)
                    throw InputError("command list", "draw range outside the geometry");
                if (c.count == 0) break;
                Op op;
                op.first = c.first, op.count = c.count, op.base = instances;
                op.func = walk.func(), op.mask = walk.mask(), op.query = walk.query();
                drawBase.push_back(instances);
                drawOp.push_back(ops.size());
                ops.push_back(op);
                instances += c.count;
                break;
            }
            default: break;  // state commands: walk.apply
        }
    }
    if (instances > std::numeric_limits<uint32_t>::max())
        throw InputError("command list", "more than 2^32 - 1 drawn triangles in one list");
    for (size_t q = 0; q < anySamples.size(); ++q) anySamples[q] = walk.anySamples(q);
    return instances;
}

void QueryIntervals::Impl::windowVertices(std::span<const Vec3f> positions, const OrthoView& view, int S) {
    vert.resize(positions.size());
    parallelFor(0, positions.size(), 4096, [&](const tbb::blocked_range<size_t>& rg) {
        for (size_t i = rg.begin(); i != rg.end(); ++i) {
            const Vec3d w = view.toWindow(positions[i]);
            Vert& v = vert[i];
            v.w = {w.x(), w.y(), w.z()};
            v.finite = std::isfinite(w.x()) && std::isfinite(w.y()) && std::isfinite(w.z());
            v.sx = snapToFixed(w.x(), S);
            v.sy = snapToFixed(w.y(), S);
        }
    });
}

void QueryIntervals::Impl::setUpRanges(std::span<const Triangle> triangles, const ListParams& p) {
    // The union of the draws' ranges: a triangle drawn several times is set up once.
    drawn.clear();
    for (const Op& op : ops)
        if (!op.clear) drawn.push_back({op.first, op.first + op.count});
    std::sort(drawn.begin(), drawn.end());
    size_t merged = 0;
    for (const auto& d : drawn) {
        if (merged > 0 && d[0] <= drawn[merged - 1][1]) drawn[merged - 1][1] = std::max(drawn[merged - 1][1], d[1]);
        else drawn[merged++] = d;
    }
    drawn.resize(merged);
    drawnBase.assign(merged + 1, 0);
    for (size_t d = 0; d < merged; ++d) drawnBase[d + 1] = drawnBase[d] + (drawn[d][1] - drawn[d][0]);
    range.resize(triangles.size());
    clipped.resize(triangles.size());
    parallelFor(0, drawnBase.back(), 4096, [&](const tbb::blocked_range<size_t>& rg) {
        Local& l = local(p.nq, p.H);
        size_t d =
            size_t(std::upper_bound(drawnBase.begin(), drawnBase.end(), uint64_t(rg.begin())) - drawnBase.begin()) - 1;
        for (size_t k = rg.begin(); k != rg.end(); ++k) {
            while (drawnBase[d + 1] <= k) ++d;
            const uint32_t t = drawn[d][0] + uint32_t(k - drawnBase[d]);
            setUpRange(t, p, triangles[t], l);
        }
    });
}

// Triangle t's pixel range and clipped flag (rule 2's trivial rejection first: nothing under any
// snapping either), and its share of the row-work histogram.
void QueryIntervals::Impl::setUpRange(uint32_t t, const ListParams& p, const Triangle& tri, Local& l) {
    const int W = p.W, H = p.H, S = p.S;
    const int64_t r = p.r, half = p.half;
    const Vert* v[3] = {&vert[tri[0]], &vert[tri[1]], &vert[tri[2]]};
    PixelRange& pr = range[t];
    pr = PixelRange{};
    clipped[t] = 0;
    if (!(v[0]->finite && v[1]->finite && v[2]->finite)) return;
    const WinV &a = v[0]->w, &b = v[1]->w, &c = v[2]->w;
    if ((a.x < 0 && b.x < 0 && c.x < 0) || (a.x > W && b.x > W && c.x > W) || (a.y < 0 && b.y < 0 && c.y < 0) ||
        (a.y > H && b.y > H && c.y > H) || (a.z < 0 && b.z < 0 && c.z < 0) || (a.z > 1 && b.z > 1 && c.z > 1))
        return;
    clipped[t] = !(insideGuardBand(a, p.G) && insideGuardBand(b, p.G) && insideGuardBand(c, p.G));
    // Pixel range: the snapped bounding box grown by r units and one pixel.
    const int64_t minx = std::min({v[0]->sx, v[1]->sx, v[2]->sx}) - r,
                  maxx = std::max({v[0]->sx, v[1]->sx, v[2]->sx}) + r;
    const int64_t miny = std::min({v[0]->sy, v[1]->sy, v[2]->sy}) - r,
                  maxy = std::max({v[0]->sy, v[1]->sy, v[2]->sy}) + r;
    const int64_t i0 = std::max<int64_t>(((minx - half) >> S), 0),
                  i1 = std::min<int64_t>(((maxx - half) >> S) + 1, W - 1);
    const int64_t j0 = std::max<int64_t>(((miny - half) >> S), 0),
                  j1 = std::min<int64_t>(((maxy - half) >> S) + 1, H - 1);
    if (i0 > i1 || j0 > j1) return;
    pr = {int32_t(i0), int32_t(i1), int32_t(j0), int32_t(j1)};
    const int64_t work = (i1 - i0 + 1) + 4;  // pixels per row, plus a share of the setup
    l.rowWork[size_t(j0)] += work;
    l.rowWork[size_t(j1) + 1] -= work;
}

// The exact track follows the list: a clear trusts, a clipped triangle distrusts (whether or not
// any of its fragments counts).
bool QueryIntervals::Impl::trustAfter(bool trusted) const {
    for (const Op& op : ops) {
        if (op.clear) trusted = true;
        else if (trusted) {
            const uint8_t* c = clipped.data() + op.first;
            if (std::find(c, c + op.count, uint8_t(1)) != c + op.count) trusted = false;
        }
    }
    return trusted;
}

void QueryIntervals::Impl::chooseBands(int width, int height, int rows) {
    static constexpr int kMinBandRows = 8;
    bandStart.clear();
    const int threads = arena.max_concurrency();
    if (rows > 0) {
        for (int j = 0; j < height; j += rows) bandStart.push_back(j);
    } else if (threads <= 1 || height <= kMinBandRows) {
        bandStart.push_back(0);
    } else {
        std::vector<int64_t> work(size_t(height) + 1, 0);
        for (const Local& l : locals)
            if (l.generation == generation)
                for (size_t j = 0; j <= size_t(height); ++j) work[j] += l.rowWork[j];
        int64_t running = 0, total = 0;
        for (size_t j = 0; j < size_t(height); ++j) {
            running += work[j];
            work[j] = running + width / 64 + 1;  // clears and empty rows cost a little too
            total += work[j];
        }
        const int64_t per = std::max<int64_t>(1, total / (4 * int64_t(threads)));
        int64_t acc = 0;
        bandStart.push_back(0);
        for (int j = 0; j < height; ++j) {
            acc += work[size_t(j)];
            if (acc >= per && j + 1 - bandStart.back() >= kMinBandRows && height - (j + 1) >= kMinBandRows) {
                bandStart.push_back(j + 1);
                acc = 0;
            }
        }
    }
    bandStart.push_back(height);
    bandOfRow.resize(size_t(height));
    for (size_t b = 0; b + 1 < bandStart.size(); ++b)
        for (int j = bandStart[b]; j < bandStart[b + 1]; ++j) bandOfRow[size_t(j)] = int32_t(b);
}

void QueryIntervals::Impl::binInstances(uint64_t instances) {
    const size_t bands = bandStart.size() - 1;
    const size_t chunks = (instances + kBinChunk - 1) / kBinChunk;
    // Calls visit(k, band) for every instance k of chunk ch and every band its pixel range touches,
    // in instance order.
    auto forChunk = [&](size_t ch, auto&& visit) {
        const size_t end = std::min<size_t>(instances, (ch + 1) * kBinChunk);
        size_t d = drawOf(ch * kBinChunk);
        for (size_t k = ch * kBinChunk; k < end; ++k) {
            const PixelRange& pr = range[triangleOf(k, d)];
            if (pr.empty()) continue;
            for (int32_t b = bandOfRow[size_t(pr.j0)]; b <= bandOfRow[size_t(pr.j1)]; ++b) visit(k, b);
        }
    };
    binPos.assign(chunks * bands, 0);
    parallelFor(0, chunks, 1, [&](const tbb::blocked_range<size_t>& rg) {
        for (size_t ch = rg.begin(); ch != rg.end(); ++ch) {
            uint64_t* cnt = binPos.data() + ch * bands;
            forChunk(ch, [&](size_t, int32_t b) { ++cnt[b]; });
        }
    });
    bandBegin.assign(bands + 1, 0);
    uint64_t pos = 0;
    for (size_t b = 0; b < bands; ++b) {
        bandBegin[b] = pos;
        for (size_t ch = 0; ch < chunks; ++ch) {
            const uint64_t n = binPos[ch * bands + b];
            binPos[ch * bands + b] = pos;
            pos += n;
        }
    }
    bandBegin[bands] = pos;
    binned.resize(pos);
    parallelFor(0, chunks, 1, [&](const tbb::blocked_range<size_t>& rg) {
        for (size_t ch = rg.begin(); ch != rg.end(); ++ch) {
            uint64_t* at = binPos.data() + ch * bands;
            forChunk(ch, [&](size_t k, int32_t b) { binned[at[b]++] = uint32_t(k); });
        }
    });
}

std::vector<QueryInterval> QueryIntervals::Impl::sumCounts(uint32_t nq, const std::vector<uint8_t>& anySamples,
                                                           std::vector<uint64_t>& exact) {
    // The per-worker counts, summed (integers: the same in any order).
    std::vector<QueryInterval> out(nq);
    exact.assign(nq, 0);
    for (Local& l : locals) {
        if (l.generation != generation) continue;
        for (uint32_t q = 0; q < nq; ++q) {
            out[q].certain += l.counts[3 * q];
            out[q].possible += l.counts[3 * q + 1];
            exact[q] += l.counts[3 * q + 2];
        }
    }
    for (uint32_t q = 0; q < nq; ++q) {
        if (anySamples[q]) {
            out[q].certain = out[q].certain > 0 ? 1 : 0;
            out[q].possible = out[q].possible > 0 ? 1 : 0;
            exact[q] = exact[q] > 0 ? 1 : 0;
        }
    }
    return out;
}

}  // namespace cullide::raster
