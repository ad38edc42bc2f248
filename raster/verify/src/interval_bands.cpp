// Phase 6 of the interval evaluator's execute() (interval_pipeline.h): each band of rows walks the
// whole list, in order, over its own rows. A clear fills the band's rows; a draw tests each of its
// triangles binned to the band at every pixel of its range within the band: whether the pixel is
// certainly, possibly and exactly covered (the margins of validate.h), and whether its fragment
// certainly or possibly passes the depth test against the stored interval, which it then updates.
#include "interval_pipeline.h"

#include "cullide/parallel.h"

#include <oneapi/tbb/blocked_range.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <utility>

namespace cullide::raster {

using namespace intervals;

namespace {

// A drawn triangle as a band tests it: its oriented snapped edges, the reference's depth plane
// and the depth margins.
struct TriangleTest {
    uint32_t t = 0;  // the triangle's number in the geometry
    bool clipped = false;
    int64_t area2 = 0;  // twice the snapped signed area
    Plane plane;
    double zmin = 0, zmax = 0;
    double depthMargin = 0;
    int64_t ax[3], ay[3], dx[3], dy[3], dl1[3];  // per edge: its start, its direction, |d|_1
    bool incl[3];  // per edge: whether the fill rule includes it
};

TriangleTest setUpTest(uint32_t t, bool clipped, const Vert* const vv[3], const ListParams& p) {
    const IntervalOptions& options = p.options;
    TriangleTest e;
    e.t = t;
    e.clipped = clipped;
    const WinV v[3] = {vv[0]->w, vv[1]->w, vv[2]->w};
    const int64_t sx[3] = {vv[0]->sx, vv[1]->sx, vv[2]->sx};
    const int64_t sy[3] = {vv[0]->sy, vv[1]->sy, vv[2]->sy};
    e.area2 = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
    int o[3] = {0, 1, 2};
    if (e.area2 < 0) std::swap(o[1], o[2]);
    // The reference's plane (with its fallback to the snapped vertices when the double vertices
    // are collinear).
    e.plane = planeFrom(v[0], v[1], v[2]);
    if (!e.plane.valid && e.area2 != 0) {
        const double unit = std::ldexp(1.0, -p.S);
        WinV s3[3];
        for (int q = 0; q < 3; ++q) s3[q] = {double(sx[o[q]]) * unit, double(sy[o[q]]) * unit, v[o[q]].z};
        e.plane = planeFrom(s3[0], s3[1], s3[2]);
        if (!e.plane.valid) e.plane = {s3[0].x, s3[0].y, s3[0].z, 0.0, 0.0, true};
    }
    e.zmin = std::min({v[0].z, v[1].z, v[2].z});
    e.zmax = std::max({v[0].z, v[1].z, v[2].z});
    const double slopeMargin = e.plane.valid ? options.depthFloatUlps * p.floatUnit *
            (1.0 + (std::abs(e.plane.dzdx) + std::abs(e.plane.dzdy)) * double(p.W + p.H))
                                             : 0.0;
    e.depthMargin = options.depthLsb * p.res + slopeMargin;
    // Edges of the oriented snapped triangle.
    for (int q = 0; q < 3; ++q) {
        const int a = o[q], b = o[(q + 1) % 3];
        e.ax[q] = sx[a], e.ay[q] = sy[a];
        e.dx[q] = sx[b] - sx[a], e.dy[q] = sy[b] - sy[a];
        e.dl1[q] = std::abs(e.dx[q]) + std::abs(e.dy[q]);
        e.incl[q] = isInclusiveEdge(options.fillRule, e.dx[q], e.dy[q]);
    }
    return e;
}

// Whether the pixel centre (px, py) (in units of 2^-S px) is covered under every allowed freedom,
// under some, and by the reference's own rules.
struct Coverage {
    bool certain = false, possible = true, exact = false;
};

Coverage coverageAt(const TriangleTest& e, int64_t px, int64_t py, int64_t r) {
    // A clipped triangle is possible everywhere in its box and never certain nor exact: its edges
    // need not be evaluated.
    Coverage c;
    if (e.clipped) return c;
    bool posA = true, posB = true;
    c.certain = e.area2 != 0, c.exact = e.area2 != 0;
    for (int q = 0; q < 3; ++q) {
        const int64_t ed = e.dx[q] * (py - e.ay[q]) - e.dy[q] * (px - e.ax[q]);
        const int64_t da = std::abs(px - e.ax[q]) + std::abs(py - e.ay[q]);
        const int64_t db = std::abs(px - e.ax[q] - e.dx[q]) + std::abs(py - e.ay[q] - e.dy[q]);
        const int64_t m = r * e.dl1[q] + 2 * r * std::min(da, db) + 4 * r * r;
        c.certain = c.certain && ed > m;
        posA = posA && ed >= -m;
        posB = posB && ed <= m;
        c.exact = c.exact && (ed > 0 || (ed == 0 && e.incl[q]));
    }
    c.possible = posA || posB;
    return c;
}

// The draw a fragment belongs to: its state, its query's counters (certain, possible, exact) and
// the capture's classes when this is the captured query (else null).
struct DrawState {
    DepthFunc func;
    bool mask;
    uint64_t* qc;
    uint8_t* cap;
};

// One possible fragment at pixel idx (centre (xc, yc)): the exact track, the interval depth test
// and the stored interval's update.
void shadeFragment(const TriangleTest& e, Coverage cov, size_t idx, double xc, double yc, const DrawState& d,
                   const PixelState& px, const DepthFormat& fmt) {
    uint32_t a, b, inc = 0;
    if (e.plane.valid && !e.clipped) {
        const double z = clampDepth(e.plane.at(xc, yc));
        inc = enc(z, fmt);
        a = enc(z - e.depthMargin, fmt);
        b = enc(z + e.depthMargin, fmt);
    } else {
        a = enc(e.zmin - e.depthMargin, fmt);
        b = enc(e.zmax + e.depthMargin, fmt);
        cov.exact = false;
    }
    // The exact track.
    if (cov.exact && depthTest(d.func, inc, px.exactDepth[idx])) {
        if (d.qc) ++d.qc[2];
        if (d.mask) px.exactDepth[idx] = inc;
        if (d.cap) d.cap[idx] |= 4;
    }
    bool all, some;
    if (px.writer[idx] == int64_t(e.t)) {
        // The stored value was certainly written by this very triangle: GL's invariance rules
        // (same primitive, same vertex data, only the depth function or mask changed) make the
        // incoming depth equal to it, whatever its exact value.
        all = some = depthTest(d.func, px.lo[idx], px.lo[idx]);
        a = px.lo[idx], b = px.hi[idx];
    } else {
        intervalTest(d.func, a, b, px.lo[idx], px.hi[idx], all, some);
    }
    const bool surely = cov.certain && all, maybe = some;  // `possible` holds here
    if (d.qc) {
        if (surely) ++d.qc[0];
        if (maybe) ++d.qc[1];
        if (d.cap) d.cap[idx] |= uint8_t((surely ? 1 : 0) | (maybe ? 2 : 0));
    }
    if (d.mask) {
        if (surely) {
            px.lo[idx] = a, px.hi[idx] = b;
            px.writer[idx] = int64_t(e.t);
        } else if (maybe) {
            px.lo[idx] = std::min(px.lo[idx], a), px.hi[idx] = std::max(px.hi[idx], b);
            px.writer[idx] = -1;
        }
    }
}

// The triangle's fragments in rows [r0, r1] of its pixel range.
void rasterizeRows(const TriangleTest& e, const PixelRange& pr, int64_t r0, int64_t r1, const ListParams& p,
                   const DrawState& d, const PixelState& px) {
    const int64_t j0 = std::max<int64_t>(pr.j0, r0), j1 = std::min<int64_t>(pr.j1, r1);
    for (int64_t j = j0; j <= j1; ++j) {
        const int64_t py = j * p.one + p.half;
        for (int64_t i = pr.i0; i <= pr.i1; ++i) {
            const int64_t pxc = i * p.one + p.half;
            const Coverage cov = coverageAt(e, pxc, py, p.r);
            if (!cov.possible) continue;
            const size_t idx = size_t(j) * size_t(p.W) + size_t(i);
            shadeFragment(e, cov, idx, double(i) + 0.5, double(j) + 0.5, d, px, p.fmt);
        }
    }
}

// A clear of pixels [p0, p1): the exact depth, the clear's interval, no writer.
void clearPixels(double depth, size_t p0, size_t p1, const DepthFormat& fmt, const PixelState& px) {
    uint32_t a, b;
    clearInterval(depth, fmt, a, b);
    std::fill(px.exactDepth + p0, px.exactDepth + p1, enc(depth, fmt));
    std::fill(px.lo + p0, px.lo + p1, a);
    std::fill(px.hi + p0, px.hi + p1, b);
    std::fill(px.writer + p0, px.writer + p1, -1);
}

}  // namespace

void QueryIntervals::Impl::runBands(std::span<const Triangle> triangles, const ListParams& p, const PixelState& pixels,
                                    CoverageCapture* capture) {
    const size_t bands = bandStart.size() - 1;
    parallelFor(0, bands, 1, [&](const tbb::blocked_range<size_t>& rg) {
        for (size_t band = rg.begin(); band != rg.end(); ++band) runBand(band, triangles, p, pixels, capture);
    });
}

void QueryIntervals::Impl::runBand(size_t band, std::span<const Triangle> triangles, const ListParams& p,
                                   const PixelState& pixels, CoverageCapture* capture) {
    Local& l = local(p.nq, p.H);
    const int64_t r0 = bandStart[band], r1 = bandStart[band + 1] - 1;
    const size_t p0 = size_t(r0) * size_t(p.W), p1 = size_t(r1 + 1) * size_t(p.W);
    const uint32_t* it = binned.data() + bandBegin[band];
    const uint32_t* const itEnd = binned.data() + bandBegin[band + 1];
    for (const Op& op : ops) {
        if (op.clear) {
            clearPixels(op.clearDepth, p0, p1, p.fmt, pixels);
            continue;
        }
        const uint64_t stop = op.base + op.count;
        const DrawState d{op.func, op.mask, op.query >= 0 ? l.counts.data() + 3 * size_t(op.query) : nullptr,
                          capture && op.query == int64_t(capture->query) ? capture->classes.data() : nullptr};
        for (; it != itEnd && *it < stop; ++it) {
            const uint32_t t = op.first + uint32_t(*it - op.base);
            const Triangle& tri = triangles[t];
            const Vert* const vv[3] = {&vert[tri[0]], &vert[tri[1]], &vert[tri[2]]};
            rasterizeRows(setUpTest(t, clipped[t] != 0, vv, p), range[t], r0, r1, p, d, pixels);
        }
    }
}

}  // namespace cullide::raster
