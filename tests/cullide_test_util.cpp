// Scenes and runs the Cullide tests share: cullide_test_util.h.
#include "cullide_test_util.h"

#include "cullide/raster/cpu_backend.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

namespace cullide::test {

// A unit icosphere subdivided `levels` times (20 * 4^levels triangles), closed, no self-intersection.
Mesh icosphere(int levels) {
    const float t = float((1.0 + std::sqrt(5.0)) / 2.0);
    Mesh m;
    m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                   {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                   {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (auto& p : m.positions) p.normalize();
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::minmax(a, b);
            auto [it, fresh] = mid.try_emplace({key.first, key.second}, uint32_t(m.positions.size()));
            if (fresh) m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
            return it->second;
        };
        std::vector<Triangle> next;
        for (const Triangle& tri : m.triangles) {
            const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
            next.insert(next.end(), {{tri[0], a, c}, {tri[1], b, a}, {tri[2], c, b}, {a, b, c}});
        }
        m.triangles = std::move(next);
    }
    return m;
}

// A ribbon swept along a planar curve that crosses itself (x = s^2 - 1, y = s^3 - s crosses at
// s = +-1), extruded along z: the two passes through the crossing cut each other along a line.
Mesh selfCrossingRibbon(int segments) {
    Mesh m;
    for (int i = 0; i <= segments; ++i) {
        const float s = -1.5f + 3.0f * float(i) / float(segments);
        const float x = s * s - 1, y = s * s * s - s;
        m.positions.push_back(Vec3f(x, y, -0.4f));
        m.positions.push_back(Vec3f(x, y, 0.4f));
    }
    for (uint32_t i = 0; i < uint32_t(segments); ++i) {
        m.triangles.push_back({2 * i, 2 * i + 2, 2 * i + 3});
        m.triangles.push_back({2 * i, 2 * i + 3, 2 * i + 1});
    }
    return m;
}

namespace {

// Exact-enough (double, generic configurations only) test whether two triangles cross: some
// edge of one passes through the interior of the other. For the hand-built scenes here, whose
// crossings are far from degenerate; the exact oracle is the real judge.
double orient(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    return (b - a).cross(c - a).dot(d - a);
}
bool edgeCrosses(const Vec3d& p, const Vec3d& q, const std::array<Vec3d, 3>& t) {
    const double sp = orient(t[0], t[1], t[2], p), sq = orient(t[0], t[1], t[2], q);
    if (sp * sq >= 0) return false;
    const double s0 = orient(p, q, t[0], t[1]), s1 = orient(p, q, t[1], t[2]), s2 = orient(p, q, t[2], t[0]);
    return (s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0);
}
bool trianglesCross(const std::array<Vec3d, 3>& a, const std::array<Vec3d, 3>& b) {
    for (int i = 0; i < 3; ++i)
        if (edgeCrosses(a[i], a[(i + 1) % 3], b) || edgeCrosses(b[i], b[(i + 1) % 3], a)) return true;
    return false;
}

}  // namespace

// Every (object, triangle) in a crossing pair (pairs sharing a vertex within an object excluded).
std::set<PcsTriangle> crossingTriangles(const Scene& scene) {
    std::vector<Mesh> world;
    for (size_t i = 0; i < scene.objects.size(); ++i) world.push_back(scene.worldMesh(i));
    auto corners = [&](size_t o, size_t t) {
        std::array<Vec3d, 3> c;
        for (int k = 0; k < 3; ++k) c[k] = world[o].positions[world[o].triangles[t][k]].cast<double>();
        return c;
    };
    std::set<PcsTriangle> out;
    for (size_t oa = 0; oa < world.size(); ++oa)
        for (size_t ta = 0; ta < world[oa].triangles.size(); ++ta)
            for (size_t ob = oa; ob < world.size(); ++ob)
                for (size_t tb = (ob == oa ? ta + 1 : 0); tb < world[ob].triangles.size(); ++tb) {
                    if (oa == ob) {
                        bool shares = false;
                        for (uint32_t u : world[oa].triangles[ta])
                            for (uint32_t v : world[ob].triangles[tb]) shares = shares || u == v;
                        if (shares) continue;
                    }
                    if (trianglesCross(corners(oa, ta), corners(ob, tb))) {
                        out.insert({uint32_t(oa), uint32_t(ta)});
                        out.insert({uint32_t(ob), uint32_t(tb)});
                    }
                }
    return out;
}

CullideResult prune(const Scene& scene, CullMethod method, uint32_t leafSize, HierarchyKind kind, int threads,
                    int resolution, double autoCoverage) {
    raster::CpuBackendOptions bo;
    bo.threads = threads;
    auto backend = raster::makeCpuBackend(bo);
    CullideOptions o;
    o.method = method;
    o.width = o.height = resolution;
    o.autoCoverage = autoCoverage;
    o.hierarchy.kind = kind;
    o.hierarchy.leafSize = leafSize;
    o.hierarchy.branching = 2;
    return runCullide(scene, *backend, o);
}

bool contains(const CullideResult& r, const std::set<PcsTriangle>& want) {
    const std::set<PcsTriangle> have(r.pcs.begin(), r.pcs.end());
    return std::includes(have.begin(), have.end(), want.begin(), want.end());
}

}  // namespace cullide::test
