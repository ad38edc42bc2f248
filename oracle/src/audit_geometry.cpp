// The geometry behind the audit's causes (audit_geometry.h).
//
// References
//   - S. Gottschalk, M. C. Lin, D. Manocha: OBBTree, SIGGRAPH 1996 (the separating-axis theorem
//     and its candidate axes for two polytopes: face normals and cross products of edges).
//   - C. Ericson: Real-Time Collision Detection, 2005, 5.2.1 (the minimum overlap over those axes
//     as the minimum translation distance).
#include "audit_geometry.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace cullide::oracle::detail {
namespace {

struct Interval {
    double lo, hi;
};

Interval project(const TrianglePoints& t, const Vec3d& axis) {
    const double p0 = t[0].dot(axis), p1 = t[1].dot(axis), p2 = t[2].dot(axis);
    return {std::min({p0, p1, p2}), std::max({p0, p1, p2})};
}

// How far the projections of `a` and `b` on `axis` overlap, in world units (negative: a gap).
double overlapAlong(const TrianglePoints& a, const TrianglePoints& b, const Vec3d& axis) {
    const Interval pa = project(a, axis), pb = project(b, axis);
    return std::min(pa.hi - pb.lo, pb.hi - pa.lo) / axis.norm();
}

std::array<Vec3d, 3> edges(const TrianglePoints& t) {
    return {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
}

}  // namespace

int sharedIndices(const Triangle& a, const Triangle& b) {
    int n = 0;
    for (uint32_t i : a) n += i == b[0] || i == b[1] || i == b[2];
    return n;
}

bool coplanar(const TrianglePoints& a, const TrianglePoints& b) {
    for (const Vec3d& p : b)
        if (orient3d(a[0], a[1], a[2], p) != 0) return false;
    return true;
}

double penetrationDepth(const TrianglePoints& a, const TrianglePoints& b) {
    const std::array<Vec3d, 3> ea = edges(a), eb = edges(b);
    std::array<Vec3d, 11> axes;
    axes[0] = ea[0].cross(ea[1]);
    axes[1] = eb[0].cross(eb[1]);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) axes[2 + 3 * i + j] = ea[i].cross(eb[j]);
    double depth = std::numeric_limits<double>::infinity();
    for (const Vec3d& axis : axes)
        if (axis.squaredNorm() > 0) depth = std::min(depth, overlapAlong(a, b, axis));
    return std::isfinite(depth) ? std::max(depth, 0.0) : 0.0;
}

bool behindFace(const TrianglePoints& a, const TrianglePoints& b) {
    const Vec3d n = (a[1] - a[0]).cross(a[2] - a[0]);
    if (!(n.squaredNorm() > 0)) return false;
    // b as a polygon, clipped by the three half-spaces inside a's edges (Sutherland-Hodgman).
    std::vector<Vec3d> poly(b.begin(), b.end()), next;
    for (int i = 0; i < 3 && !poly.empty(); ++i) {
        const Vec3d& p0 = a[i];
        const Vec3d inward = n.cross(a[(i + 1) % 3] - p0);  // points into a, in a's plane
        next.clear();
        for (size_t k = 0; k < poly.size(); ++k) {
            const Vec3d& u = poly[k];
            const Vec3d& v = poly[(k + 1) % poly.size()];
            const double du = inward.dot(u - p0), dv = inward.dot(v - p0);
            if (du >= 0) next.push_back(u);
            if ((du < 0) != (dv < 0)) next.push_back(u + (v - u) * (du / (du - dv)));
        }
        poly.swap(next);
    }
    for (const Vec3d& p : poly)
        if (n.dot(p - a[0]) < 0) return true;
    return false;
}

}  // namespace cullide::oracle::detail
