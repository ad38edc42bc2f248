// The rasterization rules of the CPU reference rasterizer, all in one place.
//
// Every constant and rounding decision that decides which fragments exist and what depth they
// store lives here, with its reason and the error bound it implies. The fast (tiled, threaded)
// path and the scalar reference path both use these functions, so they cannot disagree on a rule;
// they differ only in how they walk pixels (see cpu_backend.h).
//
// References: the OpenGL 4.6 core specification (§13.8.1 viewport, §14.6.1 polygon
// rasterization, §17.3.4 depth test, §2.3.5.2 unorm conversion); Mesa llvmpipe (lp_setup_tri.c:
// 8 subpixel bits, 64-bit edge functions, bottom-left fill rule for FBOs, float depth plane from
// the unsnapped vertices); dEQP's reference rasterizer (64-bit integer edge functions, float
// depth plane, clamp, round to n bits). docs/gl-rules.md summarizes them.
//
// Conventions (GL window coordinates, see depth_backend.h)
//   - x right, y up, origin at the bottom-left corner of the viewport; pixel (i, j) covers
//     [i, i+1) x [j, j+1) and its centre is (i + 1/2, j + 1/2) (GL §14 intro).
//   - One sample per pixel, at the centre. No MSAA, no colour.
//
// The rules, in pipeline order
//   1. Window coordinates: OrthoView::toWindow(), in double from float positions.
//   2. Clipping (GL clips; we clip, we do not clamp depth): a triangle is clipped in double
//      against the depth range 0 <= zw <= 1 (GL's near/far planes; orthographic, so clipping in
//      window space equals clipping in clip space) and against the guard band
//      |xw|, |yw| <= 2^(kGuardBandFixedBits - S). The polygon is fan-triangulated from its first
//      vertex. Intersection points are computed from the inside vertex towards the outside one,
//      so two triangles sharing an edge get bit-identical points and stay watertight. The guard
//      band only keeps integers from overflowing: it lies >= 8x the largest viewport away, so for
//      any triangle reaching it the new (snapped) vertices move the visible edge by at most a
//      subpixel (as on GPUs, whose guard bands are implementation-defined). A triangle entirely
//      beyond one side of the viewport or of the depth range is rejected (it covers no centre).
//   3. Snapping: xw, yw -> integers in units of 2^-S pixel (S = subpixel bits, default 8 like
//      llvmpipe), rounding to nearest with ties towards +infinity (floor(v*2^S + 1/2), computed
//      exactly). Ties up rather than away from zero keep snapping translation-invariant. Error
//      bound: a vertex moves by at most 2^-(S+1) px per axis, so coverage near an edge can differ
//      from the exact triangle's within 2^-(S+1)*sqrt(2) px of the edge.
//   4. Coverage: 64-bit integer edge functions E(p) = (b-a) x (p-a) of the snapped vertices,
//      evaluated at the pixel centres (exact; overflow-free, see kGuardBandFixedBits). Both
//      windings rasterize (no culling): a clockwise triangle is reoriented. A centre is covered
//      when every E > 0, or E == 0 on an edge the fill rule makes inclusive. A triangle whose
//      snapped area is zero produces nothing — the paper's edge-on blind spot — and is counted in
//      the stats, never hidden.
//   5. Fill rule (which edges own the centres exactly on them), in GL window coordinates:
//      BottomLeft (default, llvmpipe FBOs): left edges (interior to the right, i.e. x increases
//      into the triangle) and bottom edges (horizontal, interior above) are inclusive. TopLeft:
//      left and top (horizontal, interior below) edges. Either way, of two triangles sharing an
//      edge with identical snapped endpoints, exactly one owns a centre on it (GL §14.6.1).
//   6. Depth: a plane through the three *unsnapped* double window vertices of the original
//      (unclipped) triangle (as llvmpipe and dEQP: the plane from the float vertices),
//      z(x, y) = (z0 + dz/dy*(y - y0)) + dz/dx*(x - x0), evaluated in IEEE double (no FMA:
//      raster is compiled with -ffp-contract=off) at the pixel centre, with (x0, y0, z0) the
//      triangle's first vertex, exactly in this association. If the unsnapped vertices are
//      collinear (zero double determinant) while the snapped triangle is not, the plane is built
//      from the snapped x, y of the sub-triangle instead (so no NaN can arise). The result is
//      clamped to [0, 1] (NaN -> 0, -0 -> +0).
//   7. Storage: unorm n bits (8..32): k = round(z * (2^n - 1)), computed exactly (no double
//      rounding, also for n = 32), ties upwards; the only exact tie in [0,1] is z = 1/2, where up
//      and to-even agree. Error bound: |k/(2^n-1) - z| <= 1/(2*(2^n-1)). Float32: the nearest float
//      (round half to even), error <= 2^-25 relative.
//   8. Depth test and write: `incoming FUNC stored` on the stored integers (unorm k, or the
//      float's bit pattern, which orders non-negative floats like their values), the depth
//      mask gates the write. Clears store the clear depth through rule 7.
//   9. Occlusion queries count the fragments passing the depth test (SAMPLES_PASSED) or report
//      whether any did (ANY_SAMPLES_PASSED), exactly, independent of the thread count.
//
// Conservative mode (the interval buffer of depth_backend.h; raster/src/setup/conservative.h has the
// derivations). It shares rules 1 and 3 and the storage formats of rule 7, nothing else:
//  10. No clipping: a triangle is dropped only when its double bounding box lies entirely beyond
//      one side of the viewport; z outside [0, 1] is clamped in the interval (monotonic, so two
//      triangles sharing a point still share the clamped depth). A vertex beyond the guard band
//      (cannot be snapped safely) makes the triangle cover its whole bounding box.
//  11. Coverage: pixel (i, j) is covered when the snapped triangle meets the closed pixel square
//      dilated by D subpixels on every side, decided exactly in 64-bit integers by separating axes
//      (the bounding box, then the three edge normals; for a snapped segment its normal, for a
//      point nothing more). D = 1 + ceil(2^S * e_xy), e_xy a bound of toWindow's rounding error in
//      pixels for this view: snapping moves a point by <= 1/2 subpixel per axis, so any pixel the
//      exact triangle touches is covered. Zero-area and edge-on triangles are drawn as the segment
//      or point they are.
//  12. Depth interval over a covered pixel: the plane (from the unsnapped double vertices) over the
//      dilated square, widened by its own evaluation error, clamped to the triangle's vertex depth
//      range, widened by e_z (toWindow's error in depth), clamped to [0, 1]; the plane is skipped
//      (vertex range only) when its determinant is not well above its rounding error. Stored codes
//      are rounded outwards: lo = the largest code <= lo, hi = the smallest code >= hi
//      (encodeDepthDown/Up), exactly.
//  13. Test: a fragment [lo, hi] conflicts with the stored [slo, shi] unless hi < slo or lo > shi;
//      the write stores [min(lo, slo), max(hi, shi)]. Cleared: slo = 0xffffffff, shi = 0 (an empty
//      pixel conflicts only with a fragment spanning every code, never in a fitted view).
//
// Consequences for Cullide (paper Section 5): two fragments at the same centre whose computed
// depths differ by at least one stored step, 1/(2^n - 1) in window depth, i.e. a penetration of
// (far - near)/(2^n - 1) along the view, get different stored values (round(x + 1) = round(x) + 1
// and rounding is monotonic), so GREATER sees them; GEQUAL also reports equal stored values
// (contacts and sub-step penetrations). The paper's bound (far - near)/2^n is a factor
// 1 + 1/(2^n - 1) short of that: a penetration of exactly one 2^-n starting just above a
// rounding midpoint stays within one stored value (see the Figure 5(a) tests). Screen-space
// overlaps that contain no pixel centre are invisible to both queries (Figure 5(b), case A).
#pragma once

#include "cullide/depth_backend.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string_view>

namespace cullide::raster {

// Which edges own the pixel centres lying exactly on them (see rule 5).
enum class FillRule : uint8_t {
    BottomLeft,  // left + bottom edges inclusive, GL window coordinates (llvmpipe FBO convention)
    TopLeft,  // left + top edges inclusive, GL window coordinates
};

const char* toString(FillRule rule);
// The rule toString names `name` ("bottom-left", "top-left"); nullopt for any other text. The one
// parser of the name, for the trace reader and the Python module (each words its own error).
std::optional<FillRule> parseFillRule(std::string_view name);
inline constexpr const char* kFillRuleNames = "'bottom-left' or 'top-left'";

// Subpixel bits S. 8 is llvmpipe's; GL requires at least 4. At least 1 so that pixel centres
// (half-integers) are exact fixed-point numbers; at most 12 so that the guard band still covers
// 8x the largest viewport.
inline constexpr int kDefaultSubpixelBits = 8;
inline constexpr int kMinSubpixelBits = 1;
inline constexpr int kMaxSubpixelBits = 12;

// Largest viewport side: cullide::kMaxViewportSide (cullide/depth_backend.h, 2^14 pixels), which
// OrthoView::validate enforces; the ranges below rely on it.

// Snapped coordinates are kept within |v| <= 2^29 fixed-point units (the guard band). Then an
// edge's coefficients are below 2^30, a pixel centre below 2^26 (2^14 px * 2^12), and every edge
// function value below 2^61: 64-bit integers never overflow. At S = 8 the guard band is
// +-2,097,152 px, 128x the largest viewport.
inline constexpr int kGuardBandFixedBits = 29;

// Guard band half-width in pixels for S subpixel bits.
inline constexpr double guardBandPixels(int subpixelBits) {
    return double(int64_t(1) << (kGuardBandFixedBits - subpixelBits));
}

// Default tile edge of the fast path (pixels), as llvmpipe: 64x64 tiles are 16 KiB of 32-bit depth,
// small enough for L1/L2, large enough that binning stays cheap.
inline constexpr int kDefaultTileSize = 64;

// Rule 3: v * 2^S rounded to nearest, ties towards +infinity, exactly. v*2^S is exact in double;
// the truncation, the floor correction and the subtraction are exact for |v*2^S| < 2^52 (callers
// stay within the guard band).
inline int64_t snapToFixed(double v, int subpixelBits) {
    const double s = v * double(int64_t(1) << subpixelBits);
    double f = double(int64_t(s));  // truncation towards zero
    if (f > s) f -= 1.0;  // floor
    return int64_t(f) + (s - f >= 0.5 ? 1 : 0);
}

// Rule 5: whether the edge a -> b of a counter-clockwise triangle (interior on its left) is
// inclusive. (dx, dy) = b - a in fixed point. The interior normal is (-dy, dx): a left edge has
// -dy > 0; a horizontal edge (dy == 0) is a bottom edge when the interior is above (dx > 0) and a
// top edge when it is below (dx < 0).
// Written as bit operations, not branches: setup calls it per edge, and the signs are data
// (a branch on them is mispredicted about half the time).
constexpr bool isInclusiveEdge(FillRule rule, int64_t dx, int64_t dy) {
    const bool along = rule == FillRule::BottomLeft ? dx > 0 : dx < 0;  // the rule is fixed per draw
    return (dy < 0) | ((dy == 0) & along);  // a left edge, or a bottom (top) horizontal one
}

// Rule 6 (last step): clamp to [0,1]; NaN and -0 become +0.
inline double clampDepth(double z) {
    if (!(z > 0.0)) return 0.0;
    return z > 1.0 ? 1.0 : z;
}

// Rule 7, unorm: round(z * (2^n - 1)) for z in [0,1], exact for every n in 8..32.
// Derivation: z*(2^n - 1) = a - z with a = z*2^n (exact in double). Let f = floor(a) and
// r = a - f in [0,1) (both exact). Then a - z = f + (r - z) with r - z in (-1, 1), so the result
// is f - 1, f or f + 1 depending on r - z against -1/2 and +1/2. Both comparisons are exact:
// r - 1/2 is exact for r in [1/2, 1) (Sterbenz), and r + 1/2 is exact because r is a multiple of
// ulp(a) >= 2^-52 whenever a >= 1 (if a < 1 then r = a >= z, and rounding down cannot happen).
inline uint32_t encodeUnorm(double z, int bits) {
    const double a = z * double(uint64_t(1) << bits);  // exact (power of two), a in [0, 2^n]
    const double f = double(int64_t(a));  // floor, a >= 0
    const double r = a - f;  // exact
    // Branch-free (the hot loop calls this per fragment): up when r - z >= 1/2 (tie: up), down
    // when r - z < -1/2. r - 1/2 is only used (and only exact) when r >= 1/2.
    const int64_t up = int64_t((r >= 0.5) & (r - 0.5 >= z));
    const int64_t down = int64_t((r < 0.5) & (r + 0.5 < z));
    return uint32_t(int64_t(f) + up - down);
}

// Rule 7: the stored representation of a window depth (clamped first).
inline uint32_t encodeDepth(double z, const DepthFormat& format) {
    z = clampDepth(z);
    if (format.kind == DepthFormat::Kind::Float32) return std::bit_cast<uint32_t>(float(z));
    return encodeUnorm(z, format.bits);
}

// Rule 12: the largest stored code whose value is <= z, and the smallest whose value is >= z, for
// z in [0, 1] (clamped first). Unorm: z*(2^n - 1) = f + (r - z) as in encodeUnorm, with r - z in
// (-1, 1) and its sign exact (the sign of a rounded difference is the sign of the difference), so
// floor = f - [r < z] and ceil = f + [r > z]. Float: the nearest float, stepped once when it lies
// on the wrong side (the comparison in double is exact).
inline uint32_t encodeDepthDown(double z, const DepthFormat& format) {
    z = clampDepth(z);
    if (format.kind == DepthFormat::Kind::Float32) {
        float f = float(z);
        if (double(f) > z) f = std::nextafter(f, 0.0f);
        return std::bit_cast<uint32_t>(f);
    }
    if (z >= 1.0) return uint32_t((uint64_t(1) << format.bits) - 1);  // r - z = -1: outside (-1, 1)
    const double a = z * double(uint64_t(1) << format.bits);
    const double f = double(int64_t(a));
    const double r = a - f;
    return uint32_t(int64_t(f) - (r < z ? 1 : 0));
}

inline uint32_t encodeDepthUp(double z, const DepthFormat& format) {
    z = clampDepth(z);
    if (format.kind == DepthFormat::Kind::Float32) {
        float f = float(z);
        if (double(f) < z) f = std::nextafter(f, 2.0f);
        return std::bit_cast<uint32_t>(f);
    }
    if (z >= 1.0) return uint32_t((uint64_t(1) << format.bits) - 1);  // r - z = -1: outside (-1, 1)
    const double a = z * double(uint64_t(1) << format.bits);
    const double f = double(int64_t(a));
    const double r = a - f;
    return uint32_t(int64_t(f) + (r > z ? 1 : 0));
}

// Rule 13: the cleared interval, and the conflict test on stored codes.
inline constexpr uint32_t kEmptyIntervalLo = 0xffffffffu;
inline constexpr uint32_t kEmptyIntervalHi = 0;
constexpr bool intervalConflicts(uint32_t lo, uint32_t hi, uint32_t storedLo, uint32_t storedHi) {
    return hi >= storedLo && lo <= storedHi;
}

}  // namespace cullide::raster
