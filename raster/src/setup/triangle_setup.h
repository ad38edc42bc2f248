// Triangle setup shared by the fast and the scalar reference paths: clipping, snapping, the depth
// plane (rules 2, 3 and 6 of cullide/raster/rules.h). Private to raster/.
#pragma once

#include "cullide/mesh.h"
#include "cullide/raster/rules.h"

#include <cstddef>
#include <cstdint>
#include <limits>

namespace cullide::raster::detail {

struct WinVertex {
    double x, y, z;  // GL window coordinates (OrthoView::toWindow)
};

// A vertex snapped once (rule 3); `inside` when it needs no clipping (then |x|, |y| <= 2^29).
// `beyond`: the sides of the viewport it lies beyond (kBeyond*), as trivialReject tests them: three
// inside vertices beyond one common side make a rejected triangle (inside vertices are finite and
// within the depth range, trivialReject's other tests).
struct SnapVertex {
    int32_t x, y;
    bool inside;
    uint8_t beyond;
};

// Rule 6: z(x, y) = (z0 + dzdy*(y - y0)) + dzdx*(x - x0) at pixel centres, in this association.
struct DepthPlane {
    double x0 = 0, y0 = 0, z0 = 0, dzdx = 0, dzdy = 0;
    double row(int j) const { return z0 + dzdy * ((double(j) + 0.5) - y0); }
    double at(double rowValue, int i) const { return rowValue + dzdx * ((double(i) + 0.5) - x0); }
};

// A snapped triangle with positive area (counter-clockwise in GL window coordinates), in fixed
// point with S subpixel bits, and the depth plane of the triangle it came from.
struct SnappedTri {
    int64_t x[3], y[3];
    DepthPlane plane;
};

enum TriFlags : uint8_t {
    kRejected = 1,  // outside the viewport or the depth range: nothing to draw
    kClipped = 2,  // needed clipping against the depth range or the guard band
    kZeroArea = 4,  // not rejected, but no sub-triangle with non-zero snapped area
};

struct SetupParams {
    int subpixelBits = kDefaultSubpixelBits;
    int width = 1, height = 1;
    // The whole grid when the view is a tile (OrthoView::tile), in the tile's pixels: columns
    // [gridX0, gridX1] and rows [gridY0, gridY1]. Conservative setup bounds its depth error over
    // the triangle's pixels clipped to the grid, not to the tile, so that a tile's intervals are
    // those of the whole view. The defaults (no grid) bound it over the unclipped range: sound.
    int gridX0 = std::numeric_limits<int>::min(), gridY0 = std::numeric_limits<int>::min();
    int gridX1 = std::numeric_limits<int>::max(), gridY1 = std::numeric_limits<int>::max();
    FillRule fillRule = FillRule::BottomLeft;
    // Drop sub-triangles whose bounding box holds no pixel centre of the viewport (they cannot
    // produce a fragment). The fast path sets it; the scalar reference path does not, so that it
    // stays free of bounding-box logic. Flags are the same either way.
    bool dropEmpty = false;
};

// A clipped triangle fans into at most 3 + 6 - 2 sub-triangles (six clip planes).
inline constexpr int kMaxSubTriangles = 7;

// Sets up one triangle: writes its snapped sub-triangles to out[0..count) and returns TriFlags.
// Non-finite window coordinates count as rejected.
uint8_t setupTriangle(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const SetupParams& params,
                      SnappedTri out[kMaxSubTriangles], int& count);

// The tests setupTriangle makes first, for a caller that snaps each vertex once (the fast path):
// setupTriangle(v) == kRejected if trivialReject(v); when every vertex is insideClipVolume, no
// clipping happens and the one sub-triangle is the snapped triangle itself, dropped when its
// snappedArea2 is zero or its box holds no centre (boxHoldsCentre).
bool trivialReject(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const SetupParams& params);
// The sides of the viewport a vertex lies beyond (kBeyond*): trivialReject rejects three vertices
// beyond one common side.
enum : uint8_t { kBeyondLeft = 1, kBeyondRight = 2, kBeyondBottom = 4, kBeyondTop = 8 };
inline uint8_t beyondSides(const WinVertex& v, const SetupParams& params) {
    return uint8_t((v.x < 0 ? kBeyondLeft : 0) | (v.x > double(params.width) ? kBeyondRight : 0) |
                   (v.y < 0 ? kBeyondBottom : 0) | (v.y > double(params.height) ? kBeyondTop : 0));
}
bool insideClipVolume(const WinVertex& v, const SetupParams& params);
// Twice the signed area of the snapped triangle (positive counter-clockwise), and whether its
// bounding box holds a pixel centre of the viewport: the tests by which setup drops a
// sub-triangle. Snapped coordinates inside the guard band are below 2^30, so the products fit.
inline int64_t snappedArea2(const int64_t sx[3], const int64_t sy[3]) {
    return (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
}
bool boxHoldsCentre(const int64_t sx[3], const int64_t sy[3], const SetupParams& params);

// The fast path's form of a snapped triangle: edge functions over pixel indices,
// E_k(i, j) = a[k]*i + b[k]*j + c[k], with the fill rule folded into c so that the centre of
// pixel (i, j) is covered iff all three are >= 0; and the inclusive pixel bounding box clipped to
// the viewport. The snapped edge function at a centre is 2^S*(a*i + b*j) + c' with c' the
// constant part; since a*i + b*j is an integer, 2^S*(a*i + b*j) + c' >= 0 iff
// a*i + b*j + floor(c' / 2^S) >= 0, so c holds floor(c' / 2^S) and a, b the bare coordinate
// differences, which fit 32 bits inside the guard band (|x|, |y| <= 2^kGuardBandFixedBits). 96
// bytes: records are most of the backend's memory (one per triangle drawn).
struct EdgeTri {
    int64_t c[3];
    int32_t a[3], b[3];
    uint16_t x0, y0, x1, y1;  // viewports are at most 16384 pixels wide
    DepthPlane plane;
};
static_assert(sizeof(EdgeTri) == 96);

// Returns false (and leaves `out` unspecified) when the bounding box holds no pixel centre of the
// viewport.
bool makeEdgeTri(const SnappedTri& t, const SetupParams& params, EdgeTri& out);

// setupTriangle and makeEdgeTri of its one sub-triangle, fused, for the fast path's common case: a
// triangle whose vertices are all insideClipVolume, whose snappedArea2 is non-zero, and whose box
// holds a pixel centre (boxHoldsCentre).
// The same record, bit for bit, without the sub-triangle in between.
void setupInsideEdgeTri(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const int64_t sx[3],
                        const int64_t sy[3], bool clockwise, const SetupParams& params, EdgeTri& out);

// Up to four such triangles side by side, for setupInsideEdgeTri4: lane l is the triangle whose
// vertex k is window[v[k][l]] (snapped[v[k][l]] snapped) of the arrays the batch is set up from.
struct InsideBatch {
    uint32_t v[3][4];  // vertex indices
    alignas(16) int32_t clockwise[4];  // -1 when clockwise, else 0
};

// setupInsideEdgeTri of lane l of `batch`.
void setupInsideLane(const InsideBatch& batch, int l, const WinVertex* window, const SnapVertex* snapped,
                     const SetupParams& params, EdgeTri& out);

// Whether this CPU runs the AVX2 setup (setupInsideEdgeTri4, and the count pass's eight-wide
// form in records.cpp).
bool haveSetupAvx2();

// The direct path's (direct_path.h) form of a record whose pixel box is at most 2 x 2: its
// fragments and their incoming depth codes, computed for a block of records before any of them is
// tested, so that the arithmetic of many records overlaps and only the tests and writes stay in
// order. Lane l is pixel (x0 + (l & 1), y0 + (l >> 1)); the same fragments and codes as the pixel
// loops give the record (tile_kernels.h).
struct SmallFrags {
    uint32_t pixel;  // depth-buffer index of (x0, y0)
    uint32_t lanes;  // bit l: lane l is a fragment; kNotSmall: a larger record, for the pixel loop
    uint32_t z[4];  // incoming depth codes
};
inline constexpr uint32_t kNotSmall = 16;

// Where setupInsideEdgeTri4 also writes its records' small forms: out[0..4), for a depth buffer
// `stride` pixels wide in the format (isFloat, bits).
struct SmallOut {
    SmallFrags* out;
    size_t stride;
    int bits;
    bool isFloat;
};

// setupInsideEdgeTri on the four triangles of `batch` at once with AVX2 (haveSetupAvx2()), their
// vertices read from `window` and `snapped`: the same integer and double operations in the same
// order (no FMA), so the same four records bit for bit. A lane whose depth plane needs
// planeFrom's fallback is set up by the scalar step. With `small`, the records' small forms from
// the lanes instead, where they have one (the record is then not written); a lane set up by the
// scalar step, or with a larger box, gets kNotSmall and its record.
void setupInsideEdgeTri4(const InsideBatch& batch, const WinVertex* window, const SnapVertex* snapped,
                         const SetupParams& params, EdgeTri* const out[4], const SmallOut* small = nullptr);

// What setupSmallGroup8 found in its eight triangles: the forms it wrote, and the triangles
// without a record that setupTriangle flags rejected or zero-area.
struct SmallGroup {
    uint32_t forms, rejected, zeroArea;
};

// The count and the four-wide setup fused for the direct path's common case, eight triangles
// tris[0..8) at once with AVX2 (haveSetupAvx2()): when none needs clipping and each is either a
// one-record triangle whose record would get a small form (setupInsideEdgeTri4 with `small`, its
// plane from its vertices) or a triangle without a record (countHints's verdicts), writes the
// small forms of the one-record triangles in triangle order to small.out[0..forms) and returns
// true. Otherwise returns false, `got` unspecified; small.out[0..8) may have been written either
// way.
bool setupSmallGroup8(const Triangle* tris, const WinVertex* window, const SnapVertex* snapped,
                      const SetupParams& params, const SmallOut& small, SmallGroup& got);

}  // namespace cullide::raster::detail
