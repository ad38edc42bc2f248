// Conservative rasterization with depth intervals (rules 10-13 of cullide/raster/rules.h), shared
// by the fast and the scalar reference paths. Private to raster/.
//
// References: Hasselgren, Akenine-Moller, Ohlsson, "Conservative rasterization", GPU Gems 2
// ch. 42 (overestimating coverage; depth over a partly covered pixel clamped to the primitive's
// range); the D3D12 / Vulkan overestimation rules (closed pixel squares, degenerate triangles
// still rasterized); Govindaraju, Lin, Manocha, R-CULLIDE (VRST 2004: dilate so that no overlap
// is lost); docs/paper.md#related-work (the interval sketch the reliable method follows).
//
// What is guaranteed (the error analysis is in conservative.cpp): let T be a triangle of the
// geometry and W the exact (real-number) window map of the view. For every point x of T whose
// exact window position W(x) lies within the viewport (closed), the pixel whose closed square
// contains (W(x).x, W(x).y) is covered by T, and T's interval there contains W(x).z clamped to
// [0, 1], after outward rounding to stored codes. Two triangles sharing a point therefore share a
// covered pixel where their stored intervals overlap.
#pragma once

#include "cullide/raster/rules.h"
#include "setup/triangle_setup.h"

#include <cstdint>
#include <span>

namespace cullide::raster::detail {

// Rounding-error bounds of OrthoView::toWindow for one view and geometry: |computed - exact| <=
// xy (pixels, both axes) and <= z (window depth) for every vertex.
struct WindowError {
    double xy = 0, z = 0;
};
// The bound for a view, from M = positionsMagnitude(positions), the largest sum_k |p_k| of the
// geometry's vertices (view-independent: computed once per geometry).
WindowError windowError(const OrthoView& view, double M);
double positionsMagnitude(std::span<const Vec3f> positions);

// A triangle set up for conservative rasterization.
struct ConsTri {
    enum Shape : uint8_t { Triangle, Segment, Point, Box };
    Shape shape = Triangle;
    int64_t x[3], y[3];  // snapped vertices (Triangle: counter-clockwise; Segment: x[0..1] its ends)
    int64_t dilation = 1;  // D, subpixels
    double dilationPx = 0;  // D in pixels
    int32_t x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // candidate pixels (inclusive), clipped to the viewport
    // Depth: interval at pixel (i, j) = [max(zmin, c - spread) - eps, min(zmax, c + spread) + eps]
    // with c the plane at the pixel centre (usePlane); else the depth range of the triangle clipped
    // (in double) to the dilated pixel's prism, widened by its rounding and clamped to [zmin, zmax]
    // (Box: [zmin, zmax]); then widened by zeta.
    bool usePlane = false;
    DepthPlane plane;
    double spread = 0, eps = 0, zmin = 0, zmax = 0;
    double zeta = 0;  // e_z: toWindow's depth error, added at both ends
    WinVertex v[3];  // the unsnapped vertices: without a usable plane (edge-on or nearly), the
                     // interval is the depth range of the triangle clipped to the dilated pixel
};

// Sets up one triangle. Returns false when it cannot cover any pixel (its double bounding box is
// beyond one side of the viewport, or a coordinate is not finite).
bool setupConservative(const WinVertex& v0, const WinVertex& v1, const WinVertex& v2, const SetupParams& params,
                       const WindowError& err, ConsTri& out);

// The stored codes [lo, hi] of the triangle's interval at pixel (i, j) (rule 12).
void consInterval(const ConsTri& t, int i, int j, const DepthFormat& format, uint32_t& lo, uint32_t& hi);

// The reference path's coverage test: the separating-axis test of rule 11 at pixel (i, j),
// computed from scratch from the snapped vertices (the pixel range is not consulted).
bool consCoversReference(const ConsTri& t, int i, int j, int subpixelBits);

// The fast path's form: three linear functions over pixel indices, F_k(i, j) = a[k]*i + b[k]*j +
// c[k], the pixel covered iff all three are >= 0 and (i, j) lies in [x0, x1] x [y0, y1].
struct ConsEdges {
    int64_t a[3], b[3], c[3];
};
ConsEdges consEdges(const ConsTri& t, int subpixelBits);

}  // namespace cullide::raster::detail
