// ViewMode::Clustered's groups: the PCS nodes whose projected rectangles overlap, transitively
// (docs/cullide.md#views-per-cluster). See cullide.h.
#include "cullide/cullide.h"

#include "cullide/parallel.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <tuple>

namespace cullide {

std::vector<std::vector<uint32_t>> viewGroups(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                              std::span<const TriangleRange> ranges, const Vec3d& dir) {
    const OrthoView frame = OrthoView::looking(dir);
    const size_t n = ranges.size();
    // Each item's projected rectangle, closed. Two triangles that share a point p have p's exact
    // projection inside both exact rectangles; the computed ones differ from those by the dot
    // products' rounding, a few units in the last place of |p|, far below the 1e-9 * |p|_1 added
    // on every side: so touching items always overlap here. Snapping and conservative dilation
    // need nothing: the argument is about the triangles themselves, not their images.
    struct Rect {
        double xlo, xhi, ylo, yhi;
    };
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<Rect> rect(n, Rect{inf, -inf, inf, -inf});
    parallelFor(0, n, 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i) {
            Rect& r = rect[i];
            double scale = 0;
            for (uint32_t t = ranges[i].first; t < ranges[i].first + ranges[i].count; ++t)
                for (uint32_t v : triangles[t]) {
                    const Vec3d p = positions[v].cast<double>();
                    const double x = frame.right.dot(p), y = frame.up.dot(p);
                    r.xlo = std::min(r.xlo, x), r.xhi = std::max(r.xhi, x);
                    r.ylo = std::min(r.ylo, y), r.yhi = std::max(r.yhi, y);
                    scale = std::max(scale, p.cwiseAbs().sum());
                }
            const double eps = 1e-9 * scale;
            r.xlo -= eps, r.xhi += eps, r.ylo -= eps, r.yhi += eps;
        }
    });
    // Connected components of overlap: a sweep in increasing xlo (ties by index) keeps the items
    // whose x extent reaches the current one and unites those whose y extents meet it too.
    std::vector<uint32_t> order(n), parent(n);
    std::iota(order.begin(), order.end(), 0u);
    std::iota(parent.begin(), parent.end(), 0u);
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return std::tie(rect[a].xlo, a) < std::tie(rect[b].xlo, b); });
    auto find = [&](uint32_t a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    };
    std::vector<uint32_t> active;
    for (uint32_t i : order) {
        const Rect& r = rect[i];
        if (!(r.xlo <= r.xhi)) continue;  // an empty item: a group of its own
        size_t keep = 0;
        for (uint32_t a : active) {
            if (rect[a].xhi < r.xlo) continue;  // ends before every item still to come
            active[keep++] = a;
            if (rect[a].ylo <= r.yhi && r.ylo <= rect[a].yhi) {
                const uint32_t ra = find(a), ri = find(i);
                if (ra != ri) parent[std::max(ra, ri)] = std::min(ra, ri);
            }
        }
        active.resize(keep);
        active.push_back(i);
    }
    // Roots are each group's smallest index, so numbering the groups in index order numbers them
    // by their first item.
    std::vector<std::vector<uint32_t>> groups;
    std::vector<uint32_t> groupOf(n);
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t root = find(i);
        if (root == i) {
            groupOf[i] = uint32_t(groups.size());
            groups.emplace_back();
        }
        groups[groupOf[root]].push_back(i);
    }
    return groups;
}

}  // namespace cullide
