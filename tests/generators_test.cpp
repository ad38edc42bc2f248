// Generators: subdivision, decimation, resampling and the paper's scenes (deformed bunny, two
// cows, cylinders, twist). The intersection properties are checked with a small double-precision
// triangle-triangle test below (test-only: it is a good-enough check, not the exact oracle).
#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <vector>

using namespace cullide;

namespace {

// ---- A brute-force-with-grid triangle-triangle intersection counter (test-only) ----------
// Double precision; a pair intersects when an edge of one properly crosses the other's interior
// (the non-coplanar case of Moller's test). Coplanar or touching pairs and pairs sharing a vertex
// index are not counted.
struct Intersections {
    std::vector<std::pair<uint32_t, uint32_t>> pairs;  // i < j, sorted
    Bounds box;  // of the triangles in `pairs`
};

Vec3d dvec(const Vec3f& p) {
    return {double(p.x()), double(p.y()), double(p.z())};
}

// Does segment pq cross the interior of triangle abc, by more than `tol` (a length) on every
// side? Touching and coplanar contacts do not count: with float inputs they are rounding noise
// (a subdivision midpoint is off its edge by up to half an ulp), and a real crossing of two
// surfaces always has some pair that crosses properly.
bool segmentCrossesTriangle(const Vec3d& p, const Vec3d& q, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                            double tol) {
    const Vec3d n = (b - a).cross(c - a);
    const double len = n.norm();
    if (len == 0) return false;  // degenerate triangle
    const Vec3d un = n / len;
    const double dp = un.dot(p - a), dq = un.dot(q - a);
    if (!((dp > tol && dq < -tol) || (dp < -tol && dq > tol))) return false;
    const Vec3d x = p + (q - p) * (dp / (dp - dq));
    const Vec3d* v[3] = {&a, &b, &c};
    for (int e = 0; e < 3; ++e) {
        const Vec3d& s = *v[e];
        const Vec3d& t = *v[(e + 1) % 3];
        const Vec3d edge = t - s;
        const double el = edge.norm();
        if (el == 0) return false;
        // Distance of x from the edge's line, positive inside the triangle.
        if (un.dot(edge.cross(x - s)) / el <= tol) return false;
    }
    return true;
}

bool trianglesIntersect(const std::array<Vec3d, 3>& t, const std::array<Vec3d, 3>& u) {
    Vec3d lo = t[0], hi = t[0];
    for (const auto* tri : {&t, &u})
        for (const auto& p : *tri) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    const double tol = 1e-6 * (hi - lo).norm();
    for (int e = 0; e < 3; ++e) {
        if (segmentCrossesTriangle(t[e], t[(e + 1) % 3], u[0], u[1], u[2], tol)) return true;
        if (segmentCrossesTriangle(u[e], u[(e + 1) % 3], t[0], t[1], t[2], tol)) return true;
    }
    return false;
}

Intersections findSelfIntersections(const Mesh& m) {
    const size_t n = m.triangles.size();
    std::vector<std::array<Vec3d, 3>> tri(n);
    std::vector<Vec3d> lo(n), hi(n);
    Vec3d glo = Vec3d::Constant(1e300), ghi = Vec3d::Constant(-1e300);
    double meanSize = 0;
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) tri[i][k] = dvec(m.positions[m.triangles[i][k]]);
        lo[i] = tri[i][0].cwiseMin(tri[i][1]).cwiseMin(tri[i][2]);
        hi[i] = tri[i][0].cwiseMax(tri[i][1]).cwiseMax(tri[i][2]);
        glo = glo.cwiseMin(lo[i]);
        ghi = ghi.cwiseMax(hi[i]);
        meanSize += (hi[i] - lo[i]).maxCoeff();
    }
    meanSize /= double(n);
    const double cell = std::max({2.0 * meanSize, (ghi - glo).maxCoeff() / 512.0, 1e-12});
    auto cellOf = [&](const Vec3d& p) {
        return Eigen::Array<int64_t, 3, 1>(int64_t((p.x() - glo.x()) / cell), int64_t((p.y() - glo.y()) / cell),
                                           int64_t((p.z() - glo.z()) / cell));
    };
    auto key = [](const Eigen::Array<int64_t, 3, 1>& c) { return (c.x() << 42) | (c.y() << 21) | c.z(); };
    std::vector<std::pair<int64_t, uint32_t>> entries;
    for (size_t i = 0; i < n; ++i) {
        const auto a = cellOf(lo[i]), b = cellOf(hi[i]);
        for (int64_t x = a.x(); x <= b.x(); ++x)
            for (int64_t y = a.y(); y <= b.y(); ++y)
                for (int64_t z = a.z(); z <= b.z(); ++z) entries.emplace_back(key({x, y, z}), uint32_t(i));
    }
    std::sort(entries.begin(), entries.end());
    Intersections out;
    for (size_t s = 0; s < entries.size();) {
        size_t e = s;
        while (e < entries.size() && entries[e].first == entries[s].first) ++e;
        for (size_t i = s; i < e; ++i)
            for (size_t j = i + 1; j < e; ++j) {
                const uint32_t a = entries[i].second, b = entries[j].second;
                if ((lo[a].array() > hi[b].array()).any() || (lo[b].array() > hi[a].array()).any()) continue;
                // Test each pair once: in the cell holding the low corner of the boxes' overlap.
                if (key(cellOf(lo[a].cwiseMax(lo[b]))) != entries[s].first) continue;
                const auto& ta = m.triangles[a];
                const auto& tb = m.triangles[b];
                bool shared = false;
                for (uint32_t va : ta)
                    for (uint32_t vb : tb) shared = shared || va == vb;
                if (shared || !trianglesIntersect(tri[a], tri[b])) continue;
                out.pairs.emplace_back(std::min(a, b), std::max(a, b));
            }
        s = e;
    }
    std::sort(out.pairs.begin(), out.pairs.end());
    for (const auto& [a, b] : out.pairs)
        for (uint32_t t : {a, b})
            for (uint32_t v : m.triangles[t]) out.box.add(m.positions[v]);
    return out;
}

// All objects of a scene as one mesh (indices offset, so objects share no vertex index);
// owner[t] is the object of triangle t.
Mesh mergeWorld(const Scene& s, std::vector<uint32_t>* owner) {
    FlatScene flat = flatten(s);
    for (uint32_t i = 0; owner && i < s.objects.size(); ++i)
        owner->insert(owner->end(), flat.firstTriangle[i + 1] - flat.firstTriangle[i], i);
    return std::move(flat.mesh);
}

const Mesh& bunny() {
    static const Mesh m = loadMesh(CULLIDE_DATA_DIR "/meshes/bunny.off");
    return m;
}
const Mesh& cow() {
    static const Mesh m = loadMesh(CULLIDE_DATA_DIR "/meshes/cow.off");
    return m;
}

// A request for `triangles` triangles in `frames` frames.
SceneRequest request(size_t triangles, size_t frames) {
    SceneRequest q;
    q.triangles = triangles;
    q.frames = frames;
    return q;
}

// `a` has `frames` frames, each fitting its base scene (fatal otherwise: callers index frames).
void assertValid(const Animation& a, size_t frames, const char* name) {
    ASSERT_EQ(a.frameCount(), frames) << name;
    EXPECT_NO_THROW(validateAnimation(a, name));
}

double diagonal(const Bounds& b) {
    return double(b.extent().norm());
}

size_t off(size_t a, size_t b) {
    return a > b ? a - b : b - a;
}

// Bit patterns, so that -0 != +0 and NaN == NaN: "same bytes", not "same values".
std::vector<uint32_t> bits(const Mesh& m) {
    std::vector<uint32_t> out;
    for (const Vec3f& p : m.positions)
        for (int k = 0; k < 3; ++k) out.push_back(std::bit_cast<uint32_t>(p[k]));
    for (const Triangle& t : m.triangles) out.insert(out.end(), t.begin(), t.end());
    return out;
}
std::vector<uint32_t> bits(const Animation& a) {
    std::vector<uint32_t> out;
    for (size_t f = 0; f < a.frameCount(); ++f) {
        const Scene s = a.sceneAt(f);
        for (const Object& o : s.objects) {
            const auto b = bits(o.mesh);
            out.insert(out.end(), b.begin(), b.end());
            for (int k = 0; k < 16; ++k) out.push_back(std::bit_cast<uint32_t>(o.transform.matrix().data()[k]));
        }
    }
    return out;
}

Mesh tetrahedron() {
    Mesh m;
    m.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, 0, 1)};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
    return m;
}

// Every undirected edge used by exactly two triangles, in opposite directions (closed, oriented).
bool closedAndOriented(const Mesh& m) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (const Triangle& t : m.triangles)
        for (int e = 0; e < 3; ++e) ++directed[{t[e], t[(e + 1) % 3]}];
    for (const auto& [edge, n] : directed) {
        if (n != 1) return false;
        auto it = directed.find({edge.second, edge.first});
        if (it == directed.end() || it->second != 1) return false;
    }
    return true;
}

}  // namespace

// ---- subdivide ------------------------------------------------------------------------------

// Trap: midpoints made per triangle instead of per edge would double the vertices and crack
// the surface open; a closed mesh must stay closed and consistently oriented, twice over.
TEST(GeneratorsSubdivide, ClosedMeshStaysClosedWithSharedMidpoints) {
    const Mesh t0 = tetrahedron();
    const Mesh t1 = subdivide(t0);
    EXPECT_EQ(t1.triangleCount(), 16u);
    EXPECT_EQ(t1.vertexCount(), 4u + 6u);  // V + E
    EXPECT_TRUE(closedAndOriented(t1));
    const Mesh t2 = subdivide(t1);
    EXPECT_EQ(t2.triangleCount(), 64u);
    EXPECT_EQ(t2.vertexCount(), 10u + 24u);
    EXPECT_TRUE(closedAndOriented(t2));
}

// Trap: face order is part of the mesh contract; triangle i's children must be 4i..4i+3 (corner
// at t[0], t[1], t[2], then the centre), whatever order is convenient for the edge table.
TEST(GeneratorsSubdivide, TriangleIBecomesFourIToFourIPlusThree) {
    const Mesh m = tetrahedron();
    const Mesh s = subdivide(m);
    for (size_t i = 0; i < m.triangleCount(); ++i) {
        const Triangle& t = m.triangles[i];
        EXPECT_EQ(s.triangles[4 * i + 0][0], t[0]);
        EXPECT_EQ(s.triangles[4 * i + 1][1], t[1]);
        EXPECT_EQ(s.triangles[4 * i + 2][2], t[2]);
        for (uint32_t v : s.triangles[4 * i + 3]) EXPECT_GE(v, m.vertexCount()) << "centre child uses midpoints only";
        // The children cover exactly the parent's corners and its three edge midpoints.
        std::set<uint32_t> used;
        for (int c = 0; c < 4; ++c) used.insert(s.triangles[4 * i + c].begin(), s.triangles[4 * i + c].end());
        EXPECT_EQ(used.size(), 6u);
    }
}

// Trap: numbering must not depend on hashing or on which triangle saw an edge in which
// direction: originals first, then midpoints in order of first creation; a shared midpoint is
// bit-identical from both sides.
TEST(GeneratorsSubdivide, DeterministicVertexNumbering) {
    Mesh quad;
    quad.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(1, 1, 0), Vec3f(0, 1, 0.5f)};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    const Mesh s = subdivide(quad);
    ASSERT_EQ(s.vertexCount(), 9u);
    for (size_t i = 0; i < 4; ++i) EXPECT_EQ(s.positions[i], quad.positions[i]);
    EXPECT_EQ(s.positions[4], Vec3f(0.5f, 0, 0));  // 0-1
    EXPECT_EQ(s.positions[5], Vec3f(1, 0.5f, 0));  // 1-2
    EXPECT_EQ(s.positions[6], Vec3f(0.5f, 0.5f, 0));  // 2-0, reused by triangle 1 as 0-2
    EXPECT_EQ(s.positions[7], Vec3f(0.5f, 1, 0.25f));  // 2-3
    EXPECT_EQ(s.positions[8], Vec3f(0, 0.5f, 0.25f));  // 3-0
    EXPECT_EQ(s.triangles[4], (Triangle{0, 6, 8}));
    EXPECT_EQ(s.triangles[7], (Triangle{6, 7, 8}));
}

// ---- decimate -------------------------------------------------------------------------------

// Trap: meshoptimizer's target is an index count and it may stop short; the result must land
// near the target, never above the input, with no unreferenced vertices left behind.
TEST(GeneratorsDecimate, ReachesTargetAndNeverIncreases) {
    for (size_t target : {500u, 1000u, 2000u, 3000u}) {
        const Mesh d = decimate(bunny(), target);
        EXPECT_LE(d.triangleCount(), bunny().triangleCount());
        EXPECT_LE(off(d.triangleCount(), target), target / 10) << "target " << target << " got " << d.triangleCount();
        std::vector<bool> used(d.vertexCount());
        for (const Triangle& t : d.triangles)
            for (uint32_t v : t) used[v] = true;
        EXPECT_EQ(std::count(used.begin(), used.end(), false), 0) << "unreferenced vertices kept";
        EXPECT_NO_THROW(validateMesh(d, "decimated"));
    }
    EXPECT_EQ(decimate(bunny(), bunny().triangleCount()), bunny());
    EXPECT_EQ(decimate(bunny(), 10 * bunny().triangleCount()), bunny());
}

// Trap: a triangle soup is all border, where edge collapses cannot keep the topology and
// meshopt_simplify stops at once; the sloppy fallback must still get near the target.
TEST(GeneratorsDecimate, SoupFallsBackToSloppy) {
    Mesh soup;
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j) {
            const uint32_t b = uint32_t(soup.positions.size());
            const float x = float(i) * 0.1f, y = float(j) * 0.1f;
            soup.positions.insert(soup.positions.end(),
                                  {Vec3f(x, y, 0), Vec3f(x + 0.1f, y, 0), Vec3f(x, y + 0.1f, 0.01f * float(i % 3))});
            soup.triangles.push_back({b, b + 1, b + 2});
        }
    const Mesh d = decimate(soup, 400);
    EXPECT_LT(d.triangleCount(), soup.triangleCount());
    // meshopt_simplify alone stops at 965 here; the sloppy simplifier gets 361.
    EXPECT_LE(off(d.triangleCount(), 400), 100u) << d.triangleCount();
}

// ---- resample -------------------------------------------------------------------------------

// Trap: upsampling by "subdivide past the target, then decimate" folds the coplanar patches
// that subdivision makes (measured: 54 overlapping pairs at 50,000). Counts must land near the
// target and the rest bunny must stay free of self-intersections at every count.
TEST(GeneratorsResample, TargetsAndNoNewIntersections) {
    EXPECT_EQ(findSelfIntersections(bunny()).pairs.size(), 0u) << "the shipped bunny itself";
    for (size_t target : {3000u, 5000u, 50000u}) {
        const Mesh r = resample(bunny(), target);
        EXPECT_LE(off(r.triangleCount(), target), target / 100) << "target " << target << " got " << r.triangleCount();
        EXPECT_NO_THROW(validateMesh(r, "resampled"));
        EXPECT_EQ(findSelfIntersections(r).pairs.size(), 0u) << "target " << target;
    }
    EXPECT_EQ(resample(bunny(), bunny().triangleCount()), bunny());
}

// Trap: 300k triangles is the paper's top size; generation must stay interactive (< 2 s in a
// Release build; measured about 20 ms) and land on the target.
TEST(GeneratorsResample, Bunny300kIsQuick) {
    const auto start = std::chrono::steady_clock::now();
    SceneRequest q;
    q.triangles = 300000;
    const Animation a = makeDeformedBunny(bunny(), q);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LE(off(a.scene.triangleCount(), 300000), 3000u) << a.scene.triangleCount();
#ifdef NDEBUG
    EXPECT_LT(s, 2.0);
#endif
    std::printf("deformed bunny, 300k: %zu triangles in %.3f s\n", a.scene.triangleCount(), s);
}

// ---- deformed bunny -------------------------------------------------------------------------

// Trap: the deformation must make ONE localized crossing (the bent ear through the back), not
// several, and must do it at every triangle count; the rest (undeformed) mesh has none.
TEST(GeneratorsBunny, SingleLocalizedIntersectionArea) {
    const double bunnyDiagonal = diagonal(referencedBounds(bunny()));
    for (size_t target : {3000u, 5000u, 10000u}) {
        SceneRequest q;
        q.triangles = target;
        const Animation a = makeDeformedBunny(bunny(), q);
        ASSERT_EQ(a.scene.objects.size(), 1u);
        EXPECT_EQ(a.scene.objects[0].name, "bunny");
        const Mesh& m = a.scene.objects[0].mesh;
        EXPECT_EQ(m.triangles, resample(bunny(), target).triangles);
        const Intersections x = findSelfIntersections(m);
        EXPECT_GT(x.pairs.size(), 10u) << "target " << target;
        // Localized: the intersecting triangles fit in a box a quarter of the bunny's size,
        // where the ear meets the back (x -2.5..1.5, y 4.5..8.5 in the shipped bunny's frame).
        EXPECT_LT(diagonal(x.box), 0.25 * bunnyDiagonal) << "target " << target;
        EXPECT_GT(x.box.lo.x(), -2.5f);
        EXPECT_LT(x.box.hi.x(), 1.5f);
        EXPECT_GT(x.box.lo.y(), 4.5f);
        EXPECT_LT(x.box.hi.y(), 8.5f);
        // One area: the intersecting triangles, joined by shared vertices and by the pairs
        // themselves, form a single cluster.
        std::vector<uint32_t> parent(m.triangleCount());
        std::iota(parent.begin(), parent.end(), 0u);
        auto find = [&](uint32_t v) {
            while (parent[v] != v) v = parent[v] = parent[parent[v]];
            return v;
        };
        std::vector<bool> in(m.triangleCount());
        for (const auto& [p, r] : x.pairs) {
            in[p] = in[r] = true;
            parent[find(p)] = find(r);
        }
        std::map<uint32_t, uint32_t> firstAtVertex;
        for (uint32_t t = 0; t < m.triangleCount(); ++t)
            if (in[t])
                for (uint32_t v : m.triangles[t]) {
                    auto [it, fresh] = firstAtVertex.emplace(v, t);
                    if (!fresh) parent[find(t)] = find(it->second);
                }
        std::set<uint32_t> clusters;
        for (uint32_t t = 0; t < m.triangleCount(); ++t)
            if (in[t]) clusters.insert(find(t));
        EXPECT_EQ(clusters.size(), 1u) << "target " << target;
        std::printf("deformed bunny %zu: %zu triangles, %zu intersecting pairs\n", target, m.triangleCount(),
                    x.pairs.size());
    }
}

// Trap: the animation must start from the undeformed mesh bit for bit (frame 0), end at the
// still scene, keep the vertex count in every frame, and cross only once the ear is down.
TEST(GeneratorsBunny, AnimationGrowsFromRest) {
    const Animation a = makeDeformedBunny(bunny(), request(3000, 5));
    ASSERT_NO_FATAL_FAILURE(assertValid(a, 5, "bunny"));
    const Mesh rest = resample(bunny(), 3000);
    for (const Frame& f : a.frames) {
        ASSERT_EQ(f.poses.size(), 1u);
        ASSERT_TRUE(f.poses[0].positions.has_value());
        EXPECT_EQ(f.poses[0].positions->size(), rest.vertexCount());
    }
    EXPECT_EQ(bits(a.sceneAt(0).objects[0].mesh), bits(rest));
    EXPECT_EQ(bits(a.sceneAt(4).objects[0].mesh), bits(a.scene.objects[0].mesh));
    EXPECT_EQ(findSelfIntersections(a.sceneAt(0).objects[0].mesh).pairs.size(), 0u);
    EXPECT_GT(findSelfIntersections(a.sceneAt(4).objects[0].mesh).pairs.size(), 0u);
}

// ---- two cows -------------------------------------------------------------------------------

// Trap: CGAL's cow is not clean: it self-intersects natively around its head (83 pairs here at
// full resolution, x in [-0.5, -0.39]); "many crossings" must be counted between the two
// copies, not inherited from each copy.
TEST(GeneratorsCows, ManyCrossingsBetweenTheCopies) {
    EXPECT_GT(findSelfIntersections(cow()).pairs.size(), 0u) << "documented: the shipped cow self-intersects";
    SceneRequest q;
    q.triangles = 3000;
    const Animation a = makeTwoCows(cow(), q);
    ASSERT_EQ(a.scene.objects.size(), 1u);
    EXPECT_EQ(a.scene.objects[0].name, "two_cows");
    const Mesh& m = a.scene.objects[0].mesh;
    EXPECT_LE(off(m.triangleCount(), 3000), 30u);
    const uint32_t half = uint32_t(m.triangleCount() / 2);
    const Intersections x = findSelfIntersections(m);
    size_t between = 0;
    for (const auto& [p, r] : x.pairs) between += (p < half) != (r < half);
    EXPECT_GT(between, 50u);
    std::printf("two cows 3000: %zu intersecting pairs, %zu between the copies\n", x.pairs.size(), between);
}

// Trap: the moving copy must start and end clear of the first, and the middle frame is the still
// scene; the first copy never moves.
TEST(GeneratorsCows, SecondCowMovesThroughTheFirst) {
    const Animation a = makeTwoCows(cow(), request(3000, 9));
    ASSERT_NO_FATAL_FAILURE(assertValid(a, 9, "cows"));
    const Mesh& still = a.scene.objects[0].mesh;
    const size_t half = still.vertexCount() / 2;
    const uint32_t halfT = uint32_t(still.triangleCount() / 2);
    auto between = [&](const Mesh& m) {
        size_t n = 0;
        for (const auto& [p, r] : findSelfIntersections(m).pairs) n += (p < halfT) != (r < halfT);
        return n;
    };
    const Mesh first = a.sceneAt(0).objects[0].mesh, last = a.sceneAt(8).objects[0].mesh;
    EXPECT_EQ(between(first), 0u);
    EXPECT_EQ(between(last), 0u);
    EXPECT_EQ(bits(a.sceneAt(4).objects[0].mesh), bits(still));
    for (size_t v = 0; v < half; ++v) EXPECT_EQ(first.positions[v], still.positions[v]);
}

// ---- cylinders ------------------------------------------------------------------------------

// Trap: "many interpenetrating" must still leave most pairs apart (else nothing is culled);
// tubes are open and never cross themselves; counts and names as documented.
TEST(GeneratorsCylinders, SomeButNotAllPairsIntersect) {
    SceneRequest q;
    q.triangles = 5000;
    const Animation a = makeCylinders(100, q);
    ASSERT_EQ(a.scene.objects.size(), 100u);
    EXPECT_EQ(a.scene.objects[0].name, "cyl_000");
    EXPECT_EQ(a.scene.objects[99].name, "cyl_099");
    EXPECT_LE(off(a.scene.triangleCount(), 5000), 250u);
    std::vector<uint32_t> owner;
    const Mesh all = mergeWorld(a.scene, &owner);
    const Intersections x = findSelfIntersections(all);
    std::set<std::pair<uint32_t, uint32_t>> objectPairs;
    std::set<uint32_t> touched;
    for (const auto& [p, r] : x.pairs) {
        EXPECT_NE(owner[p], owner[r]) << "a tube crosses itself";
        objectPairs.insert({owner[p], owner[r]});
        touched.insert(owner[p]);
        touched.insert(owner[r]);
    }
    EXPECT_GT(objectPairs.size(), 10u);
    EXPECT_LT(objectPairs.size(), 100u * 99u / 2u / 10u);
    EXPECT_GT(touched.size(), 20u);
    EXPECT_LT(touched.size(), 95u);
    std::printf("cylinders 100 x 5000: %zu intersecting triangle pairs, %zu object pairs, %zu objects touched\n",
                x.pairs.size(), objectPairs.size(), touched.size());
}

// Trap: the seed must matter (a generator ignoring it would pass every other test).
TEST(GeneratorsCylinders, DifferentSeedsDiffer) {
    SceneRequest q;
    q.triangles = 2000;
    const Animation a = makeCylinders(20, q);
    q.seed = 2;
    const Animation b = makeCylinders(20, q);
    EXPECT_NE(bits(a), bits(b));
    EXPECT_EQ(a.scene.triangleCount(), b.scene.triangleCount());
}

// Trap: every frame must give positions for every object, with unchanged counts; frame 0 is
// the straight (still) scene.
TEST(GeneratorsCylinders, AnimationBendsEveryTube) {
    const Animation a = makeCylinders(20, request(2000, 6));
    ASSERT_NO_FATAL_FAILURE(assertValid(a, 6, "cylinders"));
    for (const Frame& f : a.frames) {
        ASSERT_EQ(f.poses.size(), 20u);
        for (size_t i = 0; i < 20; ++i) {
            ASSERT_TRUE(f.poses[i].positions.has_value());
            EXPECT_EQ(f.poses[i].positions->size(), a.scene.objects[i].mesh.vertexCount());
        }
    }
    for (size_t i = 0; i < 20; ++i) {
        EXPECT_EQ(bits(a.sceneAt(0).objects[i].mesh), bits(a.scene.objects[i].mesh));
        EXPECT_NE(bits(a.sceneAt(1).objects[i].mesh), bits(a.scene.objects[i].mesh));
    }
}

// ---- twist ----------------------------------------------------------------------------------

// Trap: a twist is a rotation about the longest axis: coordinates along that axis must not move
// at all, distances from the axis must be kept, and frame 0 is the mesh itself bit for bit.
TEST(GeneratorsTwist, RotatesAboutTheLongestAxis) {
    SceneRequest q;
    q.frames = 4;
    Mesh base = tetrahedron();
    for (Vec3f& p : base.positions) p.z() *= 3.0f;  // z is the longest axis
    base = subdivide(base);
    const Animation a = makeTwistAnimation(base, q);
    ASSERT_NO_FATAL_FAILURE(assertValid(a, 4, "twist"));
    EXPECT_EQ(bits(a.sceneAt(0).objects[0].mesh), bits(base));
    const Mesh end = a.sceneAt(3).objects[0].mesh;
    EXPECT_EQ(bits(end), bits(a.scene.objects[0].mesh));
    const Bounds b = referencedBounds(base);
    const Vec3f c = (b.lo + b.hi) * 0.5f;
    bool moved = false;
    for (size_t v = 0; v < base.vertexCount(); ++v) {
        const Vec3f p = base.positions[v], r = end.positions[v];
        EXPECT_EQ(p.z(), r.z());
        const float d0 = std::hypot(p.x() - c.x(), p.y() - c.y()), d1 = std::hypot(r.x() - c.x(), r.y() - c.y());
        EXPECT_NEAR(d0, d1, 1e-5f);
        moved = moved || p != r;
    }
    EXPECT_TRUE(moved);
}

// ---- determinism ----------------------------------------------------------------------------

// Trap: hidden nondeterminism (hash order, uninitialized memory, std distributions): every
// generator, run twice, gives the same bits.
TEST(GeneratorsDeterminism, SameInputsSameBits) {
    SceneRequest q;
    q.triangles = 4000;
    q.frames = 3;
    q.seed = 7;
    EXPECT_EQ(bits(resample(bunny(), 7000)), bits(resample(bunny(), 7000)));
    EXPECT_EQ(bits(decimate(cow(), 1234)), bits(decimate(cow(), 1234)));
    EXPECT_EQ(bits(makeDeformedBunny(bunny(), q)), bits(makeDeformedBunny(bunny(), q)));
    EXPECT_EQ(bits(makeTwoCows(cow(), q)), bits(makeTwoCows(cow(), q)));
    EXPECT_EQ(bits(makeCylinders(30, q)), bits(makeCylinders(30, q)));
    EXPECT_EQ(bits(makeTwistAnimation(cow(), q)), bits(makeTwistAnimation(cow(), q)));
}

// ---- sheets ----------------------------------------------------------------------------------

// Trap: a "tilted sheets" scene on which nothing crosses (no edge-on loss to see) or everything
// does, or sheets tilted by other than documented: names, counts, every normal within 0.5 to 1.5
// times the tilt from +z, some but not all sheet pairs crossing, same seed same bytes.
TEST(GeneratorsSheets, NearlyParallelSomeCross) {
    SceneRequest q;
    q.triangles = 4000;
    const Animation a = makeSheets(8, 3.0, q);
    ASSERT_EQ(a.scene.objects.size(), 8u);
    EXPECT_EQ(a.scene.objects[0].name, "sheet_000");
    EXPECT_EQ(a.frames.size(), 0u);
    EXPECT_LE(off(a.scene.triangleCount(), 4000), 400u);
    const double deg = 3.14159265358979323846 / 180;
    for (const Object& o : a.scene.objects)
        for (const Triangle& t : o.mesh.triangles) {
            const Vec3d p0 = o.mesh.positions[t[0]].cast<double>(), p1 = o.mesh.positions[t[1]].cast<double>(),
                        p2 = o.mesh.positions[t[2]].cast<double>();
            const double tilt = std::acos(std::abs((p1 - p0).cross(p2 - p0).normalized().z()));
            EXPECT_GT(tilt, 1.5 * deg - 1e-4);
            EXPECT_LT(tilt, 4.5 * deg + 1e-4);
        }
    std::vector<uint32_t> owner;
    const Intersections x = findSelfIntersections(mergeWorld(a.scene, &owner));
    std::set<std::pair<uint32_t, uint32_t>> objectPairs;
    for (const auto& [p, r] : x.pairs) {
        EXPECT_NE(owner[p], owner[r]) << "a flat sheet crosses itself";
        objectPairs.insert({std::min(owner[p], owner[r]), std::max(owner[p], owner[r])});
    }
    EXPECT_GT(objectPairs.size(), 2u);
    EXPECT_LT(objectPairs.size(), 8u * 7u / 2u);
    EXPECT_EQ(bits(a), bits(makeSheets(8, 3.0, q)));
    q.seed = 2;
    EXPECT_NE(bits(a), bits(makeSheets(8, 3.0, q)));
}

// ---- source meshes ---------------------------------------------------------------------------

// Trap: a source mesh with no extent to take fractions of (all vertices one point; for the bunny a
// mesh without height, or a line) divides by zero and writes NaN positions; it must be refused
// naming the mesh, by every generator made from a mesh.
TEST(GeneratorsSourceMesh, ZeroExtentIsRefusedNamingTheMesh) {
    auto meshOf = [](std::vector<Vec3f> positions) {
        Mesh m;
        m.positions = std::move(positions);
        m.triangles = {{0, 1, 2}};
        return m;
    };
    const Mesh point = meshOf({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}});
    const Mesh flatInY = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 0, 1}});
    const Mesh upright = meshOf({{0, 0, 0}, {0, 1, 0}, {0, 2, 0}});
    auto refused = [](const std::function<void()>& make, const std::string& cause) {
        try {
            make();
            ADD_FAILURE() << "accepted: " << cause;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind("m.off: ", 0), 0u) << e.what();
            EXPECT_NE(std::string(e.what()).find(cause), std::string::npos) << e.what();
        }
    };
    const SceneRequest q = request(100, 2);
    refused([&] { makeDeformedBunny(point, q, "m.off"); }, "zero extent (all its vertices are one point)");
    refused([&] { makeTwoCows(point, q, "m.off"); }, "zero extent");
    refused([&] { makeTwistAnimation(point, q, "m.off"); }, "zero extent");
    refused([&] { makeDeformedBunny(flatInY, q, "m.off"); }, "zero extent along y");
    refused([&] { makeDeformedBunny(upright, q, "m.off"); }, "zero extent along x and z");
    refused([&] { makeTwoCows(meshOf({{-3e38f, 0, 0}, {3e38f, 0, 0}, {0, 1, 0}}), q, "m.off"); }, "overflows float");
    // A flat mesh still twists (about its longest axis) and still makes two cows.
    EXPECT_NO_THROW(makeTwistAnimation(flatInY, q, "m.off"));
    EXPECT_NO_THROW(makeTwoCows(flatInY, q, "m.off"));
}
