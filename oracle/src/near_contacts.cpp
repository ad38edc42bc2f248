// Near contacts (near_contacts.h): the oracle's broad phase on boxes grown by the distance, then
// a double-precision distance test on the candidates that the oracle did not find intersecting.
//
// References
//   - C. Ericson: Real-Time Collision Detection, 2005: ClosestPtPointTriangle (5.1.5) and
//     ClosestPtSegmentSegment (5.1.9), which triangleDistance combines as the minimum over the
//     six corner-triangle and nine edge-edge pairs (exact for triangles that do not intersect).
#include "cullide/oracle/near_contacts.h"

#include "broad_phase.h"
#include "narrow_phase.h"

#include "cullide/error.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <span>
#include <string>
#include <vector>

namespace cullide::oracle {
namespace {

using detail::Box;
using detail::Candidate;

double squaredPointTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();  // vertex region a
    const Vec3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();  // vertex region b
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).squaredNorm();  // edge ab
    const Vec3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();  // vertex region c
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).squaredNorm();  // edge ac
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).squaredNorm();  // edge bc
    const double denom = 1.0 / (va + vb + vc);  // inside the face
    return (p - (a + ab * (vb * denom) + ac * (vc * denom))).squaredNorm();
}

double squaredSegmentSegment(const Vec3d& p1, const Vec3d& q1, const Vec3d& p2, const Vec3d& q2) {
    const Vec3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
    double s = 0, t = 0;
    if (a == 0 && e == 0) return r.squaredNorm();
    if (a == 0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = d1.dot(r);
        if (e == 0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = d1.dot(d2), denom = a * e - b * b;
            s = denom != 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
            else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
        }
    }
    return ((p1 + d1 * s) - (p2 + d2 * t)).squaredNorm();
}

// Per object: world positions in double, its triangles, and which are degenerate.
struct ObjectData {
    std::vector<Vec3d> positions;
    std::vector<Triangle> triangles;
    std::vector<char> degenerate;
    std::vector<Box> boxes;  // grown by half the distance; degenerate triangles get empty boxes far away
};

// The box of triangle t, grown by `grow` on every side and rounded outward to float.
Box grownBox(const ObjectData& o, const Triangle& t, double grow) {
    Box b;
    for (int k = 0; k < 3; ++k) {
        const double lo = std::min({o.positions[t[0]][k], o.positions[t[1]][k], o.positions[t[2]][k]}) - grow;
        const double hi = std::max({o.positions[t[0]][k], o.positions[t[1]][k], o.positions[t[2]][k]}) + grow;
        b.lo[k] = detail::roundDown(float(lo));
        b.hi[k] = detail::roundUp(float(hi));
    }
    return b;
}

std::vector<ObjectData> objectData(const Scene& scene, const Truth& truth, double grow) {
    std::vector<ObjectData> objects(scene.objects.size());
    for (size_t i = 0; i < objects.size(); ++i) {
        const Mesh world = scene.worldMesh(i);
        ObjectData& o = objects[i];
        o.positions.reserve(world.positions.size());
        for (const Vec3f& p : world.positions) o.positions.push_back(p.cast<double>());
        o.triangles = world.triangles;
        o.degenerate.assign(o.triangles.size(), 0);
    }
    for (const TriangleRef& d : truth.degenerate)
        if (d.object < objects.size() && d.triangle < objects[d.object].degenerate.size())
            objects[d.object].degenerate[d.triangle] = 1;
    for (ObjectData& o : objects) {
        o.boxes.reserve(o.triangles.size());
        for (size_t t = 0; t < o.triangles.size(); ++t)
            o.boxes.push_back(o.degenerate[t] ? Box{{0, 0, 0}, {0, 0, 0}} : grownBox(o, o.triangles[t], grow));
    }
    return objects;
}

bool shareVertex(const Triangle& a, const Triangle& b) {
    for (uint32_t i : a)
        for (uint32_t j : b)
            if (i == j) return true;
    return false;
}

struct Context {
    const std::vector<ObjectData>* objects;
    const Truth* truth;
    double squaredDistance;
    std::atomic<size_t> selfPairs{0}, objectPairs{0};
};

bool intersecting(const Truth& truth, const Candidate& c) {
    IntersectingPair key{c.object0, c.prim0, c.object1, c.prim1, PairClass::Crossing};
    const auto it = std::lower_bound(truth.pairs.begin(), truth.pairs.end(), key,
                                     [](const IntersectingPair& x, const IntersectingPair& y) {
                                         return std::tie(x.objectA, x.triangleA, x.objectB, x.triangleB) <
                                                std::tie(y.objectA, y.triangleA, y.objectB, y.triangleB);
                                     });
    return it != truth.pairs.end() && it->objectA == c.object0 && it->triangleA == c.prim0 &&
           it->objectB == c.object1 && it->triangleB == c.prim1;
}

void testCandidates(void* user, const Candidate* pairs, uint32_t count) {
    Context& ctx = *static_cast<Context*>(user);
    size_t self = 0, between = 0;
    for (uint32_t k = 0; k < count; ++k) {
        const Candidate& c = pairs[k];
        if (!detail::inTestOrder(c)) continue;
        const ObjectData& oa = (*ctx.objects)[c.object0];
        const ObjectData& ob = (*ctx.objects)[c.object1];
        if (oa.degenerate[c.prim0] || ob.degenerate[c.prim1]) continue;
        const Triangle& ta = oa.triangles[c.prim0];
        const Triangle& tb = ob.triangles[c.prim1];
        const bool sameObject = c.object0 == c.object1;
        if (sameObject && shareVertex(ta, tb)) continue;
        const double d = triangleDistance(oa.positions[ta[0]], oa.positions[ta[1]], oa.positions[ta[2]],
                                          ob.positions[tb[0]], ob.positions[tb[1]], ob.positions[tb[2]]);
        if (d * d > ctx.squaredDistance || intersecting(*ctx.truth, c)) continue;
        ++(sameObject ? self : between);
    }
    ctx.selfPairs.fetch_add(self, std::memory_order_relaxed);
    ctx.objectPairs.fetch_add(between, std::memory_order_relaxed);
}

}  // namespace

double triangleDistance(const Vec3d& a0, const Vec3d& a1, const Vec3d& a2, const Vec3d& b0, const Vec3d& b1,
                        const Vec3d& b2) {
    const Vec3d a[3] = {a0, a1, a2}, b[3] = {b0, b1, b2};
    double best = std::min({squaredPointTriangle(a0, b0, b1, b2), squaredPointTriangle(a1, b0, b1, b2),
                            squaredPointTriangle(a2, b0, b1, b2), squaredPointTriangle(b0, a0, a1, a2),
                            squaredPointTriangle(b1, a0, a1, a2), squaredPointTriangle(b2, a0, a1, a2)});
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            best = std::min(best, squaredSegmentSegment(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]));
    return std::sqrt(best);
}

NearContacts countNearContacts(const Scene& scene, const Truth& truth, double distance) {
    if (!std::isfinite(distance) || distance < 0 || distance > 0x1p59)
        throw InputError("near contacts", "the distance must be from 0 to 2^59, got " + std::to_string(distance));
    const std::vector<ObjectData> objects = objectData(scene, truth, distance / 2);
    std::vector<std::span<const Box>> boxes;
    for (const ObjectData& o : objects) boxes.emplace_back(o.boxes);
    Context ctx;
    ctx.objects = &objects, ctx.truth = &truth, ctx.squaredDistance = distance * distance;
    detail::GridScratch scratch;
    detail::collideGrid(boxes, testCandidates, &ctx, scratch);
    return {ctx.selfPairs.load(), ctx.objectPairs.load()};
}

}  // namespace cullide::oracle
