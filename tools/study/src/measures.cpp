// Measures of a PCS against the oracle's truth (see measures.h). Plain double arithmetic: these
// numbers explain false prunes, they decide nothing.
#include "cullide/study/measures.h"

#include "cullide/error.h"

#include "polygon.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace cullide::study {

using oracle::IntersectingPair;
using oracle::PairClass;
using oracle::Truth;

namespace {

// Depth of the plane through three projected points (x, y, z) at (x, y); the triangle must have
// non-zero projected area.
struct DepthPlane {
    double a = 0, b = 0, c = 0;  // z = a x + b y + c
    DepthPlane(const Vec3d p[3]) {
        const double ux = p[1].x() - p[0].x(), uy = p[1].y() - p[0].y(), uz = p[1].z() - p[0].z();
        const double vx = p[2].x() - p[0].x(), vy = p[2].y() - p[0].y(), vz = p[2].z() - p[0].z();
        const double det = ux * vy - uy * vx;
        a = (uz * vy - uy * vz) / det;
        b = (ux * vz - uz * vx) / det;
        c = p[0].z() - a * p[0].x() - b * p[0].y();
    }
    double at(const P2& q) const { return a * q.x + b * q.y + c; }
};

// Whether the closed convex polygon (window coordinates) holds a pixel centre of the viewport.
bool holdsPixelCentre(const std::vector<P2>& poly, int width, int height) {
    double ylo = std::numeric_limits<double>::infinity(), yhi = -ylo;
    for (const P2& p : poly) ylo = std::min(ylo, p.y), yhi = std::max(yhi, p.y);
    const long j0 = std::max(0L, long(std::ceil(ylo - 0.5))),
               j1 = std::min(long(height) - 1, long(std::floor(yhi - 0.5)));
    for (long j = j0; j <= j1; ++j) {
        const double yc = double(j) + 0.5;
        double xl = std::numeric_limits<double>::infinity(), xr = -xl;
        for (size_t i = 0; i < poly.size(); ++i) {
            const P2& p = poly[i];
            const P2& q = poly[(i + 1) % poly.size()];
            if ((p.y - yc) * (q.y - yc) > 0) continue;  // edge entirely above or below the row
            if (p.y == q.y) {
                xl = std::min({xl, p.x, q.x});
                xr = std::max({xr, p.x, q.x});
            } else {
                const double x = p.x + (yc - p.y) / (q.y - p.y) * (q.x - p.x);
                xl = std::min(xl, x);
                xr = std::max(xr, x);
            }
        }
        if (!(xl <= xr)) continue;
        const long i0 = std::max(0L, long(std::ceil(xl - 0.5))),
                   i1 = std::min(long(width) - 1, long(std::floor(xr - 0.5)));
        if (i0 <= i1) return true;
    }
    return false;
}

using Corners = std::array<Vec3d, 3>;

Corners corners(const FlatScene& world, const TriangleRef& t) {
    const Mesh& m = world.mesh;
    const Triangle& tri = m.triangles[world.triangle(t.object, t.triangle)];
    return {m.positions[tri[0]].cast<double>(), m.positions[tri[1]].cast<double>(), m.positions[tri[2]].cast<double>()};
}

// |n . d| for the unit normal n of the triangle and the unit direction d (0: edge-on).
double facing(const Corners& c, const Vec3d& dir) {
    const Vec3d n = (c[1] - c[0]).cross(c[2] - c[0]);
    const double len = n.norm();
    return len > 0 ? std::abs(n.dot(dir)) / (len * dir.norm()) : 0.0;
}

DirectionMeasure measure(const OrthoView& view, const Corners& a, const Corners& b) {
    DirectionMeasure m;
    m.depthUnit = (view.zfar - view.znear) * view.depth.resolution();
    m.penetration = std::numeric_limits<double>::quiet_NaN();
    Vec3d pa[3], pb[3];  // view coordinates (x, y, depth)
    for (int k = 0; k < 3; ++k) {
        pa[k] = Vec3d(view.right.dot(a[k]), view.up.dot(a[k]), view.dir.dot(a[k]));
        pb[k] = Vec3d(view.right.dot(b[k]), view.up.dot(b[k]), view.dir.dot(b[k]));
    }
    P2 ta[3], tb[3];
    for (int k = 0; k < 3; ++k) ta[k] = {pa[k].x(), pa[k].y()}, tb[k] = {pb[k].x(), pb[k].y()};
    const double areaA = cross(ta[0], ta[1], ta[2]), areaB = cross(tb[0], tb[1], tb[2]);
    if (areaA == 0 || areaB == 0) return m;  // edge-on: no depth function, no fragments
    if (areaB < 0) std::swap(tb[1], tb[2]);
    const std::vector<P2> overlap = clipToTriangle({ta[0], ta[1], ta[2]}, tb);
    if (overlap.empty()) return m;
    const DepthPlane za(pa), zb(pb);
    double ab = -std::numeric_limits<double>::infinity(), ba = ab;
    for (const P2& q : overlap) {
        const double d = za.at(q) - zb.at(q);
        ab = std::max(ab, d);
        ba = std::max(ba, -d);
    }
    m.penetration = std::min(ab, ba);
    std::vector<P2> window;
    for (const P2& q : overlap)
        window.push_back({(q.x - view.xmin) / (view.xmax - view.xmin) * view.width,
                          (q.y - view.ymin) / (view.ymax - view.ymin) * view.height});
    m.pixelCentre = holdsPixelCentre(window, view.width, view.height);
    return m;
}

}  // namespace

PcsReport measurePcs(const Scene& scene, const Truth& truth, std::span<const PcsTriangle> pcs,
                     const CullideOptions& options) {
    PcsReport r;
    const size_t objects = scene.objects.size();
    std::vector<std::vector<char>> inPcs(objects), colliding(objects), crossing(objects);
    for (size_t o = 0; o < objects; ++o) {
        const size_t n = scene.objects[o].mesh.triangleCount();
        inPcs[o].assign(n, 0);
        colliding[o].assign(n, 0);
        crossing[o].assign(n, 0);
    }
    for (const PcsTriangle& p : pcs) {
        if (p.object >= objects || p.triangle >= inPcs[p.object].size())
            throw InputError("pcs",
                             "entry (" + std::to_string(p.object) + ", " + std::to_string(p.triangle) +
                                 ") names no triangle of the scene");
        if (!inPcs[p.object][p.triangle]) ++r.pcsTriangles;
        inPcs[p.object][p.triangle] = 1;
    }
    for (const IntersectingPair& p : truth.pairs) {
        CULLIDE_CHECK(p.objectB < objects && p.triangleA < colliding[p.objectA].size() &&
                          p.triangleB < colliding[p.objectB].size(),
                      "measurePcs: the truth is not of this scene");
        colliding[p.objectA][p.triangleA] = colliding[p.objectB][p.triangleB] = 1;
        if (p.cls == PairClass::Crossing) crossing[p.objectA][p.triangleA] = crossing[p.objectB][p.triangleB] = 1;
    }
    for (size_t o = 0; o < objects; ++o)
        for (size_t t = 0; t < inPcs[o].size(); ++t) {
            if (colliding[o][t]) {
                ++r.collidingTriangles;
                if (inPcs[o][t]) ++r.collidingInPcs;
                else ++r.falsePrunes[crossing[o][t] ? size_t(PairClass::Crossing) : size_t(PairClass::Touching)];
            } else if (inPcs[o][t]) {
                ++r.falsePositives;
            }
        }
    r.efficiency = r.pcsTriangles ? double(r.collidingInPcs) / double(r.pcsTriangles) : 1.0;

    std::vector<const IntersectingPair*> missed;
    for (const IntersectingPair& p : truth.pairs)
        if (!inPcs[p.objectA][p.triangleA] || !inPcs[p.objectB][p.triangleB]) missed.push_back(&p);
    if (missed.empty()) return r;

    // The whole scene as one geometry, and one view per direction fitted to all of it.
    const FlatScene world = flatten(scene);
    const TriangleRange all{0, uint32_t(world.mesh.triangles.size())};
    std::vector<OrthoView> views;
    for (const Vec3d& d : options.directions)
        views.push_back(fitView(world.mesh.positions, world.mesh.triangles, std::span(&all, 1), d, options.width,
                                options.height, options.depth));

    for (const IntersectingPair* p : missed) {
        MissedPair mp;
        mp.pair = *p;
        mp.missingA = !inPcs[p->objectA][p->triangleA];
        mp.missingB = !inPcs[p->objectB][p->triangleB];
        const size_t c = size_t(p->cls);
        ++r.missedPairs[c];
        if (p->selfPair()) ++r.missedSelfPairs[c];
        const Corners a = corners(world, p->a()), b = corners(world, p->b());
        mp.edgeOnA = mp.edgeOnB = 1;
        for (const OrthoView& v : views) {
            mp.directions.push_back(measure(v, a, b));
            mp.edgeOnA = std::min(mp.edgeOnA, facing(a, v.dir));
            mp.edgeOnB = std::min(mp.edgeOnB, facing(b, v.dir));
        }
        r.missed.push_back(std::move(mp));
    }
    return r;
}

double sceneDiagonal(const Scene& scene) {
    Bounds box;
    for (size_t i = 0; i < scene.objects.size(); ++i) box.add(referencedBounds(scene.worldMesh(i)));
    return box.empty() ? 0.0 : box.extent().cast<double>().norm();
}

NearMeasure measureNear(const Scene& scene, const oracle::Truth& truth, double distance) {
    return {distance, oracle::countNearContacts(scene, truth, distance)};
}

}  // namespace cullide::study
