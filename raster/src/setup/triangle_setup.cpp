// Triangle setup: clipping in double, snapping to the subpixel grid, the depth plane.
// Rules 2, 3 and 6 of cullide/raster/rules.h; the derivations are there.
//
// References: GL 4.6 §13.5 (clipping), §14.6.1 (polygon rasterization), eq. 14.10 (depth
// interpolation); Mesa llvmpipe lp_setup_tri.c (snapping, edge functions, float depth plane).
#include "setup/triangle_setup.h"

#include "setup/depth_simd.h"
#include "setup/snap_lanes.h"

#include "cullide/error.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cullide::raster::detail {

namespace {

constexpr int kMaxPolygon = 9;  // a triangle clipped by six planes has at most 3 + 6 vertices

// Signed distance to one clip plane; inside when >= 0.
struct ClipPlane {
    int axis;  // 0: x, 1: y, 2: z
    double sign;  // +1: coordinate >= bound; -1: coordinate <= bound
    double bound;
    double distance(const WinVertex& v) const {
        const double c = axis == 0 ? v.x : axis == 1 ? v.y : v.z;
        return sign > 0 ? c - bound : bound - c;
    }
};

// Point on the segment from the inside vertex `in` towards the outside vertex `out`. Always
// computed in that direction so that a shared edge gives the same point in both triangles.
WinVertex intersect(const WinVertex& in, double dIn, const WinVertex& out, double dOut) {
    const double t = dIn / (dIn - dOut);
    return {in.x + t * (out.x - in.x), in.y + t * (out.y - in.y), in.z + t * (out.z - in.z)};
}

// Sutherland-Hodgman against one plane; returns the new vertex count.
int clipPolygon(const WinVertex* src, int n, const ClipPlane& plane, WinVertex* dst) {
    int m = 0;
    for (int k = 0; k < n; ++k) {
        const WinVertex& a = src[k];
        const WinVertex& b = src[(k + 1) % n];
        const double da = plane.distance(a), db = plane.distance(b);
        const bool aIn = da >= 0, bIn = db >= 0;
        if (aIn) dst[m++] = a;
        if (aIn && !bIn) dst[m++] = intersect(a, da, b, db);
        if (!aIn && bIn) dst[m++] = intersect(b, db, a, da);
    }
    return m;
}

bool finite(const WinVertex& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// The plane through three window vertices; false when they are collinear in x, y (or the
// gradients overflow).
bool planeFrom(const WinVertex& p0, const WinVertex& p1, const WinVertex& p2, DepthPlane& plane) {
    const double x1 = p1.x - p0.x, y1 = p1.y - p0.y, z1 = p1.z - p0.z;
    const double x2 = p2.x - p0.x, y2 = p2.y - p0.y, z2 = p2.z - p0.z;
    const double det = x1 * y2 - x2 * y1;
    if (det == 0.0 || !std::isfinite(det)) return false;
    plane.x0 = p0.x;
    plane.y0 = p0.y;
    plane.z0 = p0.z;
    plane.dzdx = (z1 * y2 - z2 * y1) / det;
    plane.dzdy = (x1 * z2 - x2 * z1) / det;
    return std::isfinite(plane.dzdx) && std::isfinite(plane.dzdy);
}

}  // namespace

namespace {

// The plane of a snapped sub-triangle (x, y; depths z) whose original triangle is collinear in
// double but not after snapping. Rare: its ldexp is not paid per triangle.
DepthPlane snappedPlane(const int64_t x[3], const int64_t y[3], const std::array<double, 3>& z,
                        const SetupParams& params) {
    const double unit = std::ldexp(1.0, -params.subpixelBits);
    WinVertex s[3];
    for (int v = 0; v < 3; ++v) s[v] = {double(x[v]) * unit, double(y[v]) * unit, z[v]};
    DepthPlane plane;
    if (!planeFrom(s[0], s[1], s[2], plane)) plane = DepthPlane{s[0].x, s[0].y, s[0].z, 0.0, 0.0};
    return plane;
}

// Snapped sub-triangles of the polygon poly[0..n) (snapped coordinates sx, sy), fanned from vertex
// 0, all carrying the depth plane of the original triangle (v0, v1, v2). Returns how many of the
// fan's triangles have non-zero snapped area (before dropping empty ones).
int fanPolygon(const WinVertex* poly, int n, const int64_t* sx, const int64_t* sy, const WinVertex& v0,
               const WinVertex& v1, const WinVertex& v2, const SetupParams& params, SnappedTri* out, int& count) {
    int nonZero = 0;
    DepthPlane plane;  // of the whole (unclipped, unsnapped) triangle, computed on first use
    int havePlane = -1;
    for (int k = 1; k + 1 < n; ++k) {
        int i0 = 0, i1 = k, i2 = k + 1;
        const int64_t tx[3] = {sx[i0], sx[i1], sx[i2]}, ty[3] = {sy[i0], sy[i1], sy[i2]};
        const int64_t area2 = snappedArea2(tx, ty);
        if (area2 == 0) continue;  // zero area after snapping: no fragment (counted by the caller)
        ++nonZero;
        if (params.dropEmpty && !boxHoldsCentre(tx, ty, params)) continue;
        if (havePlane < 0) havePlane = planeFrom(v0, v1, v2, plane) ? 1 : 0;
        if (area2 < 0) std::swap(i1, i2);  // both windings rasterize
        SnappedTri& t = out[count++];
        const int idx[3] = {i0, i1, i2};
        for (int v = 0; v < 3; ++v) {
            t.x[v] = sx[idx[v]];
            t.y[v] = sy[idx[v]];
        }
        if (havePlane == 1) t.plane = plane;
        else t.plane = snappedPlane(t.x, t.y, {poly[idx[0]].z, poly[idx[1]].z, poly[idx[2]].z}, params);
    }
    return nonZero;
}

}  // namespace

bool trivialReject(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const SetupParams& params) {
    if (!finite(v0) || !finite(v1) || !finite(v2)) return true;
    // All three vertices beyond one side of the viewport or the depth range. Beyond x < 0 every
    // snapped x is <= 0, left of every centre (>= 1/2); likewise for the others.
    return (beyondSides(v0, params) & beyondSides(v1, params) & beyondSides(v2, params)) != 0 ||
        (v0.z < 0 && v1.z < 0 && v2.z < 0) || (v0.z > 1 && v1.z > 1 && v2.z > 1);
}

bool insideClipVolume(const WinVertex& v, const SetupParams& params) {
    const double G = guardBandPixels(params.subpixelBits);
    return v.z >= 0 && v.z <= 1 && v.x >= -G && v.x <= G && v.y >= -G && v.y <= G;
}

namespace {

// Smallest and largest of three, as selects: std::min of an initializer list compiled to
// compare-and-branch chains here, whose mispredictions were most of boxHoldsCentre's time
// (~13% of a prune); these give conditional moves (5-8% off a 270k prune).
inline int64_t min3(int64_t a, int64_t b, int64_t c) {
    const int64_t ab = a < b ? a : b;
    return ab < c ? ab : c;
}
inline int64_t max3(int64_t a, int64_t b, int64_t c) {
    const int64_t ab = a > b ? a : b;
    return ab > c ? ab : c;
}

inline int64_t floorShift(int64_t v, int s) {
    return v >> s;
}  // floor(v / 2^s), arithmetic shift
inline int64_t ceilShift(int64_t v, int s) {
    return -((-v) >> s);
}  // ceil(v / 2^s)

// The pixels whose centres i*2^S + half lie within the snapped triangle's bounding box, clipped to
// the viewport: [i0, i1] x [j0, j1], empty when i0 > i1 or j0 > j1. The AVX2 forms (countHints8 in
// records.cpp, setupInsideEdgeTri4) compute the same in 32-bit lanes.
struct PixelBox {
    int64_t i0, i1, j0, j1;
};
inline PixelBox pixelBox(const int64_t x[3], const int64_t y[3], const SetupParams& params) {
    const int S = params.subpixelBits;
    const int64_t half = int64_t(1) << (S - 1);
    return {std::max<int64_t>(ceilShift(min3(x[0], x[1], x[2]) - half, S), 0),
            std::min<int64_t>(floorShift(max3(x[0], x[1], x[2]) - half, S), params.width - 1),
            std::max<int64_t>(ceilShift(min3(y[0], y[1], y[2]) - half, S), 0),
            std::min<int64_t>(floorShift(max3(y[0], y[1], y[2]) - half, S), params.height - 1)};
}

}  // namespace

bool boxHoldsCentre(const int64_t sx[3], const int64_t sy[3], const SetupParams& params) {
    const PixelBox box = pixelBox(sx, sy, params);
    return box.i0 <= box.i1 && box.j0 <= box.j1;
}

uint8_t setupTriangle(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const SetupParams& params,
                      SnappedTri out[kMaxSubTriangles], int& count) {
    count = 0;
    if (trivialReject(v0, v1, v2, params)) return kRejected;
    const int S = params.subpixelBits;
    if (insideClipVolume(v0, params) && insideClipVolume(v1, params) && insideClipVolume(v2, params)) {
        const int64_t sx[3] = {snapToFixed(v0.x, S), snapToFixed(v1.x, S), snapToFixed(v2.x, S)};
        const int64_t sy[3] = {snapToFixed(v0.y, S), snapToFixed(v1.y, S), snapToFixed(v2.y, S)};
        const WinVertex poly[3] = {v0, v1, v2};
        return fanPolygon(poly, 3, sx, sy, v0, v1, v2, params, out, count) == 0 ? kZeroArea : 0;
    }

    // Clipping against the depth range and the guard band.
    const double G = guardBandPixels(S);
    WinVertex polyA[kMaxPolygon];  // not value-initialized: cheap
    WinVertex polyB[kMaxPolygon];
    polyA[0] = v0;
    polyA[1] = v1;
    polyA[2] = v2;
    WinVertex* poly = polyA;
    WinVertex* other = polyB;
    int n = 3;
    const ClipPlane planes[6] = {{2, +1, 0.0}, {2, -1, 1.0}, {0, +1, -G}, {0, -1, G}, {1, +1, -G}, {1, -1, G}};
    for (const ClipPlane& cp : planes) {
        n = clipPolygon(poly, n, cp, other);
        std::swap(poly, other);
        if (n < 3) return kClipped | kRejected;
    }
    // Snap every polygon vertex once, then fan from vertex 0.
    int64_t sx[kMaxPolygon], sy[kMaxPolygon];
    for (int k = 0; k < n; ++k) {
        sx[k] = snapToFixed(poly[k].x, S);
        sy[k] = snapToFixed(poly[k].y, S);
    }
    return kClipped | (fanPolygon(poly, n, sx, sy, v0, v1, v2, params, out, count) == 0 ? kZeroArea : 0);
}

bool makeEdgeTri(const SnappedTri& t, const SetupParams& params, EdgeTri& out) {
    const int S = params.subpixelBits;
    const int64_t half = int64_t(1) << (S - 1);
    const PixelBox box = pixelBox(t.x, t.y, params);
    if (box.i0 > box.i1 || box.j0 > box.j1) return false;
    out.x0 = uint16_t(box.i0);
    out.x1 = uint16_t(box.i1);
    out.y0 = uint16_t(box.j0);
    out.y1 = uint16_t(box.j1);
    for (int k = 0; k < 3; ++k) {
        const int n = (k + 1) % 3;
        const int64_t dx = t.x[n] - t.x[k], dy = t.y[n] - t.y[k];
        CULLIDE_CHECK(std::abs(dx) <= INT32_MAX && std::abs(dy) <= INT32_MAX, "snapped edge beyond the guard band");
        // E(p) = dx*(py - yk) - dy*(px - xk) with p = (i*2^S + half, j*2^S + half), divided by 2^S
        // (EdgeTri).
        out.a[k] = int32_t(-dy);
        out.b[k] = int32_t(dx);
        out.c[k] = floorShift(
            dx * (half - t.y[k]) - dy * (half - t.x[k]) - (isInclusiveEdge(params.fillRule, dx, dy) ? 0 : 1), S);
    }
    out.plane = t.plane;
    return true;
}

void setupInsideEdgeTri(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const int64_t sx[3],
                        const int64_t sy[3], bool clockwise, const SetupParams& params, EdgeTri& out) {
    const int S = params.subpixelBits;
    const int64_t half = int64_t(1) << (S - 1);
    // fanPolygon's one sub-triangle: vertex 0 first, the other two swapped when clockwise.
    const int64_t x[3] = {sx[0], clockwise ? sx[2] : sx[1], clockwise ? sx[1] : sx[2]};
    const int64_t y[3] = {sy[0], clockwise ? sy[2] : sy[1], clockwise ? sy[1] : sy[2]};
    // makeEdgeTri's box, known to hold a centre.
    const PixelBox box = pixelBox(x, y, params);
    out.x0 = uint16_t(box.i0);
    out.x1 = uint16_t(box.i1);
    out.y0 = uint16_t(box.j0);
    out.y1 = uint16_t(box.j1);
    // makeEdgeTri's edges. Inside the clip volume |x|, |y| <= 2^kGuardBandFixedBits = 2^29, so the
    // differences fit 32 bits without its check.
    for (int k = 0; k < 3; ++k) {
        const int n = k == 2 ? 0 : k + 1;
        const int64_t dx = x[n] - x[k], dy = y[n] - y[k];
        const int64_t exclusive = int64_t(!isInclusiveEdge(params.fillRule, dx, dy));
        out.a[k] = int32_t(-dy);
        out.b[k] = int32_t(dx);
        out.c[k] = floorShift(dx * (half - y[k]) - dy * (half - x[k]) - exclusive, S);
    }
    if (!planeFrom(v0, v1, v2, out.plane)) {
        const double z[3] = {v0.z, clockwise ? v2.z : v1.z, clockwise ? v1.z : v2.z};
        out.plane = snappedPlane(x, y, {z[0], z[1], z[2]}, params);
    }
}

void setupInsideLane(const InsideBatch& b, int l, const WinVertex* window, const SnapVertex* snapped,
                     const SetupParams& params, EdgeTri& out) {
    const uint32_t i[3] = {b.v[0][l], b.v[1][l], b.v[2][l]};
    const int64_t sx[3] = {snapped[i[0]].x, snapped[i[1]].x, snapped[i[2]].x};
    const int64_t sy[3] = {snapped[i[0]].y, snapped[i[1]].y, snapped[i[2]].y};
    setupInsideEdgeTri(window[i[0]], window[i[1]], window[i[2]], sx, sy, b.clockwise[l] != 0, params, out);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))

bool haveSetupAvx2() {
    return __builtin_cpu_supports("avx2");
}

namespace {

// floor(v / 2^s) on four int64 lanes (AVX2 has no 64-bit arithmetic shift): the logical shift,
// with the sign's s high ones put back (`rest` = 64 - s).
__attribute__((target("avx2"))) inline __m256i floorShift4(__m256i v, __m128i s, __m128i rest) {
    const __m256i negative = _mm256_cmpgt_epi64(_mm256_setzero_si256(), v);
    return _mm256_or_si256(_mm256_srl_epi64(v, s), _mm256_sll_epi64(negative, rest));
}

// The lanes small enough for a small form: a pixel box [i0, i1] x [j0, j1] of at most 2 x 2
// and a snapped extent (min to max, in fixed point with S = `s` bits) under three pixels on both
// axes, which smallForms4's 32-bit edge sums need (below).
__attribute__((target("avx2"), always_inline)) inline int smallLanes4(__m128i i0, __m128i i1, __m128i j0, __m128i j1,
                                                                      __m128i minx, __m128i maxx, __m128i miny,
                                                                      __m128i maxy, __m128i s) {
    static_assert(kMaxSubpixelBits <= 12, "smallForms4's 32-bit edge sums");
    const __m128i two = _mm_set1_epi32(2);
    const __m128i three = _mm_sll_epi32(_mm_set1_epi32(3), s);  // three pixels in fixed point
    const __m128i narrow = _mm_and_si128(_mm_cmpgt_epi32(three, _mm_sub_epi32(maxx, minx)),
                                         _mm_cmpgt_epi32(three, _mm_sub_epi32(maxy, miny)));
    const __m128i fitsBox =
        _mm_and_si128(_mm_cmpgt_epi32(two, _mm_sub_epi32(i1, i0)), _mm_cmpgt_epi32(two, _mm_sub_epi32(j1, j0)));
    return _mm_movemask_ps(_mm_castsi128_ps(_mm_and_si128(fitsBox, narrow)));
}

// The small forms (SmallFrags) of four lanes set up in registers (setupInsideEdgeTri4,
// setupSmallGroup8): per pixel of the 2 x 2 block at (i0, j0), whether the record's edge functions
// are all >= 0 there, and the depth (z0 + dzdy*((j + 0.5) - y0)) + dzdx*((i + 0.5) - x0),
// DepthPlane's operations in its order, so the same fragments and codes as the pixel loops.
// `smallLanes`: the lanes to form, small (smallLanes4) and with their plane in these registers (the
// others are set up by the scalar step). The lanes in `write` are stored to small.out[0..), in
// order (setupInsideEdgeTri4: all four, to out[l]); those not in `smallLanes` get kNotSmall.
//
// The edge tests in 32 bits, from the block's corner: the record's E(i, j) = floor(c'(i, j) / 2^S)
// is >= 0 iff c'(i, j) >= 0, where c'(i, j) = 2^S*(a*i + b*j) + c' is the snapped edge function at
// the centre of pixel (i, j) (EdgeTri). With X = x_k - 2^S*i0 and Y = y_k - 2^S*j0 (the vertex
// from the corner pixel), c'(i0 + di, j0 + dj) = dx*(half - Y) - dy*(half - X) - exclusive
// + 2^S*(dx*dj - dy*di): exact in 32 bits for a lane whose snapped extent is under three pixels on
// both axes (|dx|, |dy| < 3*2^S and |half - X|, |half - Y| < 4*2^S, S <= 12: below 2^30), which
// every small lane is required to have (a box clipped to the viewport can be small when the
// triangle is not); this replaced 64-bit products and sums for 4 pixels x 3 edges.
// The depths share their terms: a row's z0 + dzdy*(...) for both pixels of the row, a column's
// dzdx*(...) for both of the column.
__attribute__((target("avx2"), always_inline)) inline int smallForms4(
    __m128i i0, __m128i i1, __m128i j0, __m128i j1, const __m128i x[3], const __m128i y[3], const __m128i dx[3],
    const __m128i dy[3], const __m128i exclusive[3], __m128i s, __m128i half, __m256d x0, __m256d y0, __m256d z0,
    __m256d dzdx, __m256d dzdy, int smallLanes, int write, const SmallOut& small) {
    const __m128i one = _mm_set1_epi32(1);
    const __m128i w = _mm_sub_epi32(i1, i0), h = _mm_sub_epi32(j1, j0);  // >= 0: the box holds a centre
    SmallFrags* const out = small.out;
    if (smallLanes == 0) {
        for (int l = 0, c = 0; l < 4; ++l)
            if (write >> l & 1) out[c++].lanes = kNotSmall;
        return 0;
    }
    const int wide = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(w, one)));
    const int tall = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(h, one)));
    const int valid[4] = {15, wide, tall, wide & tall};  // per pixel, the lanes whose box holds it
    // Per pixel (di, dj) = (p & 1, p >> 1), the OR of the three edges' c': its sign bit is set
    // where some edge is negative. cx, cy: the corner pixel's centre in fixed point (half - X =
    // cx - x_k, half - Y = cy - y_k).
    const __m128i cx = _mm_add_epi32(_mm_sll_epi32(i0, s), half), cy = _mm_add_epi32(_mm_sll_epi32(j0, s), half);
    __m128i any[4] = {_mm_setzero_si128(), _mm_setzero_si128(), _mm_setzero_si128(), _mm_setzero_si128()};
    for (int k = 0; k < 3; ++k) {
        const __m128i hx = _mm_sub_epi32(cx, x[k]), hy = _mm_sub_epi32(cy, y[k]);
        const __m128i e0 =
            _mm_sub_epi32(_mm_sub_epi32(_mm_mullo_epi32(dx[k], hy), _mm_mullo_epi32(dy[k], hx)), exclusive[k]);
        const __m128i e1 = _mm_sub_epi32(e0, _mm_sll_epi32(dy[k], s));
        const __m128i e2 = _mm_add_epi32(e0, _mm_sll_epi32(dx[k], s));
        const __m128i e3 = _mm_sub_epi32(e2, _mm_sll_epi32(dy[k], s));
        any[0] = _mm_or_si128(any[0], e0);
        any[1] = _mm_or_si128(any[1], e1);
        any[2] = _mm_or_si128(any[2], e2);
        any[3] = _mm_or_si128(any[3], e3);
    }
    const __m256d halfd = _mm256_set1_pd(0.5);
    const __m256d col[2] = {
        _mm256_mul_pd(dzdx, _mm256_sub_pd(_mm256_add_pd(_mm256_cvtepi32_pd(i0), halfd), x0)),
        _mm256_mul_pd(dzdx, _mm256_sub_pd(_mm256_add_pd(_mm256_cvtepi32_pd(_mm_add_epi32(i0, one)), halfd), x0))};
    const __m256d row[2] = {
        _mm256_add_pd(z0, _mm256_mul_pd(dzdy, _mm256_sub_pd(_mm256_add_pd(_mm256_cvtepi32_pd(j0), halfd), y0))),
        _mm256_add_pd(
            z0,
            _mm256_mul_pd(dzdy, _mm256_sub_pd(_mm256_add_pd(_mm256_cvtepi32_pd(_mm_add_epi32(j0, one)), halfd), y0)))};
    __m128 codes[4];
    int inside[4];
    for (int p = 0; p < 4; ++p) {
        inside[p] = ~_mm_movemask_ps(_mm_castsi128_ps(any[p])) & valid[p];
        const __m256d z = _mm256_add_pd(row[p >> 1], col[p & 1]);
        codes[p] =
            _mm_castsi128_ps(small.isFloat ? clampEncode4<true>(z, small.bits) : clampEncode4<false>(z, small.bits));
    }
    _MM_TRANSPOSE4_PS(codes[0], codes[1], codes[2], codes[3]);  // now per lane: its four pixels
    // The per-pixel lane masks transposed to per-lane pixel masks: bit l of a mask spread to byte
    // l, pixel p's shifted by p; byte l then holds lane l's four pixels.
    static constexpr uint32_t kSpread[16] = {0x00000000, 0x00000001, 0x00000100, 0x00000101, 0x00010000, 0x00010001,
                                             0x00010100, 0x00010101, 0x01000000, 0x01000001, 0x01000100, 0x01000101,
                                             0x01010000, 0x01010001, 0x01010100, 0x01010101};
    const uint32_t perLane =
        kSpread[inside[0]] | kSpread[inside[1]] << 1 | kSpread[inside[2]] << 2 | kSpread[inside[3]] << 3;
    alignas(16) int32_t ci[4], cj[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(ci), i0);
    _mm_store_si128(reinterpret_cast<__m128i*>(cj), j0);
    // Every lane is stored at the next place, which advances past the lanes in `write` only: the
    // others are overwritten by the next lane or lie past the last (out[0..4) is writable).
    for (int l = 0, c = 0; l < 4; ++l) {  // a lane without a form is marked; its other fields are not read
        SmallFrags& f = out[c];
        f.pixel = uint32_t(size_t(cj[l]) * small.stride + size_t(ci[l]));
        f.lanes = smallLanes >> l & 1 ? perLane >> (8 * l) & 15 : kNotSmall;
        _mm_storeu_ps(reinterpret_cast<float*>(f.z), codes[l]);
        c += write >> l & 1;
    }
    return smallLanes;
}

// The sub-triangle of four lanes (setupInsideEdgeTri's): vertex 0, then 1 and 2 swapped in the
// clockwise lanes `cw`; each edge's differences and fill-rule offset, as makeEdgeTri.
struct Edges4 {
    __m128i x[3], y[3], dx[3], dy[3], exclusive[3];
};
__attribute__((target("avx2"), always_inline)) inline Edges4 edges4(const __m128i sx[3], const __m128i sy[3],
                                                                    __m128i cw, FillRule fillRule) {
    const __m128i zero = _mm_setzero_si128();
    Edges4 e{{sx[0], _mm_blendv_epi8(sx[1], sx[2], cw), _mm_blendv_epi8(sx[2], sx[1], cw)},
             {sy[0], _mm_blendv_epi8(sy[1], sy[2], cw), _mm_blendv_epi8(sy[2], sy[1], cw)},
             {},
             {},
             {}};
    const bool bottomLeft = fillRule == FillRule::BottomLeft;
    for (int k = 0; k < 3; ++k) {
        const int n = k == 2 ? 0 : k + 1;
        e.dx[k] = _mm_sub_epi32(e.x[n], e.x[k]);
        e.dy[k] = _mm_sub_epi32(e.y[n], e.y[k]);
        const __m128i along = bottomLeft ? _mm_cmpgt_epi32(e.dx[k], zero) : _mm_cmpgt_epi32(zero, e.dx[k]);
        const __m128i inclusive =
            _mm_or_si128(_mm_cmpgt_epi32(zero, e.dy[k]), _mm_and_si128(_mm_cmpeq_epi32(e.dy[k], zero), along));
        e.exclusive[k] = _mm_andnot_si128(inclusive, _mm_set1_epi32(1));
    }
    return e;
}

// The depth planes of four triangles, as planeFrom, in each triangle's own vertex order: lane l's
// vertex k is window[v[k][l]]. `ok`: the lanes where planeFrom succeeds.
struct Plane4 {
    __m256d x0, y0, z0, dzdx, dzdy;
    int ok;
};
__attribute__((target("avx2"), always_inline)) inline Plane4 plane4(const uint32_t v[3][4], const WinVertex* window) {
    // Each vertex's coordinates loaded into its lane (AVX2's gathers were slower: snap_lanes.h).
    __m256d wx[3], wy[3], wz[3];
    for (int k = 0; k < 3; ++k) {
        const WinVertex *w0 = &window[v[k][0]], *w1 = &window[v[k][1]], *w2 = &window[v[k][2]], *w3 = &window[v[k][3]];
        wx[k] = _mm256_setr_pd(w0->x, w1->x, w2->x, w3->x);
        wy[k] = _mm256_setr_pd(w0->y, w1->y, w2->y, w3->y);
        wz[k] = _mm256_setr_pd(w0->z, w1->z, w2->z, w3->z);
    }
    Plane4 p;
    p.x0 = wx[0];
    p.y0 = wy[0];
    p.z0 = wz[0];
    const __m256d x1 = _mm256_sub_pd(wx[1], p.x0), y1 = _mm256_sub_pd(wy[1], p.y0), z1 = _mm256_sub_pd(wz[1], p.z0);
    const __m256d x2 = _mm256_sub_pd(wx[2], p.x0), y2 = _mm256_sub_pd(wy[2], p.y0), z2 = _mm256_sub_pd(wz[2], p.z0);
    const __m256d det = _mm256_sub_pd(_mm256_mul_pd(x1, y2), _mm256_mul_pd(x2, y1));
    p.dzdx = _mm256_div_pd(_mm256_sub_pd(_mm256_mul_pd(z1, y2), _mm256_mul_pd(z2, y1)), det);
    p.dzdy = _mm256_div_pd(_mm256_sub_pd(_mm256_mul_pd(x1, z2), _mm256_mul_pd(x2, z1)), det);
    // planeFrom fails on a zero or non-finite det or gradient (|v| < inf is false for NaN too).
    const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
    const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(INT64_MAX));
    const __m256d finiteDet = _mm256_cmp_pd(_mm256_and_pd(det, absMask), inf, _CMP_LT_OQ);
    const __m256d finiteX = _mm256_cmp_pd(_mm256_and_pd(p.dzdx, absMask), inf, _CMP_LT_OQ);
    const __m256d finiteY = _mm256_cmp_pd(_mm256_and_pd(p.dzdy, absMask), inf, _CMP_LT_OQ);
    const __m256d ok = _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(det, _mm256_setzero_pd(), _CMP_NEQ_OQ), finiteDet),
                                     _mm256_and_pd(finiteX, finiteY));
    p.ok = _mm256_movemask_pd(ok);
    return p;
}

// Bit l set where lane l of the mask m is.
__attribute__((target("avx2"))) inline int laneBits8(__m256i m) {
    return _mm256_movemask_ps(_mm256_castsi256_ps(m));
}
// Lanes 4h..4h+3 of v.
__attribute__((target("avx2"))) inline __m128i lanesOf(__m256i v, int h) {
    return h == 0 ? _mm256_castsi256_si128(v) : _mm256_extracti128_si256(v, 1);
}

}  // namespace

__attribute__((target("avx2"))) void setupInsideEdgeTri4(const InsideBatch& b, const WinVertex* window,
                                                         const SnapVertex* snapped, const SetupParams& params,
                                                         EdgeTri* const out[4], const SmallOut* small) {
    const int S = params.subpixelBits;
    const __m128i s = _mm_cvtsi32_si128(S), rest = _mm_cvtsi32_si128(64 - S);
    const __m128i zero = _mm_setzero_si128(), half = _mm_set1_epi32(1 << (S - 1));
    __m128i sx[3], sy[3];
    for (int k = 0; k < 3; ++k) {
        const SnapVertex *s0 = &snapped[b.v[k][0]], *s1 = &snapped[b.v[k][1]], *s2 = &snapped[b.v[k][2]],
                         *s3 = &snapped[b.v[k][3]];
        sx[k] = _mm_setr_epi32(s0->x, s1->x, s2->x, s3->x);
        sy[k] = _mm_setr_epi32(s0->y, s1->y, s2->y, s3->y);
    }
    const Edges4 e = edges4(sx, sy, _mm_load_si128(reinterpret_cast<const __m128i*>(b.clockwise)), params.fillRule);
    const __m128i(&x)[3] = e.x, (&y)[3] = e.y;
    // The box (32 bits suffice: |coordinate| <= 2^29), as makeEdgeTri: ceilShift(m - half) is
    // -((half - m) >> S).
    const __m128i minx = _mm_min_epi32(_mm_min_epi32(x[0], x[1]), x[2]);
    const __m128i maxx = _mm_max_epi32(_mm_max_epi32(x[0], x[1]), x[2]);
    const __m128i miny = _mm_min_epi32(_mm_min_epi32(y[0], y[1]), y[2]);
    const __m128i maxy = _mm_max_epi32(_mm_max_epi32(y[0], y[1]), y[2]);
    const __m128i i0 = _mm_max_epi32(_mm_sub_epi32(zero, _mm_sra_epi32(_mm_sub_epi32(half, minx), s)), zero);
    const __m128i i1 = _mm_min_epi32(_mm_sra_epi32(_mm_sub_epi32(maxx, half), s), _mm_set1_epi32(params.width - 1));
    const __m128i j0 = _mm_max_epi32(_mm_sub_epi32(zero, _mm_sra_epi32(_mm_sub_epi32(half, miny), s)), zero);
    const __m128i j1 = _mm_min_epi32(_mm_sra_epi32(_mm_sub_epi32(maxy, half), s), _mm_set1_epi32(params.height - 1));
    const Plane4 p = plane4(b.v, window);
    // The lanes with a small form need no record (the direct path reads only the others').
    const int formed = small
        ? smallForms4(i0, i1, j0, j1, x, y, e.dx, e.dy, e.exclusive, s, half, p.x0, p.y0, p.z0, p.dzdx, p.dzdy,
                      smallLanes4(i0, i1, j0, j1, minx, maxx, miny, maxy, s) & p.ok, 15, *small)
        : 0;
    if (formed == 15) return;
    // The records of the other lanes: the box, and the edges' constants in 64 bits
    // (_mm256_mul_epi32 multiplies the low 32 bits of each lane, signed: every factor fits them).
    alignas(16) int32_t box[4][4];
    _mm_store_si128(reinterpret_cast<__m128i*>(box[0]), i0);
    _mm_store_si128(reinterpret_cast<__m128i*>(box[1]), i1);
    _mm_store_si128(reinterpret_cast<__m128i*>(box[2]), j0);
    _mm_store_si128(reinterpret_cast<__m128i*>(box[3]), j1);
    alignas(16) int32_t ea[3][4], eb[3][4];
    alignas(32) int64_t ec[3][4];
    for (int k = 0; k < 3; ++k) {
        const __m256i px =
            _mm256_mul_epi32(_mm256_cvtepi32_epi64(e.dx[k]), _mm256_cvtepi32_epi64(_mm_sub_epi32(half, y[k])));
        const __m256i qx =
            _mm256_mul_epi32(_mm256_cvtepi32_epi64(e.dy[k]), _mm256_cvtepi32_epi64(_mm_sub_epi32(half, x[k])));
        const __m256i c = _mm256_sub_epi64(_mm256_sub_epi64(px, qx), _mm256_cvtepi32_epi64(e.exclusive[k]));
        _mm_store_si128(reinterpret_cast<__m128i*>(ea[k]), _mm_sub_epi32(zero, e.dy[k]));
        _mm_store_si128(reinterpret_cast<__m128i*>(eb[k]), e.dx[k]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(ec[k]), floorShift4(c, s, rest));
    }
    alignas(32) double gx[4], gy[4];
    _mm256_store_pd(gx, p.dzdx);
    _mm256_store_pd(gy, p.dzdy);
    for (int l = 0; l < 4; ++l) {
        if (formed >> l & 1) continue;
        EdgeTri& r = *out[l];
        if (!(p.ok >> l & 1)) {
            setupInsideLane(b, l, window, snapped, params, r);
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            r.c[k] = ec[k][l];
            r.a[k] = ea[k][l];
            r.b[k] = eb[k][l];
        }
        r.x0 = uint16_t(box[0][l]);
        r.x1 = uint16_t(box[1][l]);
        r.y0 = uint16_t(box[2][l]);
        r.y1 = uint16_t(box[3][l]);
        const WinVertex& v0 = window[b.v[0][l]];
        r.plane = DepthPlane{v0.x, v0.y, v0.z, gx[l], gy[l]};
    }
}

__attribute__((target("avx2"))) bool setupSmallGroup8(const Triangle* tris, const WinVertex* window,
                                                      const SnapVertex* snapped, const SetupParams& params,
                                                      const SmallOut& small, SmallGroup& got) {
    const SnapLanes8 g = snapLanes8(tris, snapped, params);
    const int one = laneBits8(g.one);
    if (laneBits8(g.inside) != 0xFF) return false;  // clipping: the count pass and setupTriangle's
    // The others have no record; their flags as countHints gives them.
    const int rejected = laneBits8(g.rejected) & ~one;
    got.rejected = uint32_t(std::popcount(unsigned(rejected)));
    got.zeroArea = uint32_t(std::popcount(unsigned(laneBits8(g.flat) & ~one & ~rejected)));
    got.forms = 0;
    const int S = params.subpixelBits;
    const __m128i s = _mm_cvtsi32_si128(S), half = _mm_set1_epi32(1 << (S - 1));
    for (int h = 0; h < 2; ++h) {
        const int write = one >> (4 * h) & 15;
        if (write == 0) continue;
        const __m128i i0 = lanesOf(g.lox, h), i1 = lanesOf(g.hix, h), j0 = lanesOf(g.loy, h), j1 = lanesOf(g.hiy, h);
        // A larger one-record lane: the four-wide setup's record and pixel loop.
        if ((write &
             ~smallLanes4(i0, i1, j0, j1, lanesOf(g.minx, h), lanesOf(g.maxx, h), lanesOf(g.miny, h),
                          lanesOf(g.maxy, h), s)) != 0)
            return false;
        uint32_t v[3][4];
        for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 4; ++l) v[k][l] = tris[4 * h + l][k];
        const Plane4 p = plane4(v, window);
        if ((write & ~p.ok) != 0) return false;  // planeFrom's fallback: the scalar step's
        const __m128i sx[3] = {lanesOf(g.x[0], h), lanesOf(g.x[1], h), lanesOf(g.x[2], h)};
        const __m128i sy[3] = {lanesOf(g.y[0], h), lanesOf(g.y[1], h), lanesOf(g.y[2], h)};
        const Edges4 e = edges4(sx, sy, lanesOf(g.cw, h), params.fillRule);
        const SmallOut out{small.out + got.forms, small.stride, small.bits, small.isFloat};
        smallForms4(i0, i1, j0, j1, e.x, e.y, e.dx, e.dy, e.exclusive, s, half, p.x0, p.y0, p.z0, p.dzdx, p.dzdy, write,
                    write, out);
        got.forms += uint32_t(std::popcount(unsigned(write)));
    }
    return true;
}

#else

bool haveSetupAvx2() {
    return false;
}

void setupInsideEdgeTri4(const InsideBatch&, const WinVertex*, const SnapVertex*, const SetupParams&, EdgeTri* const[4],
                         const SmallOut*) {
    CULLIDE_CHECK(false, "setupInsideEdgeTri4 without AVX2");
}

bool setupSmallGroup8(const Triangle*, const WinVertex*, const SnapVertex*, const SetupParams&, const SmallOut&,
                      SmallGroup&) {
    CULLIDE_CHECK(false, "setupSmallGroup8 without AVX2");
    return false;
}

#endif

}  // namespace cullide::raster::detail
