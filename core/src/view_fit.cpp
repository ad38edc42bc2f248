// Fitting each reducePCS call's orthographic view to the triangles it draws: the frame looking
// along the call's direction (frameOf), the triangles' bounds in it (projectedBounds), the box
// around them (fitBox), and the viewport adaptive resolution chooses (adaptiveViewport). See
// cullide.h's conventions.
#include "cullide/cullide.h"

#include "triangle_pieces.h"
#include "view_fit.h"

#include "cullide/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace cullide {

namespace {

// fitView's view before its box: the frame looking along dir, the viewport and depth format.
OrthoView frameOf(const Vec3d& dir, int width, int height, const DepthFormat& depth) {
    OrthoView view = OrthoView::looking(dir);
    view.width = width;
    view.height = height;
    view.depth = depth;
    return view;
}

// The box of fitView around the bounds [lo, hi] in `view`'s frame, at its viewport and depth.
OrthoView fitBox(OrthoView view, Vec3d lo, Vec3d hi) {
    const int width = view.width, height = view.height;
    const DepthFormat depth = view.depth;
    if (!(lo.x() <= hi.x())) lo = hi = Vec3d::Zero();  // nothing to fit: any valid view will do

    // Square pixels: the pixel size that fits both extents; the box centred on the bounds.
    const double scale = std::max({std::abs(lo.x()), std::abs(hi.x()), std::abs(lo.y()), std::abs(hi.y()),
                                   std::abs(lo.z()), std::abs(hi.z()), 1e-30});
    const double tiny = scale * 1e-6;
    const double pixel =
        std::max({(hi.x() - lo.x()) / width, (hi.y() - lo.y()) / height, tiny / std::max(width, height)});
    const double cx = 0.5 * (lo.x() + hi.x()), cy = 0.5 * (lo.y() + hi.y());
    view.xmin = cx - 0.5 * pixel * width;
    view.xmax = cx + 0.5 * pixel * width;
    view.ymin = cy - 0.5 * pixel * height;
    view.ymax = cy + 0.5 * pixel * height;
    // Depth: the extent plus two depth units at each end (so the farthest fragment stays below
    // the cleared value 1.0 after rounding, and the nearest above 0).
    const double extent = std::max(hi.z() - lo.z(), tiny);
    const double margin = 2.0 * depth.resolution();
    const double range = extent / (1.0 - 2.0 * margin);
    view.znear = lo.z() - margin * range;
    view.zfar = view.znear + range;
    if (view.zfar < hi.z() + margin * range) view.zfar = hi.z() + margin * range;
    return view;
}

// The bounds in `view`'s frame of the points that `each(i, f)` passes to f for block i of
// `blocks`, per block in parallel; min and max are exact, so the result is the same for any split.
//
// A frame whose rows are signed world axes (the `axes` directions): a row's projection right.p is
// the coordinate times +-1 (the dot product's other terms are zeros), so the bounds are the
// points' float box, permuted and negated: the same numbers, but for the sign of a zero, which
// fitBox's arithmetic does not see. No dot products per point (a fit was 3% of a prune on one
// thread; this saved 1-2%).
template <typename Each>
std::pair<Vec3d, Vec3d> projectedBounds(const OrthoView& view, size_t blocks, const Each& each) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    int axis[3], sign[3];
    bool axisFrame = true;
    const Vec3d* rows[3] = {&view.right, &view.up, &view.dir};
    for (int r = 0; r < 3 && axisFrame; ++r) {
        int nonZero = 0;
        for (int k = 0; k < 3; ++k)
            if ((*rows[r])[k] != 0) axis[r] = k, ++nonZero;
        axisFrame = nonZero == 1 && std::abs((*rows[r])[axis[r]]) == 1.0;
        if (axisFrame) sign[r] = (*rows[r])[axis[r]] > 0 ? 1 : -1;
    }
    if (axisFrame) {
        constexpr float finf = std::numeric_limits<float>::infinity();
        std::vector<std::array<float, 6>> boxes(blocks);
        parallelFor(0, blocks, 1, [&](const auto& block) {
            for (size_t i = block.begin(); i != block.end(); ++i) {
                float lo[3] = {finf, finf, finf}, hi[3] = {-finf, -finf, -finf};
                each(i, [&](const Vec3f& point) {
                    for (int k = 0; k < 3; ++k) {
                        lo[k] = std::min(lo[k], point[k]);
                        hi[k] = std::max(hi[k], point[k]);
                    }
                });
                boxes[i] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
            }
        });
        float lo[3] = {finf, finf, finf}, hi[3] = {-finf, -finf, -finf};
        for (const auto& b : boxes)
            for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], b[k]), hi[k] = std::max(hi[k], b[k + 3]);
        Vec3d qlo, qhi;
        for (int r = 0; r < 3; ++r) {
            const double l = lo[axis[r]], h = hi[axis[r]];
            qlo[r] = sign[r] > 0 ? l : -h;
            qhi[r] = sign[r] > 0 ? h : -l;
        }
        return {qlo, qhi};
    }
    std::vector<std::pair<Vec3d, Vec3d>> bounds(blocks);
    parallelFor(0, blocks, 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i) {
            Vec3d lo(inf, inf, inf), hi(-inf, -inf, -inf);
            each(i, [&](const Vec3f& point) {
                const Vec3d p = point.cast<double>();
                const Vec3d q(view.right.dot(p), view.up.dot(p), view.dir.dot(p));
                lo = lo.cwiseMin(q);
                hi = hi.cwiseMax(q);
            });
            bounds[i] = {lo, hi};
        }
    });
    Vec3d lo(inf, inf, inf), hi(-inf, -inf, -inf);
    for (const auto& [l, h] : bounds) lo = lo.cwiseMin(l), hi = hi.cwiseMax(h);
    return {lo, hi};
}

}  // namespace

OrthoView fitView(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                  std::span<const TriangleRange> ranges, const Vec3d& dir, int width, int height,
                  const DepthFormat& depth) {
    const OrthoView view = frameOf(dir, width, height, depth);
    // Per piece in parallel (levels 0-2 fit the whole mesh: 4-6% of a prune on one thread).
    const std::vector<TriangleRange> pieces = detail::piecesOf(ranges);
    const auto [lo, hi] = projectedBounds(view, pieces.size(), [&](size_t i, auto&& f) {
        for (uint32_t t = pieces[i].first; t < pieces[i].first + pieces[i].count; ++t)
            for (uint32_t v : triangles[t]) f(positions[v]);
    });
    return fitBox(view, lo, hi);
}

namespace detail {

OrthoView fitViewToPoints(std::span<const Vec3f> positions, const Vec3d& dir, int width, int height,
                          const DepthFormat& depth) {
    const OrthoView view = frameOf(dir, width, height, depth);
    constexpr size_t kBlock = 4096;
    const auto [lo, hi] = projectedBounds(view, (positions.size() + kBlock - 1) / kBlock, [&](size_t i, auto&& f) {
        for (size_t v = i * kBlock; v < std::min(positions.size(), (i + 1) * kBlock); ++v) f(positions[v]);
    });
    return fitBox(view, lo, hi);
}

}  // namespace detail

std::pair<int, int> adaptiveViewport(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                     std::span<const TriangleRange> ranges, const Vec3d& dir, double coverage,
                                     int baseWidth, int baseHeight, int64_t budget, int maxSide) {
    const OrthoView frame = OrthoView::looking(dir);
    size_t n = 0;
    for (const TriangleRange& r : ranges) n += r.count;
    if (n == 0) return {baseWidth, baseHeight};
    // The PCS's projected area (the sum of its triangles' areas in the view plane) and bounds, per
    // piece of at most kPiece triangles and then in piece order: the pieces depend on the ranges
    // only, so the sums do not depend on the thread count.
    struct ProjectedBox {
        double area, xlo, xhi, ylo, yhi;
    };
    const std::vector<TriangleRange> pieces = detail::piecesOf(ranges);
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<ProjectedBox> perPiece(pieces.size(), ProjectedBox{0, inf, -inf, inf, -inf});
    parallelFor(0, pieces.size(), 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i) {
            ProjectedBox& b = perPiece[i];
            for (uint32_t k = 0; k < pieces[i].count; ++k) {
                const Triangle& t = triangles[pieces[i].first + k];
                double x[3], y[3];
                for (int c = 0; c < 3; ++c) {
                    const Vec3d p = positions[t[c]].cast<double>();
                    x[c] = frame.right.dot(p), y[c] = frame.up.dot(p);
                    b.xlo = std::min(b.xlo, x[c]), b.xhi = std::max(b.xhi, x[c]);
                    b.ylo = std::min(b.ylo, y[c]), b.yhi = std::max(b.yhi, y[c]);
                }
                b.area += 0.5 * std::abs((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
            }
        }
    });
    ProjectedBox all{0, inf, -inf, inf, -inf};
    for (const ProjectedBox& b : perPiece) {
        all.area += b.area;
        all.xlo = std::min(all.xlo, b.xlo), all.xhi = std::max(all.xhi, b.xhi);
        all.ylo = std::min(all.ylo, b.ylo), all.yhi = std::max(all.yhi, b.yhi);
    }
    const double ex = all.xhi - all.xlo, ey = all.yhi - all.ylo;
    // The base's pixel (fitView's at the base viewport) and the wanted one: the PCS covers
    // `coverage` base viewports' worth of pixels.
    const double basePixel = std::max(ex / baseWidth, ey / baseHeight);
    const double wanted = std::sqrt(all.area / (coverage * double(baseWidth) * double(baseHeight)));
    if (!(basePixel > 0) || !(wanted < basePixel)) return {baseWidth, baseHeight};
    // Sides covering the bounds at the wanted pixel, in double so that nothing overflows.
    double w = std::max(1.0, std::ceil(ex / wanted)), h = std::max(1.0, std::ceil(ey / wanted));
    if (w * h > double(budget)) {
        const double f = std::sqrt(double(budget) / (w * h));
        w = std::max(1.0, std::floor(w * f)), h = std::max(1.0, std::floor(h * f));
    }
    const double side = double(std::clamp(maxSide, 1, kMaxViewportSide));
    if (w > side || h > side) {
        const double f = side / std::max(w, h);
        w = std::clamp(std::floor(w * f), 1.0, side), h = std::clamp(std::floor(h * f), 1.0, side);
    }
    // Rounding down to the budget or the side limit may have made the pixel the base's or coarser:
    // then the base itself (the side limit aside, never coarser than the base).
    if (std::max(ex / w, ey / h) >= basePixel && baseWidth <= side && baseHeight <= side)
        return {baseWidth, baseHeight};
    return {int(w), int(h)};
}

}  // namespace cullide
