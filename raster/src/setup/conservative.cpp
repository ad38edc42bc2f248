// Conservative rasterization with depth intervals: rules 10-13 of cullide/raster/rules.h.
// References in conservative.h.
//
// Error analysis (u = 2^-53, the unit roundoff of double).
//   Window map. toWindow computes x = r.p (three products, two sums: error <= 3u * sum|r_k p_k|
//   plus u per operation), then (x - xmin) / (xmax - xmin) * width. The computed denominators are
//   the same for every vertex, so we take the map with those denominators as "exact" W; each
//   vertex's computed window position is then within e_xy = 8u * A pixels of W(vertex), with
//   A = (2M + |xmin| + |xmax|) / (xmax - xmin) * width (M = max_v sum_k |p_k|; likewise for y), and
//   its depth within e_z = 8u * (2M + |znear| + |zfar|) / (zfar - znear) + 8u. Any point x of T
//   has barycentrics b; the point y = sum b_k * computed(v_k) of the computed triangle is within
//   e_xy / e_z of W(x), per axis.
//   Coverage. Snapping moves each vertex by <= 1/2 subpixel per axis, so the snapped triangle
//   holds a point within 1/2 subpixel of y. If W(x) lies in pixel square Q, the snapped triangle
//   meets Q dilated by 1/2 subpixel + e_xy <= D subpixels. The separating-axis test on integers is
//   exact, so the pixel is covered.
//   Depth. y's depth lies in [zmin, zmax] (a convex combination of the computed vertex depths),
//   and equals P(y) for the exact plane P through the computed vertices (when they are not
//   collinear). P over the dilated square lies within c +- (|gx| + |gy|)(1/2 + D/2^S) of P at the
//   centre; the computed gradients are within gerr of P's, and the computed centre value within
//   16u(|z0| + |gx dx| + |gy dy|) + gerr * distance of P's (both bounded over the pixel range).
//   Widening by e_z then contains W(x).z. Clamping to [0, 1] and rounding outwards are monotonic.
#include "setup/conservative.h"

#include <algorithm>
#include <cmath>

namespace cullide::raster::detail {

namespace {

constexpr double kU = 0x1p-53;

int64_t floorDiv(int64_t a, int64_t b) {
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

}  // namespace

double positionsMagnitude(std::span<const Vec3f> positions) {
    double m = 0;
    for (const Vec3f& p : positions)
        m = std::max(m, double(std::abs(p.x())) + double(std::abs(p.y())) + double(std::abs(p.z())));
    return m;
}

WindowError windowError(const OrthoView& view, double m) {
    WindowError e;
    // A tile's window coordinates are the whole view's minus an integer (exact): the grid's error.
    const double ax = (2 * m + std::abs(view.xmin) + std::abs(view.xmax)) / (view.xmax - view.xmin) * view.fullWidth();
    const double ay = (2 * m + std::abs(view.ymin) + std::abs(view.ymax)) / (view.ymax - view.ymin) * view.fullHeight();
    e.xy = 8 * kU * std::max(ax, ay);
    e.z = 8 * kU * ((2 * m + std::abs(view.znear) + std::abs(view.zfar)) / (view.zfar - view.znear) + 1);
    return e;
}

bool setupConservative(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const SetupParams& params,
                       const WindowError& err, ConsTri& out) {
    const WinVertex* v[3] = {&v0, &v1, &v2};
    for (const WinVertex* p : v)
        if (!std::isfinite(p->x) || !std::isfinite(p->y) || !std::isfinite(p->z)) return false;
    const double W = params.width, H = params.height;
    const double minx = std::min({v0.x, v1.x, v2.x}), maxx = std::max({v0.x, v1.x, v2.x});
    const double miny = std::min({v0.y, v1.y, v2.y}), maxy = std::max({v0.y, v1.y, v2.y});
    // Rule 10: beyond one side by more than a pixel (far more than e_xy plus snapping).
    const double m = 1 + err.xy;
    if (maxx < -m || minx > W + m || maxy < -m || miny > H + m) return false;
    out.zmin = std::min({v0.z, v1.z, v2.z});
    out.zmax = std::max({v0.z, v1.z, v2.z});
    out.usePlane = false;
    out.spread = out.eps = 0;

    const int S = params.subpixelBits;
    const int64_t one = int64_t(1) << S;
    const double G = guardBandPixels(S);
    int64_t bx0, bx1, by0, by1;  // candidate pixel range before clipping
    if (std::max(std::abs(minx), std::abs(maxx)) > G || std::max(std::abs(miny), std::abs(maxy)) > G ||
        !(err.xy < 1024)) {
        // Cannot snap safely (or the window error is so large that the dilation could overflow
        // the edge functions): cover the bounding box (plus a pixel) with the vertex depth range.
        // e_xy >= 1024 px means coordinates ~2^40 times the view's extent: not a real scene.
        out.shape = ConsTri::Box;
        out.dilation = one;
        const double pad = 2 + std::ceil(std::min(err.xy, 1e6));  // a pixel, plus the window error
        bx0 = int64_t(std::floor(std::max(minx, -2.0) - pad));
        bx1 = int64_t(std::floor(std::min(maxx, W + 2) + pad));
        by0 = int64_t(std::floor(std::max(miny, -2.0) - pad));
        by1 = int64_t(std::floor(std::min(maxy, H + 2) + pad));
        for (int k = 0; k < 3; ++k) out.x[k] = out.y[k] = 0;
    } else {
        int64_t sx[3], sy[3];
        for (int k = 0; k < 3; ++k) {
            sx[k] = snapToFixed(v[k]->x, S);
            sy[k] = snapToFixed(v[k]->y, S);
        }
        out.dilation = 1 + int64_t(std::ceil(err.xy * double(one)));
        const int64_t area2 = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
        int idx[3] = {0, 1, 2};
        if (area2 != 0) {
            out.shape = ConsTri::Triangle;
            if (area2 < 0) std::swap(idx[1], idx[2]);
        } else {
            // Collinear after snapping: the farthest pair spans the third point.
            int64_t best = -1;
            for (int a = 0; a < 3; ++a) {
                const int b = (a + 1) % 3;
                const int64_t dx = sx[b] - sx[a], dy = sy[b] - sy[a];
                const int64_t d2 = dx * dx + dy * dy;
                if (d2 > best) best = d2, idx[0] = a, idx[1] = b, idx[2] = 3 - a - b;
            }
            out.shape = best == 0 ? ConsTri::Point : ConsTri::Segment;
        }
        for (int k = 0; k < 3; ++k) {
            out.x[k] = sx[idx[k]];
            out.y[k] = sy[idx[k]];
        }
        const int64_t D = out.dilation;
        const int64_t lx = std::min({sx[0], sx[1], sx[2]}), hx = std::max({sx[0], sx[1], sx[2]});
        const int64_t ly = std::min({sy[0], sy[1], sy[2]}), hy = std::max({sy[0], sy[1], sy[2]});
        // Pixel i's dilated square [i*one - D, (i+1)*one + D] meets [lx, hx].
        bx0 = -floorDiv(-(lx - D - one), one);
        bx1 = floorDiv(hx + D, one);
        by0 = -floorDiv(-(ly - D - one), one);
        by1 = floorDiv(hy + D, one);
    }
    // The pixel range clipped to the grid (the whole view), over which the depth error is
    // bounded: the same for a tile as for the whole view, so both get the same intervals.
    const int64_t gx0 = std::max<int64_t>(bx0, params.gridX0), gx1 = std::min<int64_t>(bx1, params.gridX1);
    const int64_t gy0 = std::max<int64_t>(by0, params.gridY0), gy1 = std::min<int64_t>(by1, params.gridY1);
    bx0 = std::max<int64_t>(bx0, 0);
    by0 = std::max<int64_t>(by0, 0);
    bx1 = std::min<int64_t>(bx1, params.width - 1);
    by1 = std::min<int64_t>(by1, params.height - 1);
    if (bx0 > bx1 || by0 > by1) return false;
    out.x0 = int32_t(bx0);
    out.x1 = int32_t(bx1);
    out.y0 = int32_t(by0);
    out.y1 = int32_t(by1);

    // Depth plane through the unsnapped vertices, with its error bound (see above).
    if (out.shape != ConsTri::Box) {
        const double x1 = v1.x - v0.x, y1 = v1.y - v0.y, z1 = v1.z - v0.z;
        const double x2 = v2.x - v0.x, y2 = v2.y - v0.y, z2 = v2.z - v0.z;
        const double det = x1 * y2 - x2 * y1;
        const double errDet = 6 * kU * (std::abs(x1 * y2) + std::abs(x2 * y1));
        if (std::isfinite(det) && std::abs(det) > 64 * errDet && det != 0) {
            const double numX = z1 * y2 - z2 * y1, numY = x1 * z2 - x2 * z1;
            const double gx = numX / det, gy = numY / det;
            const double errX = 6 * kU * (std::abs(z1 * y2) + std::abs(z2 * y1));
            const double errY = 6 * kU * (std::abs(x1 * z2) + std::abs(x2 * z1));
            const double denom = std::abs(det) - errDet;
            const double gerrX = (errX + std::abs(gx) * errDet) / denom * 1.01 + 2 * kU * std::abs(gx);
            const double gerrY = (errY + std::abs(gy) * errDet) / denom * 1.01 + 2 * kU * std::abs(gy);
            if (std::isfinite(gx) && std::isfinite(gy) && std::isfinite(gerrX) && std::isfinite(gerrY)) {
                out.usePlane = true;
                out.plane = DepthPlane{v0.x, v0.y, v0.z, gx, gy};
                const double dpx = 0.5 + double(out.dilation) / double(one);
                out.spread = (std::abs(gx) + std::abs(gy) + gerrX + gerrY) * dpx;
                const double mdx = std::max(std::abs(double(gx0) + 0.5 - v0.x), std::abs(double(gx1) + 0.5 - v0.x)) + 1;
                const double mdy = std::max(std::abs(double(gy0) + 0.5 - v0.y), std::abs(double(gy1) + 0.5 - v0.y)) + 1;
                out.eps = gerrX * mdx + gerrY * mdy +
                    16 * kU * (std::abs(v0.z) + std::abs(gx) * mdx + std::abs(gy) * mdy + out.spread);
            }
        }
    }
    out.zeta = err.z;
    out.dilationPx = double(out.dilation) / double(one);
    out.v[0] = v0, out.v[1] = v1, out.v[2] = v2;
    return true;
}

namespace {

// The depth range of triangle v clipped to the prism over [x0, x1] x [y0, y1] (Sutherland-Hodgman
// in double, each new point computed from the inside vertex along its edge). Every computed vertex
// is a point of the triangle up to a few units of roundoff per coordinate, and lies within
// roundoff of the square; the square is dilated by >= 1/2^S px beyond what soundness needs, far
// more than the roundoff, so the computed range, widened by its roundoff, contains the range over
// the needed square. Returns false when nothing is left (the triangle misses the square).
bool clippedDepthRange(const WinVertex* v, double x0, double x1, double y0, double y1, double& lo, double& hi) {
    WinVertex a[9], b[9];
    int n = 3;
    for (int k = 0; k < 3; ++k) a[k] = v[k];
    WinVertex* src = a;
    WinVertex* dst = b;
    for (int plane = 0; plane < 4; ++plane) {
        auto dist = [&](const WinVertex& p) {
            switch (plane) {
                case 0: return p.x - x0;
                case 1: return x1 - p.x;
                case 2: return p.y - y0;
                default: return y1 - p.y;
            }
        };
        int m = 0;
        for (int k = 0; k < n; ++k) {
            const WinVertex &p = src[k], &q = src[(k + 1) % n];
            const double dp = dist(p), dq = dist(q);
            if (dp >= 0) dst[m++] = p;
            if ((dp >= 0) != (dq >= 0)) {
                const WinVertex& in = dp >= 0 ? p : q;
                const WinVertex& outv = dp >= 0 ? q : p;
                const double di = dp >= 0 ? dp : dq, dout = dp >= 0 ? dq : dp;
                const double t = di / (di - dout);
                dst[m++] = {in.x + t * (outv.x - in.x), in.y + t * (outv.y - in.y), in.z + t * (outv.z - in.z)};
            }
        }
        n = m;
        std::swap(src, dst);
        if (n == 0) return false;
    }
    lo = hi = src[0].z;
    for (int k = 1; k < n; ++k) lo = std::min(lo, src[k].z), hi = std::max(hi, src[k].z);
    return true;
}

}  // namespace

void consInterval(const ConsTri& t, int i, int j, const DepthFormat& format, uint32_t& lo, uint32_t& hi) {
    double a = t.zmin, b = t.zmax;
    if (t.usePlane) {
        const double c = t.plane.at(t.plane.row(j), i);
        a = std::max(a, c - t.spread - t.eps);
        b = std::min(b, c + t.spread + t.eps);
        // Empty only when the triangle misses the pixel in truth (the bounds are supersets):
        // any interval is then sound; keep an ordered one.
        if (a > b) std::swap(a, b);
    } else if (t.shape != ConsTri::Box) {
        const double d = t.dilationPx;
        double clo, chi;
        if (clippedDepthRange(t.v, i - d, i + 1 + d, j - d, j + 1 + d, clo, chi)) {
            const double r = 64 * kU * (std::max(std::abs(t.zmin), std::abs(t.zmax)) + (t.zmax - t.zmin));
            a = std::max(a, clo - r);
            b = std::min(b, chi + r);
            if (a > b) std::swap(a, b);
        }
    }
    lo = encodeDepthDown(a - t.zeta, format);
    hi = encodeDepthUp(b + t.zeta, format);
}

bool consCoversReference(const ConsTri& t, int i, int j, int subpixelBits) {
    if (t.shape == ConsTri::Box) return i >= t.x0 && i <= t.x1 && j >= t.y0 && j <= t.y1;
    const int64_t one = int64_t(1) << subpixelBits, D = t.dilation;
    const int64_t X[2] = {int64_t(i) * one - D, int64_t(i + 1) * one + D};
    const int64_t Y[2] = {int64_t(j) * one - D, int64_t(j + 1) * one + D};
    const int n = t.shape == ConsTri::Triangle ? 3 : t.shape == ConsTri::Segment ? 2 : 1;
    // Axis x and y: the bounding box of the shape against the square.
    int64_t lx = t.x[0], hx = t.x[0], ly = t.y[0], hy = t.y[0];
    for (int k = 1; k < n; ++k) {
        lx = std::min(lx, t.x[k]), hx = std::max(hx, t.x[k]);
        ly = std::min(ly, t.y[k]), hy = std::max(hy, t.y[k]);
    }
    if (hx < X[0] || lx > X[1] || hy < Y[0] || ly > Y[1]) return false;
    auto corners = [&](int k, int m, int& neg, int& pos) {
        const int64_t dx = t.x[m] - t.x[k], dy = t.y[m] - t.y[k];
        neg = pos = 0;
        for (int64_t px : X)
            for (int64_t py : Y) {
                const int64_t e = dx * (py - t.y[k]) - dy * (px - t.x[k]);
                neg += e < 0;
                pos += e > 0;
            }
    };
    int neg = 0, pos = 0;
    if (t.shape == ConsTri::Segment) {
        corners(0, 1, neg, pos);
        return neg < 4 && pos < 4;  // the square is not strictly on one side of the segment's line
    }
    if (t.shape == ConsTri::Triangle)
        for (int k = 0; k < 3; ++k) {
            corners(k, (k + 1) % 3, neg, pos);
            if (neg == 4) return false;  // every corner strictly outside this edge
        }
    return true;
}

ConsEdges consEdges(const ConsTri& t, int subpixelBits) {
    ConsEdges e{};
    const int64_t one = int64_t(1) << subpixelBits, D = t.dilation;
    auto maxEdge = [&](int k, int m, int slot) {
        // max over the dilated square's corners of E(p) = dx (py - yk) - dy (px - xk).
        const int64_t dx = t.x[m] - t.x[k], dy = t.y[m] - t.y[k];
        const int64_t ox = dy < 0 ? one + D : -D, oy = dx > 0 ? one + D : -D;
        e.a[slot] = -dy * one;
        e.b[slot] = dx * one;
        e.c[slot] = dx * (oy - t.y[k]) - dy * (ox - t.x[k]);
    };
    if (t.shape == ConsTri::Triangle) {
        for (int k = 0; k < 3; ++k) maxEdge(k, (k + 1) % 3, k);
    } else if (t.shape == ConsTri::Segment) {
        maxEdge(0, 1, 0);
        // -(min over the corners of E) >= 0.
        const int64_t dx = t.x[1] - t.x[0], dy = t.y[1] - t.y[0];
        const int64_t ox = dy < 0 ? -D : one + D, oy = dx > 0 ? -D : one + D;
        e.a[1] = dy * one;
        e.b[1] = -dx * one;
        e.c[1] = -(dx * (oy - t.y[0]) - dy * (ox - t.x[0]));
    }
    return e;
}

}  // namespace cullide::raster::detail
