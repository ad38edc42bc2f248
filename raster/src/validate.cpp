// Per-query intervals [certain, certain + ambiguous] and the comparing tee (cullide/raster/validate.h).
//
// The reference's rules are re-derived here from cullide/raster/rules.h (snapping, fill rule,
// depth plane, storage), for triangles that need no clipping; a triangle that needs clipping is
// treated as ambiguous over its bounding box (Cullide's fitted views never clip). References:
// the dEQP rasterization verifier (FULL / PARTIAL / NONE pixels, floor/ceil snapping of every
// vertex), docs/gl-rules.md#deqp.
#include "cullide/raster/validate.h"

#include "command_state.h"
#include "cullide/error.h"
#include "cullide/parallel.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace cullide::raster {

namespace {

struct WinV {
    double x, y, z;
};

// Stored value of a window depth, clamped (rule 7).
uint32_t enc(double z, const DepthFormat& f) {
    return encodeDepth(z, f);
}

// Interval of stored values of a clear depth: exact when representable, else +-1 step.
void clearInterval(double c, const DepthFormat& f, uint32_t& lo, uint32_t& hi) {
    const uint32_t k = enc(c, f);
    bool exact;
    if (f.kind == DepthFormat::Kind::Float32) exact = double(float(c)) == c;
    else exact = double(k) / (std::ldexp(1.0, f.bits) - 1.0) == c;
    lo = hi = k;
    if (!exact) {
        lo = k > 0 ? k - 1 : 0;
        hi = k < 0xFFFFFFFFu ? k + 1 : k;
    }
}

// Whether `incoming FUNC stored` holds for every / for some incoming in [a, b], stored in [s, t].
void intervalTest(DepthFunc f, uint32_t a, uint32_t b, uint32_t s, uint32_t t, bool& all, bool& some) {
    switch (f) {
        case DepthFunc::Never: all = some = false; return;
        case DepthFunc::Always: all = some = true; return;
        case DepthFunc::Less: all = b < s, some = a < t; return;
        case DepthFunc::LEqual: all = b <= s, some = a <= t; return;
        case DepthFunc::Greater: all = a > t, some = b > s; return;
        case DepthFunc::GEqual: all = a >= t, some = b >= s; return;
        case DepthFunc::Equal: all = a == b && s == t && a == s, some = a <= t && s <= b; return;
        case DepthFunc::NotEqual: all = b < s || t < a, some = !(a == b && s == t && a == s); return;
    }
    all = some = false;
}

// The reference's depth plane (rule 6): through the unsnapped double vertices, evaluated as
// (z0 + dzdy*(y - y0)) + dzdx*(x - x0).
struct Plane {
    double x0 = 0, y0 = 0, z0 = 0, dzdx = 0, dzdy = 0;
    bool valid = false;
    double at(double x, double y) const { return (z0 + dzdy * (y - y0)) + dzdx * (x - x0); }
};

Plane planeFrom(const WinV& p0, const WinV& p1, const WinV& p2) {
    Plane p;
    const double x1 = p1.x - p0.x, y1 = p1.y - p0.y, z1 = p1.z - p0.z;
    const double x2 = p2.x - p0.x, y2 = p2.y - p0.y, z2 = p2.z - p0.z;
    const double det = x1 * y2 - x2 * y1;
    if (det == 0.0 || !std::isfinite(det)) return p;
    p.x0 = p0.x, p.y0 = p0.y, p.z0 = p0.z;
    p.dzdx = (z1 * y2 - z2 * y1) / det;
    p.dzdy = (x1 * z2 - x2 * z1) / det;
    p.valid = std::isfinite(p.dzdx) && std::isfinite(p.dzdy);
    return p;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// execute(): bands of rows in parallel.
//
// A pixel's state (exactDepth_, lo_, hi_, writer_) depends only on the sequence of fragments at
// that pixel, in list order. So the image is split into bands of rows, each band walks the whole
// list on its own (clears fill its rows; each triangle is set up only in the bands its pixel
// range touches) and counts into its thread's counters; the per-query counts are integer sums,
// the same for any split and thread count. Phases, each a parallel loop over disjoint data:
//   1. window coordinates and snapped positions of every vertex;
//   2. (serial) the list's clears and draws with their state, and the draws' instance numbering;
//   3. per drawn triangle ("instance"): its pixel range and whether it needs clipping;
//   4. (serial) exactTrusted_ from the clipped flags, in list order; the band split;
//   5. binning of the instances to the bands they touch (count, prefix sum, fill: in order);
//   6. the bands.

namespace {

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

constexpr size_t kBinChunk = size_t(1) << 14;  // instances per binning task

}  // namespace

struct QueryIntervals::Impl {
    explicit Impl(int threads) : arena(threads > 0 ? threads : tbb::task_arena::automatic) {}
    tbb::task_arena arena;
    uint64_t generation = 0;
    tbb::enumerable_thread_specific<Local> locals;
    // Per-list scratch, capacity kept across lists.
    std::vector<Vert> vert;
    std::vector<Op> ops;
    std::vector<uint64_t> drawBase;  // base of each draw op, ascending
    std::vector<size_t> drawOp;  // its index in ops
    // Per triangle of the geometry (set for the triangles the list draws: a triangle drawn four
    // times is set up once).
    std::vector<PixelRange> range;
    std::vector<uint8_t> clipped;
    std::vector<std::array<uint32_t, 2>> drawn;  // the union of the draws' ranges, sorted, disjoint
    std::vector<uint64_t> drawnBase;  // per range of `drawn`: its first position in that union
    std::vector<int32_t> bandStart;  // band b: rows [bandStart[b], bandStart[b + 1])
    std::vector<int32_t> bandOfRow;
    std::vector<uint64_t> binPos;  // per (chunk, band): count, then write position
    std::vector<uint64_t> bandBegin;  // band b: binned[bandBegin[b], bandBegin[b + 1])
    std::vector<uint32_t> binned;  // instance numbers per band, ascending

    // Bands of `rows` rows, or, when 0, ~4 per thread of about equal work (the row-work
    // histogram of phase 3), at least kMinBandRows rows each so that few triangles are set up
    // in two bands. Only the speed depends on the split, never the results.
    void chooseBands(int width, int height, int rows) {
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

    // The draw of instance k (drawBase[d] <= k), and the triangle of instance k, advancing d
    // (instances are visited in increasing order).
    size_t drawOf(uint64_t k) const {
        return size_t(std::upper_bound(drawBase.begin(), drawBase.end(), k) - drawBase.begin()) - 1;
    }
    uint32_t triangleOf(uint64_t k, size_t& d) const {
        while (d + 1 < drawBase.size() && drawBase[d + 1] <= k) ++d;
        const Op& op = ops[drawOp[d]];
        return op.first + uint32_t(k - op.base);
    }

    Local& local(size_t queries, int height) {
        Local& l = locals.local();
        if (l.generation != generation) {
            l.generation = generation;
            l.counts.assign(3 * queries, 0);
            l.rowWork.assign(size_t(height) + 1, 0);
        }
        return l;
    }
};

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
    const uint32_t nq = list.queryCount();
    const int W = view_.width, H = view_.height, S = options_.subpixelBits;
    const DepthFormat& fmt = view_.depth;
    const int64_t one = int64_t(1) << S, half = one >> 1;
    const int64_t r = options_.otherSubpixelBits >= S ? 2 : (int64_t(1) << (S - options_.otherSubpixelBits)) + 1;
    const double res = fmt.resolution();
    const double floatUnit = std::ldexp(1.0, -24);
    if (capture) capture->classes.assign(size_t(W) * size_t(H), 0);
    ++im.generation;

    // Phase 2 first (serial, cheap): it throws on bad commands before any state changes.
    im.ops.clear();
    im.drawBase.clear();
    im.drawOp.clear();
    uint64_t instances = 0;
    std::vector<uint8_t> anySamples(nq);  // their counts become 0/1 at the end
    {
        detail::StateWalker walk(func_, mask_, nq);
        for (const Command& c : list.commands()) {
            if (walk.apply(c)) continue;
            switch (c.op) {
                case Command::Op::Clear: {
                    Op op;
                    op.clear = true;
                    op.clearDepth = c.clearDepth;
                    im.ops.push_back(op);
                    break;
                }
                case Command::Op::ClearIntervals:
                case Command::Op::DrawConservative:
                    throw InputError("command list",
                                     "validation covers the GL-like commands only, not conservative ones");
                case Command::Op::Draw: {
                    if (uint64_t(c.first) + c.count > triangles_.size())
                        throw InputError("command list", "draw range outside the geometry");
                    if (c.count == 0) break;
                    Op op;
                    op.first = c.first, op.count = c.count, op.base = instances;
                    op.func = walk.func(), op.mask = walk.mask(), op.query = walk.query();
                    im.drawBase.push_back(instances);
                    im.drawOp.push_back(im.ops.size());
                    im.ops.push_back(op);
                    instances += c.count;
                    break;
                }
                default: break;  // state commands: walk.apply
            }
        }
        if (instances > std::numeric_limits<uint32_t>::max())
            throw InputError("command list", "more than 2^32 - 1 drawn triangles in one list");
        for (uint32_t q = 0; q < nq; ++q) anySamples[q] = walk.anySamples(q);
    }
    const double G = guardBandPixels(S);
    auto inside = [&](const WinV& v) { return v.z >= 0 && v.z <= 1 && v.x >= -G && v.x <= G && v.y >= -G && v.y <= G; };

    std::vector<QueryInterval> out(nq);
    std::vector<uint64_t> ex(nq, 0);
    executeIn(im.arena, [&] {
        // Phase 1: window coordinates of every vertex (once per list; the view is fixed within it).
        im.vert.resize(positions_.size());
        parallelFor(0, positions_.size(), 4096, [&](const tbb::blocked_range<size_t>& rg) {
            for (size_t i = rg.begin(); i != rg.end(); ++i) {
                const Vec3d w = view_.toWindow(positions_[i]);
                Vert& v = im.vert[i];
                v.w = {w.x(), w.y(), w.z()};
                v.finite = std::isfinite(w.x()) && std::isfinite(w.y()) && std::isfinite(w.z());
                v.sx = snapToFixed(w.x(), S);
                v.sy = snapToFixed(w.y(), S);
            }
        });

        // Phase 3: per triangle drawn, its pixel range and clipped flag (rule 2's trivial
        // rejection first: nothing under any snapping either), and the row-work histogram.
        im.drawn.clear();
        for (const Op& op : im.ops)
            if (!op.clear) im.drawn.push_back({op.first, op.first + op.count});
        std::sort(im.drawn.begin(), im.drawn.end());
        size_t merged = 0;
        for (const auto& d : im.drawn) {
            if (merged > 0 && d[0] <= im.drawn[merged - 1][1])
                im.drawn[merged - 1][1] = std::max(im.drawn[merged - 1][1], d[1]);
            else im.drawn[merged++] = d;
        }
        im.drawn.resize(merged);
        im.drawnBase.assign(merged + 1, 0);
        for (size_t d = 0; d < merged; ++d) im.drawnBase[d + 1] = im.drawnBase[d] + (im.drawn[d][1] - im.drawn[d][0]);
        im.range.resize(triangles_.size());
        im.clipped.resize(triangles_.size());
        parallelFor(0, im.drawnBase.back(), 4096, [&](const tbb::blocked_range<size_t>& rg) {
            Local& l = im.local(nq, H);
            size_t d = size_t(std::upper_bound(im.drawnBase.begin(), im.drawnBase.end(), uint64_t(rg.begin())) -
                              im.drawnBase.begin()) -
                1;
            for (size_t k = rg.begin(); k != rg.end(); ++k) {
                while (im.drawnBase[d + 1] <= k) ++d;
                const uint32_t t = im.drawn[d][0] + uint32_t(k - im.drawnBase[d]);
                const Triangle& tri = triangles_[t];
                const Vert* v[3] = {&im.vert[tri[0]], &im.vert[tri[1]], &im.vert[tri[2]]};
                PixelRange& pr = im.range[t];
                pr = PixelRange{};
                im.clipped[t] = 0;
                if (!(v[0]->finite && v[1]->finite && v[2]->finite)) continue;
                const WinV &a = v[0]->w, &b = v[1]->w, &c = v[2]->w;
                if ((a.x < 0 && b.x < 0 && c.x < 0) || (a.x > W && b.x > W && c.x > W) ||
                    (a.y < 0 && b.y < 0 && c.y < 0) || (a.y > H && b.y > H && c.y > H) ||
                    (a.z < 0 && b.z < 0 && c.z < 0) || (a.z > 1 && b.z > 1 && c.z > 1))
                    continue;
                im.clipped[t] = !(inside(a) && inside(b) && inside(c));
                // Pixel range: the snapped bounding box grown by r units and one pixel.
                const int64_t minx = std::min({v[0]->sx, v[1]->sx, v[2]->sx}) - r,
                              maxx = std::max({v[0]->sx, v[1]->sx, v[2]->sx}) + r;
                const int64_t miny = std::min({v[0]->sy, v[1]->sy, v[2]->sy}) - r,
                              maxy = std::max({v[0]->sy, v[1]->sy, v[2]->sy}) + r;
                const int64_t i0 = std::max<int64_t>(((minx - half) >> S), 0),
                              i1 = std::min<int64_t>(((maxx - half) >> S) + 1, W - 1);
                const int64_t j0 = std::max<int64_t>(((miny - half) >> S), 0),
                              j1 = std::min<int64_t>(((maxy - half) >> S) + 1, H - 1);
                if (i0 > i1 || j0 > j1) continue;
                pr = {int32_t(i0), int32_t(i1), int32_t(j0), int32_t(j1)};
                const int64_t work = (i1 - i0 + 1) + 4;  // pixels per row, plus a share of the setup
                l.rowWork[size_t(j0)] += work;
                l.rowWork[size_t(j1) + 1] -= work;
            }
        });
    });

    // Phase 4: exactTrusted_ follows the list: a clear trusts, a clipped triangle distrusts
    // (whether or not any of its fragments counts).
    for (const Op& op : im.ops) {
        if (op.clear) exactTrusted_ = true;
        else if (exactTrusted_) {
            const uint8_t* c = im.clipped.data() + op.first;
            if (std::find(c, c + op.count, uint8_t(1)) != c + op.count) exactTrusted_ = false;
        }
    }
    im.chooseBands(W, H, options_.bandRows);

    const size_t bands = im.bandStart.size() - 1;
    executeIn(im.arena, [&] {
        // Phase 5: binning, in instance order within each band.
        const size_t chunks = (instances + kBinChunk - 1) / kBinChunk;
        im.binPos.assign(chunks * bands, 0);
        parallelFor(0, chunks, 1, [&](const tbb::blocked_range<size_t>& rg) {
            for (size_t ch = rg.begin(); ch != rg.end(); ++ch) {
                uint64_t* cnt = im.binPos.data() + ch * bands;
                const size_t end = std::min<size_t>(instances, (ch + 1) * kBinChunk);
                size_t d = im.drawOf(ch * kBinChunk);
                for (size_t k = ch * kBinChunk; k < end; ++k) {
                    const PixelRange& pr = im.range[im.triangleOf(k, d)];
                    if (pr.empty()) continue;
                    for (int32_t b = im.bandOfRow[size_t(pr.j0)]; b <= im.bandOfRow[size_t(pr.j1)]; ++b) ++cnt[b];
                }
            }
        });
        im.bandBegin.assign(bands + 1, 0);
        uint64_t pos = 0;
        for (size_t b = 0; b < bands; ++b) {
            im.bandBegin[b] = pos;
            for (size_t ch = 0; ch < chunks; ++ch) {
                const uint64_t n = im.binPos[ch * bands + b];
                im.binPos[ch * bands + b] = pos;
                pos += n;
            }
        }
        im.bandBegin[bands] = pos;
        im.binned.resize(pos);
        parallelFor(0, chunks, 1, [&](const tbb::blocked_range<size_t>& rg) {
            for (size_t ch = rg.begin(); ch != rg.end(); ++ch) {
                uint64_t* at = im.binPos.data() + ch * bands;
                const size_t end = std::min<size_t>(instances, (ch + 1) * kBinChunk);
                size_t d = im.drawOf(ch * kBinChunk);
                for (size_t k = ch * kBinChunk; k < end; ++k) {
                    const PixelRange& pr = im.range[im.triangleOf(k, d)];
                    if (pr.empty()) continue;
                    for (int32_t b = im.bandOfRow[size_t(pr.j0)]; b <= im.bandOfRow[size_t(pr.j1)]; ++b)
                        im.binned[at[b]++] = uint32_t(k);
                }
            }
        });

        // Phase 6: the bands.
        parallelFor(0, bands, 1, [&](const tbb::blocked_range<size_t>& rg) {
            for (size_t band = rg.begin(); band != rg.end(); ++band) {
                Local& l = im.local(nq, H);
                const int64_t r0 = im.bandStart[band], r1 = im.bandStart[band + 1] - 1;
                const size_t p0 = size_t(r0) * size_t(W), p1 = size_t(r1 + 1) * size_t(W);
                const uint32_t* it = im.binned.data() + im.bandBegin[band];
                const uint32_t* const itEnd = im.binned.data() + im.bandBegin[band + 1];
                for (const Op& op : im.ops) {
                    if (op.clear) {
                        uint32_t a, b;
                        clearInterval(op.clearDepth, fmt, a, b);
                        std::fill(exactDepth_.begin() + p0, exactDepth_.begin() + p1, enc(op.clearDepth, fmt));
                        std::fill(lo_.begin() + p0, lo_.begin() + p1, a);
                        std::fill(hi_.begin() + p0, hi_.begin() + p1, b);
                        std::fill(writer_.begin() + p0, writer_.begin() + p1, -1);
                        continue;
                    }
                    const uint64_t stop = op.base + op.count;
                    const DepthFunc func = op.func;
                    const bool mask = op.mask;
                    const int64_t query = op.query;
                    uint64_t* qc = query >= 0 ? l.counts.data() + 3 * size_t(query) : nullptr;
                    uint8_t* cap = capture && query == int64_t(capture->query) ? capture->classes.data() : nullptr;
                    for (; it != itEnd && *it < stop; ++it) {
                        const uint32_t k = *it;
                        const uint32_t t = op.first + uint32_t(k - op.base);
                        const PixelRange& pr = im.range[t];
                        const bool clipped = im.clipped[t] != 0;
                        const Triangle& tri = triangles_[t];
                        const Vert* vv[3] = {&im.vert[tri[0]], &im.vert[tri[1]], &im.vert[tri[2]]};
                        const WinV v[3] = {vv[0]->w, vv[1]->w, vv[2]->w};
                        const int64_t sx[3] = {vv[0]->sx, vv[1]->sx, vv[2]->sx};
                        const int64_t sy[3] = {vv[0]->sy, vv[1]->sy, vv[2]->sy};
                        const int64_t area2 = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
                        int o[3] = {0, 1, 2};
                        if (area2 < 0) std::swap(o[1], o[2]);
                        // The reference's plane (with its fallback to the snapped vertices when the
                        // double vertices are collinear).
                        Plane plane = planeFrom(v[0], v[1], v[2]);
                        if (!plane.valid && area2 != 0) {
                            const double unit = std::ldexp(1.0, -S);
                            WinV s3[3];
                            for (int q = 0; q < 3; ++q)
                                s3[q] = {double(sx[o[q]]) * unit, double(sy[o[q]]) * unit, v[o[q]].z};
                            plane = planeFrom(s3[0], s3[1], s3[2]);
                            if (!plane.valid) plane = {s3[0].x, s3[0].y, s3[0].z, 0.0, 0.0, true};
                        }
                        const double zmin = std::min({v[0].z, v[1].z, v[2].z}),
                                     zmax = std::max({v[0].z, v[1].z, v[2].z});
                        const double slopeMargin = plane.valid ? options_.depthFloatUlps * floatUnit *
                                (1.0 + (std::abs(plane.dzdx) + std::abs(plane.dzdy)) * double(W + H))
                                                               : 0.0;
                        const double depthMargin = options_.depthLsb * res + slopeMargin;
                        // Edges of the oriented snapped triangle.
                        int64_t ax[3], ay[3], dx[3], dy[3], dl1[3];
                        bool incl[3];
                        for (int q = 0; q < 3; ++q) {
                            const int a = o[q], b = o[(q + 1) % 3];
                            ax[q] = sx[a], ay[q] = sy[a];
                            dx[q] = sx[b] - sx[a], dy[q] = sy[b] - sy[a];
                            dl1[q] = std::abs(dx[q]) + std::abs(dy[q]);
                            incl[q] = isInclusiveEdge(options_.fillRule, dx[q], dy[q]);
                        }
                        const int64_t j0 = std::max<int64_t>(pr.j0, r0), j1 = std::min<int64_t>(pr.j1, r1);
                        for (int64_t j = j0; j <= j1; ++j) {
                            const int64_t py = j * one + half;
                            for (int64_t i = pr.i0; i <= pr.i1; ++i) {
                                const int64_t px = i * one + half;
                                // A clipped triangle is possible everywhere in its box and never
                                // certain nor exact: its edges need not be evaluated.
                                bool certain = false, possible = true, exactCov = false;
                                if (!clipped) {
                                    bool posA = true, posB = true;
                                    certain = area2 != 0, exactCov = area2 != 0;
                                    for (int q = 0; q < 3; ++q) {
                                        const int64_t e = dx[q] * (py - ay[q]) - dy[q] * (px - ax[q]);
                                        const int64_t da = std::abs(px - ax[q]) + std::abs(py - ay[q]);
                                        const int64_t db = std::abs(px - ax[q] - dx[q]) + std::abs(py - ay[q] - dy[q]);
                                        const int64_t m = r * dl1[q] + 2 * r * std::min(da, db) + 4 * r * r;
                                        certain = certain && e > m;
                                        posA = posA && e >= -m;
                                        posB = posB && e <= m;
                                        exactCov = exactCov && (e > 0 || (e == 0 && incl[q]));
                                    }
                                    possible = posA || posB;
                                }
                                if (!possible) continue;
                                const size_t idx = size_t(j) * size_t(W) + size_t(i);
                                const double xc = double(i) + 0.5, yc = double(j) + 0.5;
                                uint32_t a, b, inc = 0;
                                if (plane.valid && !clipped) {
                                    const double z = clampDepth(plane.at(xc, yc));
                                    inc = enc(z, fmt);
                                    a = enc(z - depthMargin, fmt);
                                    b = enc(z + depthMargin, fmt);
                                } else {
                                    a = enc(zmin - depthMargin, fmt);
                                    b = enc(zmax + depthMargin, fmt);
                                    exactCov = false;
                                }
                                // The exact track.
                                if (exactCov && depthTest(func, inc, exactDepth_[idx])) {
                                    if (qc) ++qc[2];
                                    if (mask) exactDepth_[idx] = inc;
                                    if (cap) cap[idx] |= 4;
                                }
                                bool all, some;
                                if (writer_[idx] == int64_t(t)) {
                                    // The stored value was certainly written by this very triangle:
                                    // GL's invariance rules (same primitive, same vertex data, only
                                    // the depth function or mask changed) make the incoming depth
                                    // equal to it, whatever its exact value.
                                    all = some = depthTest(func, lo_[idx], lo_[idx]);
                                    a = lo_[idx], b = hi_[idx];
                                } else {
                                    intervalTest(func, a, b, lo_[idx], hi_[idx], all, some);
                                }
                                const bool surely = certain && all, maybe = some;  // `possible` holds here
                                if (qc) {
                                    if (surely) ++qc[0];
                                    if (maybe) ++qc[1];
                                    if (cap) cap[idx] |= uint8_t((surely ? 1 : 0) | (maybe ? 2 : 0));
                                }
                                if (mask) {
                                    if (surely) {
                                        lo_[idx] = a, hi_[idx] = b;
                                        writer_[idx] = int64_t(t);
                                    } else if (maybe) {
                                        lo_[idx] = std::min(lo_[idx], a), hi_[idx] = std::max(hi_[idx], b);
                                        writer_[idx] = -1;
                                    }
                                }
                            }
                        }
                    }
                }
            }
        });
    });

    // The per-worker counts, summed (integers: the same in any order).
    for (Local& l : im.locals) {
        if (l.generation != im.generation) continue;
        for (uint32_t q = 0; q < nq; ++q) {
            out[q].certain += l.counts[3 * q];
            out[q].possible += l.counts[3 * q + 1];
            ex[q] += l.counts[3 * q + 2];
        }
    }
    for (uint32_t q = 0; q < nq; ++q) {
        if (anySamples[q]) {
            out[q].certain = out[q].certain > 0 ? 1 : 0;
            out[q].possible = out[q].possible > 0 ? 1 : 0;
            ex[q] = ex[q] > 0 ? 1 : 0;
        }
    }
    if (exact) *exact = std::move(ex);
    if (exactValid) *exactValid = exactTrusted_;
    return out;
}

// ---------------------------------------------------------------------------------------------
// TeeBackend

TeeBackend::TeeBackend(DepthBackend& reference, DepthBackend& other, const IntervalOptions& options)
    : reference_(reference), other_(other), intervals_(options) {}

std::string TeeBackend::describe() const {
    return "tee: " + reference_.describe() + " | " + other_.describe();
}

void TeeBackend::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    reference_.setGeometry(positions, triangles);
    other_.setGeometry(positions, triangles);
    intervals_.setGeometry(positions, triangles);
}

void TeeBackend::setView(const OrthoView& view) {
    reference_.setView(view);
    other_.setView(view);
    intervals_.setView(view);
    view_ = view;
}

std::vector<uint64_t> TeeBackend::execute(const CommandList& list) {
    std::vector<uint64_t> ref = reference_.execute(list);
    const std::vector<uint64_t> oth = other_.execute(list);
    std::vector<uint64_t> exact;
    bool exactValid = false;
    CoverageCapture capture;
    const int64_t want = onCapture ? onCapture(frame_, list_) : -1;
    capture.query = want >= 0 ? uint32_t(want) : 0;
    const std::vector<QueryInterval> iv = intervals_.execute(list, &exact, &exactValid, want >= 0 ? &capture : nullptr);
    std::vector<QueryKind> kinds;
    for (const Command& c : list.commands())
        if (c.op == Command::Op::BeginQuery) kinds.push_back(c.queryKind);
    for (uint32_t q = 0; q < ref.size(); ++q) {
        QueryComparison cmp;
        cmp.frame = frame_;
        cmp.list = list_;
        cmp.query = q;
        cmp.kind = kinds[q];
        cmp.reference = ref[q];
        cmp.other = oth[q];
        cmp.interval = iv[q];
        if (exactValid) {
            ++selfChecked_;
            if (exact[q] != ref[q]) ++selfCheckMismatches_;
        }
        comparisons_.push_back(cmp);
        if (want == int64_t(q) && captured) captured(cmp, capture, view_);
    }
    ++list_;
    return ref;
}

DepthImage TeeBackend::readDepth() {
    return reference_.readDepth();
}

void TeeBackend::readDepthInto(DepthImage& out) {
    reference_.readDepthInto(out);
}

}  // namespace cullide::raster
