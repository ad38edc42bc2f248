// The Cullide loop and both reducePCS forms, end to end on the CPU reference backend.
#include "cullide/cullide.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/options.h"
#include "cullide/parallel.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene_io.h"

#include "test_util.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <map>
#include <memory>
#include <set>

#include <tbb/task_arena.h>

using namespace cullide;
using cullide::test::box;
using cullide::test::rotation;
using cullide::test::sceneOf;

namespace {

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

CullideResult prune(const Scene& scene, CullMethod method, uint32_t leafSize,
                    HierarchyKind kind = HierarchyKind::Connectivity, int threads = 0, int resolution = 256,
                    double autoCoverage = 0) {
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

// Two unit cubes that touch and do not overlap: A = [0,1]^3 and B = A moved by `offset`
// ((1,0,0): face to face, (1,1,0): along an edge, (1,1,1): at one corner). `rotated` turns both
// about z by atan(3/4) (cos 0.8, sin 0.6), in float on the positions: B's corners on the shared
// face are computed from the same inputs as A's, so the contact stays exact (the shared face
// stays vertical, so the shared corners are exactly coplanar, and both cubes split it along the
// same diagonal).
struct TouchingCase {
    const char* id;  // the test instance's name
    Vec3f offset;
    bool rotated;
    size_t pairs;  // touching pairs between the cubes (the oracle; measured)
    size_t colliding;  // triangles in some pair
};
const std::array<TouchingCase, 4> kTouching{{{"FaceFace", Vec3f(1, 0, 0), false, 62, 20},
                                             {"FaceFaceRotated", Vec3f(1, 0, 0), true, 62, 20},
                                             {"EdgeEdge", Vec3f(1, 1, 0), false, 44, 16},
                                             {"CornerCorner", Vec3f(1, 1, 1), false, 36, 12}}};

Scene touchingCubes(const TouchingCase& c) {
    auto cube = [&](const Vec3f& lo) {
        Mesh m = box(lo, lo + Vec3f(1, 1, 1));
        if (c.rotated)
            for (Vec3f& p : m.positions) p = Vec3f(0.8f * p.x() - 0.6f * p.y(), 0.6f * p.x() + 0.8f * p.y(), p.z());
        return m;
    };
    return sceneOf({{cube(Vec3f(0, 0, 0)), Transform::Identity()}, {cube(c.offset), Transform::Identity()}});
}

struct TouchOutcome {
    size_t pcs = 0, pairs = 0, lost = 0;  // PCS size, the oracle's pairs, pairs with a triangle pruned
};

TouchOutcome pruneTouching(const Scene& s, CullMethod method, int resolution, DepthFormat depth, uint32_t leafSize,
                           std::vector<Vec3d> directions = axisDirections(), double autoCoverage = 0) {
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.method = method;
    o.width = o.height = resolution;
    o.autoCoverage = autoCoverage;
    o.depth = depth;
    o.hierarchy.leafSize = leafSize;
    o.directions = std::move(directions);
    const CullideResult r = runCullide(s, *backend, o);
    const std::set<PcsTriangle> kept(r.pcs.begin(), r.pcs.end());
    const oracle::Truth truth = oracle::findIntersections(s);
    TouchOutcome out{kept.size(), truth.pairs.size(), 0};
    for (const oracle::IntersectingPair& p : truth.pairs)
        out.lost += !kept.count({p.objectA, p.triangleA}) || !kept.count({p.objectB, p.triangleB});
    return out;
}

}  // namespace

// Two separated boxes in a generic orientation, leaves of one triangle (always self-visible
// unless occluded): nothing collides, so both methods prune everything. Catches a reducePCS that
// keeps nodes it should prune (e.g. testing a node against its own earlier draw with GEQUAL, or
// fragments landing on the cleared far value).
TEST(Cullide, SeparatedBoxesArePruned) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.3, 0.5, 0.7)},
                             {box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.9, 0.2, 0.4, Vec3f(3, 0.2, 0.1))}});
    for (CullMethod m : {CullMethod::Original, CullMethod::Modified}) {
        const CullideResult r = prune(s, m, 1);
        EXPECT_TRUE(r.pcs.empty()) << toString(m) << ": " << r.pcs.size() << " triangles kept";
        EXPECT_FALSE(r.passes.empty());
    }
}

// Two interpenetrating boxes, generic orientation: the PCS holds every crossing triangle, for
// both methods and both hierarchies (the hierarchy changes speed, not what may be pruned), at a
// fixed resolution and with adaptive resolution (each call its own viewport).
TEST(Cullide, InterpenetratingBoxesKeepCrossingTriangles) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.3, 0.5, 0.7)},
                             {box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.9, 0.2, 0.4, Vec3f(0.5, 0.4, 0.3))}});
    const std::set<PcsTriangle> truth = crossingTriangles(s);
    ASSERT_GE(truth.size(), 4u);
    for (CullMethod m : {CullMethod::Original, CullMethod::Modified})
        for (HierarchyKind k : {HierarchyKind::Connectivity, HierarchyKind::Random})
            for (double adaptive : {0.0, 1.0, 4.0}) {
                const CullideResult r = prune(s, m, 1, k, 0, 256, adaptive);
                EXPECT_TRUE(contains(r, truth)) << toString(m) << "/" << toString(k) << " auto " << adaptive << ": PCS "
                                                << r.pcs.size() << ", crossing " << truth.size();
                EXPECT_LT(r.pcs.size(), 24u) << "something was pruned at all";
            }
}

// Trap: runCullide(Scene&&) (trace recording gives up each frame's scene to save memory)
// emptying the scene before its geometry is read, or answering differently from the const& form.
TEST(Cullide, ConsumedSceneGivesTheSamePcsAndIsEmptied) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.3, 0.5, 0.7)},
                             {box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.9, 0.2, 0.4, Vec3f(0.5, 0.4, 0.3))}});
    const CullideResult expected = prune(s, CullMethod::Modified, 1);
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.width = o.height = 256;
    o.hierarchy.leafSize = 1;
    o.hierarchy.branching = 2;
    Scene consumed = s;
    const CullideResult got = runCullide(std::move(consumed), *backend, o);
    EXPECT_EQ(got.pcs, expected.pcs);
    EXPECT_FALSE(expected.pcs.empty());
    EXPECT_TRUE(consumed.objects.empty());  // NOLINT(bugprone-use-after-move): emptied on purpose
}

// runCullide lends its geometry to the CPU backend (no copy) for the run only. Traps: the backend
// still reading the run's freed arrays afterwards (ASan: use after free), instead of having
// forgotten them, so a draw without new geometry is refused; and a second run on the same
// backend answering differently from the first.
TEST(Cullide, LentGeometryIsTakenBackAfterTheRun) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.3, 0.5, 0.7)},
                             {box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.9, 0.2, 0.4, Vec3f(0.5, 0.4, 0.3))}});
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.width = o.height = 64;
    const CullideResult first = runCullide(s, *backend, o);
    CommandList list;
    list.clear(1.0);
    list.draw(0, 1);
    EXPECT_THROW(backend->execute(list), InputError);
    const CullideResult second = runCullide(s, *backend, o);
    EXPECT_EQ(first.pcs, second.pcs);
    EXPECT_FALSE(first.pcs.empty());
}

// A deforming animation pruned frame by frame with a hierarchy cache: the PCS and every pass
// are those of fresh builds (trap: a reused hierarchy that no longer matches the geometry), the
// first frame builds and the later ones reuse, and a frame with other triangles rebuilds.
TEST(Cullide, HierarchyCacheGivesTheSamePcsOverFrames) {
    const Mesh source = loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/bunny.off");
    SceneRequest req;
    req.triangles = 4000;
    req.frames = 4;
    const Animation a = makeDeformedBunny(source, req);
    auto backend = raster::makeCpuBackend();
    CullideOptions fresh;
    CullideOptions cached = fresh;
    cached.hierarchyCache = std::make_shared<HierarchyCache>();
    for (size_t f = 0; f < a.frameCount(); ++f) {
        const Scene s = a.sceneAt(f);
        const CullideResult want = runCullide(s, *backend, fresh), got = runCullide(s, *backend, cached);
        EXPECT_EQ(got.pcs, want.pcs) << "frame " << f;
        ASSERT_EQ(got.passes.size(), want.passes.size());
        for (size_t k = 0; k < got.passes.size(); ++k)
            EXPECT_EQ(got.passes[k].trianglesOut, want.passes[k].trianglesOut);
        EXPECT_EQ(got.hierarchiesReused, f == 0 ? 0u : 1u) << "frame " << f;
        EXPECT_EQ(want.hierarchiesReused, 0u);
    }
    Scene other = a.sceneAt(0);
    other.objects[0].mesh.triangles.pop_back();
    const CullideResult rebuilt = runCullide(other, *backend, cached);
    EXPECT_EQ(rebuilt.hierarchiesReused, 0u);
    EXPECT_EQ(rebuilt.pcs, runCullide(other, *backend, fresh).pcs);
}

// A ribbon that passes through itself: one object, so only the modified method can see it. The
// original method is inter-object only and prunes a lone object at once (its documented limit).
TEST(Cullide, SelfCrossingRibbonKeptByModified) {
    Scene s = sceneOf({{selfCrossingRibbon(121), rotation(0.31, 0.47, 0.23)}});
    const std::set<PcsTriangle> truth = crossingTriangles(s);
    ASSERT_GE(truth.size(), 2u);
    for (HierarchyKind k : {HierarchyKind::Connectivity, HierarchyKind::Random}) {
        const CullideResult r = prune(s, CullMethod::Modified, 4, k, 0, 500);
        EXPECT_TRUE(contains(r, truth)) << toString(k) << ": PCS " << r.pcs.size() << ", crossing " << truth.size();
        EXPECT_LT(r.pcs.size() * 4, s.triangleCount()) << "most of the ribbon is pruned";
    }
    EXPECT_TRUE(prune(s, CullMethod::Original, 4).pcs.empty());
}

// A finely tessellated closed sphere that does not intersect itself: the object is never
// self-visible as a whole, but its small connected leaves each are, from one of the six axis
// directions (their normal cones are narrow). Modified prunes it completely at leaf level; a
// random hierarchy's scattered leaves cannot be pruned that way.
TEST(Cullide, ClosedSpherePrunedAtLeafLevel) {
    const Scene s = sceneOf({{icosphere(4), rotation(0.2, 0.3, 0.1)}});  // 5120 triangles
    const CullideResult r = prune(s, CullMethod::Modified, 16, HierarchyKind::Connectivity, 0, 500);
    EXPECT_TRUE(r.pcs.empty()) << r.pcs.size() << " triangles kept";
    EXPECT_GE(r.levels, 5u) << "pruned only after descending the hierarchy";
    const CullideResult random = prune(s, CullMethod::Modified, 16, HierarchyKind::Random, 0, 500);
    EXPECT_GT(random.pcs.size(), s.triangleCount() / 2) << "random leaves are not self-visible";
}

// Two coplanar, overlapping open quads (a contact, no penetration), tilted so no axis sees them
// edge-on: original keeps both (equal depth passes GEQUAL), modified prunes both (equal depth
// fails GREATER) — the paper's stated drawback, kept here so it stays documented.
TEST(Cullide, CoplanarContactOriginalKeepsModifiedLoses) {
    Mesh a;
    a.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    a.triangles = {{0, 1, 2}, {0, 2, 3}};
    Mesh b = a;
    for (auto& p : b.positions) p += Vec3f(0.5f, 0.25f, 0);
    const Transform tilt = rotation(0.5, 0.6, 0.2);
    const Scene s = sceneOf({{a, tilt}, {b, tilt}});
    EXPECT_EQ(prune(s, CullMethod::Original, 2).pcs.size(), 4u);
    EXPECT_TRUE(prune(s, CullMethod::Modified, 2).pcs.empty());
}

// Axis-aligned boxes that interpenetrate, seen along the axes: every face is edge-on (zero area,
// no fragments) in two of the three axes, so every leaf is "fully visible" there and pruned, and
// the crossing is lost by both methods — the paper's edge-on failure, tested so it is not hidden.
// The same boxes with spread directions (no face edge-on) keep their crossing triangles.
TEST(Cullide, AxisAlignedBoxesLoseCrossingEdgeOn) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(2, 2, 2)), Transform::Identity()},
                             {box(Vec3f(1.1f, 1.3f, 0.7f), Vec3f(3, 3, 3)), Transform::Identity()}});
    const std::set<PcsTriangle> truth = crossingTriangles(s);
    ASSERT_GE(truth.size(), 4u);
    for (CullMethod m : {CullMethod::Original, CullMethod::Modified})
        EXPECT_TRUE(prune(s, m, 1).pcs.empty()) << toString(m);

    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.hierarchy.leafSize = 1;
    o.directions = {Vec3d(1, 2, 3).normalized(), Vec3d(-3, 1, 2).normalized(), Vec3d(2, -3, 1).normalized()};
    const CullideResult r = runCullide(s, *backend, o);
    EXPECT_TRUE(contains(r, truth)) << "PCS " << r.pcs.size() << ", crossing " << truth.size();
}

// The touching cubes, one test instance per case (face-face, face-face rotated, edge-edge,
// corner-corner), so that each stays short.
class CullideTouching : public ::testing::TestWithParam<TouchingCase> {};

// Trap: "the original method keeps contacts" read as a promise about the image. Two cubes that
// only touch: in a view along the contact plane (+-y or +-z for face-face, +-z for the turned
// pair, every axis for edge and corner) their projections share only a segment or a point. A
// pixel centre on that boundary is owned by exactly one of the two (the fill rule,
// raster/include/cullide/raster/rules.h rule 5), any other centre by at most one, so no centre
// is shared, GEQUAL has nothing to pass on, and both objects are pruned whole at the object
// level: every pair lost, with any leaf size, whether the contact falls between centres (500)
// or on them (501; CullideTouchingView).
TEST_P(CullideTouching, OriginalLosesEveryTouchingPair) {
    const TouchingCase& c = GetParam();
    const Scene s = touchingCubes(c);
    for (int res : {500, 501})
        for (uint32_t leaf : {1u, 16u}) {
            const TouchOutcome r = pruneTouching(s, CullMethod::Original, res, DepthFormat::unorm(24), leaf);
            EXPECT_EQ(r.pairs, c.pairs);
            EXPECT_EQ(r.pcs, 0u) << res << " leaf " << leaf;
            EXPECT_EQ(r.lost, c.pairs) << res << " leaf " << leaf;
        }
}

// Trap: the modified method looks "safe" on touching cubes with the default leaves: a 12-triangle
// cube is one leaf of 16, a closed surface that hides its own back faces in every direction, so
// both cubes stay whole in the PCS (24) whether or not they touch. With one triangle per leaf
// nothing hides itself and every touching pair is lost: equal depth fails GREATER, and where the
// projections only abut no centre is shared at all.
TEST_P(CullideTouching, ModifiedKeepsClosedLeavesNotContacts) {
    const TouchingCase& c = GetParam();
    const Scene s = touchingCubes(c);
    const TouchOutcome whole = pruneTouching(s, CullMethod::Modified, 500, DepthFormat::unorm(24), 16);
    EXPECT_EQ(whole.pairs, c.pairs);
    EXPECT_EQ(whole.pcs, 24u);
    EXPECT_EQ(whole.lost, 0u);
    const TouchOutcome single = pruneTouching(s, CullMethod::Modified, 500, DepthFormat::unorm(24), 1);
    EXPECT_EQ(single.pcs, 0u);
    EXPECT_EQ(single.lost, c.pairs);
}

// Trap: a coarse image or a coarse depth format losing a contact in the reliable method. Its
// coverage is conservative (a boundary centre counts for both cubes) and its depths are
// intervals, so every touching pair is kept at 16x16 with D8 as at 2048x2048 with float depth;
// with one triangle per leaf the PCS is exactly the touching triangles (nothing else kept). At
// 2048 one view along the contact plane (+z, where the original loses every pair, checked here
// too) with the default leaves (the cubes are two units tested against each other) keeps the test
// short; sanitizer builds use 256.
TEST_P(CullideTouching, ReliableKeepsEveryTouchingPairCoarseAndFine) {
    const TouchingCase& c = GetParam();
    const Scene s = touchingCubes(c);
    const TouchOutcome coarse = pruneTouching(s, CullMethod::Reliable, 16, DepthFormat::unorm(8), 1);
    EXPECT_EQ(coarse.pairs, c.pairs);
    EXPECT_EQ(coarse.lost, 0u);
    EXPECT_EQ(coarse.pcs, c.colliding);
    const int fine = CULLIDE_SANITIZED ? 256 : 2048;
    const TouchOutcome f = pruneTouching(s, CullMethod::Reliable, fine, DepthFormat::float32(), 16, {Vec3d(0, 0, 1)});
    EXPECT_EQ(f.lost, 0u) << fine;
    EXPECT_EQ(f.pcs, 24u) << fine;
    EXPECT_EQ(pruneTouching(s, CullMethod::Original, fine, DepthFormat::float32(), 16, {Vec3d(0, 0, 1)}).lost, c.pairs)
        << fine << ": the original loses them all in this view";
    // Adaptive resolution (refitted views, rounds until one prunes nothing) keeps them too.
    const TouchOutcome adaptive =
        pruneTouching(s, CullMethod::Reliable, 16, DepthFormat::unorm(8), 1, axisDirections(), kDefaultAutoCoverage);
    EXPECT_EQ(adaptive.lost, 0u);
    EXPECT_EQ(adaptive.pcs, c.colliding);
}

INSTANTIATE_TEST_SUITE_P(Cubes, CullideTouching, ::testing::ValuesIn(kTouching),
                         [](const ::testing::TestParamInfo<TouchingCase>& i) { return std::string(i.param.id); });

// Trap: calling the face-face loss "sampling" (the contact between pixel columns) when the fill
// rule alone suffices. In the +y view that prunes the face-face cubes (fitted to both, x in [0, 2]
// filling the width) the contact x = 1 lies between two columns of centres at 500 pixels (window
// 250.0) and on a column of centres at 501 (250.5), which only one of the cubes owns; the
// original loses every pair at both (CullideTouching.OriginalLosesEveryTouchingPair).
TEST(CullideTouchingView, FaceContactBetweenCentresAt500OnCentresAt501) {
    const Scene s = touchingCubes(kTouching[0]);
    const FlatScene flat = flatten(s);
    const TriangleRange all{0, uint32_t(flat.mesh.triangles.size())};
    for (int res : {500, 501}) {
        const OrthoView v = fitView(flat.mesh.positions, flat.mesh.triangles, {&all, 1}, Vec3d(0, 1, 0), res, res,
                                    DepthFormat::unorm(24));
        const Vec3d w0 = v.toWindow(Vec3f(1, 0, 0)), w1 = v.toWindow(Vec3f(1, 0, 1));
        const double across = std::abs(w0.x() - w1.x()) < 1e-9 ? w0.x() : w0.y();  // constant along the contact
        EXPECT_NEAR(across - std::floor(across), res == 500 ? 0.0 : 0.5, 1e-9) << res;
    }
}

// Trap: reading "the original keeps both cubes" as "it sees the contact". The face-face cubes
// turned about (1, 2, 3) by 40 degrees (in float, B's shared corners from the same inputs as
// A's): no axis lies in the contact plane, so from every axis one cube is partly behind the other
// and, with the default leaves, both stay whole (24). With one triangle per leaf only the four
// triangles of the shared face stay (equal depth over an area passes GEQUAL); the contacts along
// the cubes' edges project to segments in every view and are lost.
TEST(CullideTouchingGeneric, OriginalKeepsTheSharedFaceOnly) {
    const Eigen::Matrix3f r =
        Eigen::AngleAxisf(40 * std::numbers::pi_v<float> / 180, Vec3f(1, 2, 3).normalized()).toRotationMatrix();
    auto cube = [&](const Vec3f& lo) {
        Mesh m = box(lo, lo + Vec3f(1, 1, 1));
        for (Vec3f& p : m.positions) p = r * p;
        return m;
    };
    const Scene s =
        sceneOf({{cube(Vec3f(0, 0, 0)), Transform::Identity()}, {cube(Vec3f(1, 0, 0)), Transform::Identity()}});
    const TouchOutcome whole = pruneTouching(s, CullMethod::Original, 500, DepthFormat::unorm(24), 16);
    EXPECT_EQ(whole.pairs, 62u);
    EXPECT_EQ(whole.pcs, 24u);
    EXPECT_EQ(whole.lost, 0u);
    const TouchOutcome single = pruneTouching(s, CullMethod::Original, 500, DepthFormat::unorm(24), 1);
    EXPECT_EQ(single.pcs, 4u);
    EXPECT_EQ(single.lost, 58u);
}

// Same scene and options: the same PCS and the same per-pass counts, bit for bit, for 1 and 2
// threads and for repeated runs.
TEST(Cullide, DeterministicAcrossThreadsAndRuns) {
    const Scene s = sceneOf({{icosphere(3), rotation(0.2, 0.3, 0.1)},
                             {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                             {selfCrossingRibbon(81), rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
    const CullideResult one = prune(s, CullMethod::Modified, 8, HierarchyKind::Connectivity, 1);
    for (int threads : {1, 2}) {
        const CullideResult r = prune(s, CullMethod::Modified, 8, HierarchyKind::Connectivity, threads);
        EXPECT_EQ(r.pcs, one.pcs) << threads << " threads";
        ASSERT_EQ(r.passes.size(), one.passes.size());
        for (size_t i = 0; i < r.passes.size(); ++i) {
            EXPECT_EQ(r.passes[i].nodesOut, one.passes[i].nodesOut);
            EXPECT_EQ(r.passes[i].trianglesRendered, one.passes[i].trianglesRendered);
        }
    }
    EXPECT_FALSE(one.pcs.empty());
}

// Trap: recordPrunes' log is read instead of onPass's PCS after every call (the study's
// attribution of false prunes). A log that missed a call's dropped nodes, took a kept node for a
// dropped one, or numbered the calls differently would blame the wrong call. Against the PCS each
// call leaves (onPass), for all three methods, fitted and clustered views.
TEST(Cullide, RecordedPrunesMatchThePcsAfterEachCall) {
    const Scene s = sceneOf({{icosphere(3), rotation(0.2, 0.3, 0.1)},
                             {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                             {selfCrossingRibbon(81), rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
    std::vector<size_t> offset{0};
    for (const Object& o : s.objects) offset.push_back(offset.back() + o.mesh.triangleCount());
    auto backend = raster::makeCpuBackend();
    for (CullMethod method : {CullMethod::Original, CullMethod::Modified, CullMethod::Reliable})
        for (ViewMode views : {ViewMode::Fit, ViewMode::Clustered}) {
            CullideOptions o;
            o.method = method;
            o.views = views;
            o.width = o.height = 128;
            o.hierarchy.leafSize = 4;
            o.recordPrunes = true;
            std::vector<uint32_t> expected(offset.back(), CullideResult::kNotPruned);
            std::vector<char> in(offset.back(), 1);
            uint32_t call = 0;
            o.onPass = [&](const PassStats&, std::span<const PcsTriangle> pcs) {
                std::vector<char> next(in.size(), 0);
                for (const PcsTriangle& p : pcs) next[offset[p.object] + p.triangle] = 1;
                for (size_t g = 0; g < in.size(); ++g)
                    if (in[g] && !next[g]) expected[g] = call;
                in.swap(next);
                ++call;
            };
            const CullideResult r = runCullide(s, *backend, o);
            const std::string what = std::string(toString(method)) + (views == ViewMode::Fit ? " fit" : " clustered");
            EXPECT_EQ(r.prunedAtCall, expected) << what;
            EXPECT_EQ(call, r.passes.size()) << what;
            size_t kept = 0, pruned = 0;
            for (uint32_t c : r.prunedAtCall) (c == CullideResult::kNotPruned ? kept : pruned) += 1;
            EXPECT_EQ(kept, r.pcs.size()) << what;
            EXPECT_GT(pruned, 0u) << what;
        }
    CullideOptions plain;  // without recordPrunes: no log
    EXPECT_TRUE(runCullide(s, *backend, plain).prunedAtCall.empty());
}

// Trap: adaptive resolution that depends on the thread count (a median or a sum gathered in
// whatever order the threads finish) would give a different view, hence a different PCS, per
// thread count. Same scene with --resolution auto: the same PCS, per-call viewports and counts.
TEST(Cullide, AdaptiveResolutionDeterministicAcrossThreads) {
    const Scene s = sceneOf({{icosphere(3), rotation(0.2, 0.3, 0.1)},
                             {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                             {selfCrossingRibbon(81), rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
    const CullideResult one = prune(s, CullMethod::Modified, 8, HierarchyKind::Connectivity, 1, 64, 4);
    for (int threads : {2, 4}) {
        const CullideResult r = prune(s, CullMethod::Modified, 8, HierarchyKind::Connectivity, threads, 64, 4);
        EXPECT_EQ(r.pcs, one.pcs) << threads << " threads";
        ASSERT_EQ(r.passes.size(), one.passes.size());
        for (size_t i = 0; i < r.passes.size(); ++i) {
            EXPECT_EQ(r.passes[i].width, one.passes[i].width) << i;
            EXPECT_EQ(r.passes[i].height, one.passes[i].height) << i;
            EXPECT_EQ(r.passes[i].nodesOut, one.passes[i].nodesOut) << i;
        }
    }
}

// Trap: a per-call viewport that is not recorded (or recorded as the option's) makes the
// statistics lie and the study's false-prune attribution refit the wrong view. A fixed run
// records its viewport in every call; an adaptive run never goes below its base and refines the
// calls on the small deep PCS (the 64x64 base is coarse for 2560 triangles). (Its crossings are
// checked on the boxes of InterpenetratingBoxesKeepCrossingTriangles.)
TEST(Cullide, AdaptiveResolutionRecordedPerCall) {
    const Scene s = sceneOf(
        {{icosphere(3), rotation(0.2, 0.3, 0.1)}, {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))}});
    const CullideResult fixed = prune(s, CullMethod::Modified, 4, HierarchyKind::Connectivity, 0, 64);
    for (const PassStats& p : fixed.passes) {
        EXPECT_EQ(p.width, 64);
        EXPECT_EQ(p.height, 64);
        EXPECT_EQ(p.round, 0u);
    }
    const CullideResult adaptive = prune(s, CullMethod::Modified, 4, HierarchyKind::Connectivity, 0, 64, 4);
    int finer = 0;
    for (const PassStats& p : adaptive.passes) {
        EXPECT_TRUE(std::max(p.width, p.height) >= 64 || (p.width == 64 && p.height == 64))
            << p.width << "x" << p.height;
        EXPECT_LE(int64_t(p.width) * p.height, kDefaultAutoBudget);
        finer += std::max(p.width, p.height) > 64;
    }
    EXPECT_GT(finer, 0) << "no call was refined";
}

// The size rule itself (cullide.h): no PCS or large triangles give the base viewport exactly
// (so an adaptive run that never refines is the fixed run); small triangles a finer one in the
// PCS's aspect; the pixel budget and the backend's side limit shrink it, never past 1.
TEST(Cullide, AdaptiveViewportFollowsTheRule) {
    const Mesh big = box(Vec3f(0, 0, 0), Vec3f(2, 1, 1));
    const TriangleRange all{0, uint32_t(big.triangles.size())};
    const Vec3d z(0, 0, 1);
    EXPECT_EQ(adaptiveViewport(big.positions, big.triangles, {}, z, 4, 100, 80, kDefaultAutoBudget, kMaxViewportSide),
              std::make_pair(100, 80));
    // Seen along z the box covers 2 x 1 twice (front and back): 4 / 0.02^2 = 10000 pixels at the
    // base pixel (2/100), fewer than 4 base viewports (4 * 8000): the call wants finer pixels.
    const auto [w, h] =
        adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 4, 100, 80, kDefaultAutoBudget, kMaxViewportSide);
    // (The frame's right and up may be either of x and y.)
    EXPECT_GT(std::max(w, h), 100);
    EXPECT_NEAR(double(std::max(w, h)) / std::min(w, h), 2.0, 0.05) << "the PCS's aspect";
    EXPECT_EQ(adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 0.5, 100, 80, kDefaultAutoBudget,
                               kMaxViewportSide),
              std::make_pair(100, 80))
        << "coverage already above 0.5 base viewports";
    const auto [bw, bh] = adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 1000, 100, 80, 20000, 16384);
    EXPECT_LE(int64_t(bw) * bh, 20000);
    EXPECT_GE(std::max(bw, bh), 100) << "a budget of the base's size or more never goes coarser than the base";
    const auto [sw, sh] =
        adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 1000, 100, 80, kDefaultAutoBudget, 150);
    EXPECT_LE(std::max(sw, sh), 150);
}

// The view is fitted tightly: the PCS's projected bounds touch the viewport (square pixels), and
// its depth extent maps inside (0, 1) with margins, never onto the cleared far value. In each of
// the six axis directions (whose bounds come from the points' box, permuted and negated: a wrong
// axis or sign misses this) and one oblique direction (the dot products), on a box off the origin
// in every axis.
TEST(Cullide, FitViewIsTight) {
    const Mesh m = box(Vec3f(-1, -2, 3), Vec3f(5, 2, 4));
    const TriangleRange all{0, uint32_t(m.triangles.size())};
    for (const Vec3d& dir : {Vec3d(0, 0, 1), Vec3d(0, 0, -1), Vec3d(1, 0, 0), Vec3d(-1, 0, 0), Vec3d(0, 1, 0),
                             Vec3d(0, -1, 0), Vec3d(0.3, -1, 0.2)}) {
        SCOPED_TRACE(testing::Message() << "direction " << dir.transpose());
        const OrthoView v = fitView(m.positions, m.triangles, {&all, 1}, dir, 300, 100, DepthFormat::unorm(16));
        double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9, zmin = 1e9, zmax = -1e9;
        for (const Vec3f& p : m.positions) {
            const Vec3d w = v.toWindow(p);
            xmin = std::min(xmin, w.x()), xmax = std::max(xmax, w.x());
            ymin = std::min(ymin, w.y()), ymax = std::max(ymax, w.y());
            zmin = std::min(zmin, w.z()), zmax = std::max(zmax, w.z());
        }
        // The frame's right/up may be either world axis; whichever extent limits the pixel size
        // fills its side of the viewport exactly and the other is centred.
        const bool xFills = std::abs(xmin) < 1e-9 && std::abs(xmax - 300) < 1e-9;
        const bool yFills = std::abs(ymin) < 1e-9 && std::abs(ymax - 100) < 1e-9;
        EXPECT_TRUE(xFills || yFills) << xmin << " " << xmax << " " << ymin << " " << ymax;
        EXPECT_NEAR(xmin + xmax, 300, 1e-9);
        EXPECT_NEAR(ymin + ymax, 100, 1e-9);
        EXPECT_GT(zmin * 65535, 1.5);
        EXPECT_LT(zmax * 65535, 65535 - 1.5);
        EXPECT_NEAR((v.xmax - v.xmin) / 300, (v.ymax - v.ymin) / 100, 1e-12) << "square pixels";
    }
}

// --- Views per cluster (ViewMode::Clustered) ---

namespace {

CullideResult pruneViews(const Scene& scene, CullMethod method, ViewMode views, int resolution, int threads = 0,
                         double autoCoverage = 0, uint32_t leafSize = 16) {
    raster::CpuBackendOptions bo;
    bo.threads = threads;
    auto backend = raster::makeCpuBackend(bo);
    CullideOptions o;
    o.method = method;
    o.views = views;
    o.width = o.height = resolution;
    o.autoCoverage = autoCoverage;
    o.hierarchy.leafSize = leafSize;
    return runCullide(scene, *backend, o);
}

// Two crossing triangles about one unit across, in a generic orientation (no axis sees one
// edge-on), moved by `at`: the lower one's plane is pierced by the upper one's, well inside.
std::pair<Mesh, Mesh> crossingPair(const Vec3f& at) {
    const Transform t = test::rotation(0.31, 0.47, 0.23, at);
    Mesh a, b;
    a.positions = {t * Vec3f(0, 0, 0), t * Vec3f(1, 0, 0), t * Vec3f(0, 1, 0)};
    b.positions = {t * Vec3f(0.2f, 0.2f, -0.5f), t * Vec3f(0.45f, 0.3f, 0.5f), t * Vec3f(0.15f, 0.5f, 0.5f)};
    a.triangles = b.triangles = {{0, 1, 2}};
    return {a, b};
}

}  // namespace

// The built case of docs/cullide.md#views-per-cluster. Two crossing pairs 1000 units apart: one
// 32x32 view fitted to both has pixels about 31 units wide, so each pair is far below a pixel,
// covers no pixel centre and is "fully visible": fit prunes all four triangles, crossings and
// all. Clustered sees two groups (the pairs' projections are far apart), fits a 32x32 view to
// each pair, and keeps all four under modified and original (each triangle its own object).
// Reliable keeps them either way (its dilation covers any pixel). The trap: groups made from
// something other than the projections (e.g. one group, or one per object: that would test
// every triangle alone and prune it), or a group view fitted to the whole PCS.
TEST(CullideViews, FarApartSubPixelCrossingsKeptOnlyByClustered) {
    const auto [a0, b0] = crossingPair(Vec3f(0, 0, 0));
    const auto [a1, b1] = crossingPair(Vec3f(1000, 300, -200));
    const Scene s = sceneOf({{a0, Transform::Identity()},
                             {b0, Transform::Identity()},
                             {a1, Transform::Identity()},
                             {b1, Transform::Identity()}});
    const std::set<PcsTriangle> crossing = crossingTriangles(s);
    ASSERT_EQ(crossing.size(), 4u) << "the built pairs should cross";
    for (CullMethod m : {CullMethod::Modified, CullMethod::Original}) {
        const CullideResult fit = pruneViews(s, m, ViewMode::Fit, 32);
        EXPECT_TRUE(fit.pcs.empty()) << toString(m) << ": fit kept " << fit.pcs.size()
                                     << " (the case is not sub-pixel)";
        const CullideResult clustered = pruneViews(s, m, ViewMode::Clustered, 32);
        EXPECT_TRUE(contains(clustered, crossing)) << toString(m) << ": clustered kept " << clustered.pcs.size();
        ASSERT_FALSE(clustered.passes.empty());
        EXPECT_EQ(clustered.passes[0].views, 2u) << toString(m);
        EXPECT_EQ(clustered.passes[0].width, 32);
        for (const PassStats& p : fit.passes) EXPECT_EQ(p.views, 1u);
    }
    for (ViewMode v : {ViewMode::Fit, ViewMode::Clustered})
        EXPECT_TRUE(contains(pruneViews(s, CullMethod::Reliable, v, 32), crossing)) << toString(v);
}

// Trap: a group that holds one object's nodes only. Original tests a node against other objects
// only, so it prunes them without drawing them (no view counted); modified tests a node against
// itself, so a lone self-crossing ribbon far from everything must still be drawn and kept.
TEST(CullideViews, LoneGroupsOriginalPrunesModifiedTests) {
    const Scene s = sceneOf({{selfCrossingRibbon(81), rotation(0.31, 0.47, 0.23)},
                             {icosphere(2), rotation(0.2, 0.3, 0.1, Vec3f(50, 50, 50))}});
    const std::set<PcsTriangle> crossing = crossingTriangles(s);
    ASSERT_FALSE(crossing.empty());
    const CullideResult modified = pruneViews(s, CullMethod::Modified, ViewMode::Clustered, 256, 0, 0, 1);
    EXPECT_TRUE(contains(modified, crossing)) << modified.pcs.size();
    const CullideResult original = pruneViews(s, CullMethod::Original, ViewMode::Clustered, 256, 0, 0, 1);
    EXPECT_TRUE(original.pcs.empty()) << original.pcs.size();
    ASSERT_EQ(original.passes.size(), 1u);  // the first call prunes both objects, undrawn
    EXPECT_EQ(original.passes[0].views, 0u);
    EXPECT_EQ(original.passes[0].trianglesRendered, 0u);
    EXPECT_EQ(original.passes[0].width, 256);  // no view: the base viewport is reported
}

// The oracle on the bundled scenes (frames 0, 4, 8 of the animation): clustered misses no more
// colliding triangles than fit, for each method at 128x128 (64 for reliable), and reliable misses
// none (its promise, whatever the views). Not "clustered keeps every one fit keeps": that is no
// theorem for modified and original. In fit, nodes of different groups never share a pixel
// centre, so a group's outcome depends on its own nodes only, but through the pixel grid and
// depth range of the whole PCS's view: clustered samples the group on another, finer grid, and
// a pair kept by fit's grid by luck can fall between clustered's samples (measured: bunny through
// cow frame 4, modified: fit misses 175 colliding triangles, clustered 141, 33 of them kept by
// fit). The trap: groups split where projections overlap (a rectangle on the wrong axes, an open
// comparison at touching bounds), or a group's answers written to the wrong nodes: either loses
// far more than fit does. Under the sanitizers the middle frame only (frames 0, 4 and 8 took 98 s
// of the ThreadSanitizer stage).
TEST(CullideViews, ClusteredMissesNoMoreThanFitOnBundledScenes) {
    for (const char* name : {"bunny_through_cow.json", "two_cows_and_bunny.json"}) {
        const Animation a = loadScene(std::string(CULLIDE_DATA_DIR) + "/scenes/" + name);
        std::vector<size_t> frames;
        for (size_t f = 0; f < a.frameCount(); f += 4) frames.push_back(f);
        if (CULLIDE_SANITIZED) frames = {a.frameCount() / 2};  // bunny through cow: 4 of 9
        for (size_t f : frames) {
            const Scene s = a.sceneAt(f);
            const oracle::Truth truth = oracle::findIntersections(s);
            std::set<PcsTriangle> colliding;
            for (const oracle::IntersectingPair& p : truth.pairs)
                colliding.insert({p.objectA, p.triangleA}), colliding.insert({p.objectB, p.triangleB});
            for (CullMethod m : {CullMethod::Modified, CullMethod::Original, CullMethod::Reliable}) {
                const int res = m == CullMethod::Reliable ? 64 : 128;
                auto missing = [&](ViewMode v) {
                    const CullideResult r = pruneViews(s, m, v, res);
                    const std::set<PcsTriangle> kept(r.pcs.begin(), r.pcs.end());
                    size_t n = 0;
                    for (const PcsTriangle& t : colliding) n += !kept.count(t);
                    return n;
                };
                const size_t fit = missing(ViewMode::Fit), clustered = missing(ViewMode::Clustered);
                EXPECT_LE(clustered, fit) << name << " frame " << f << " " << toString(m);
                if (m == CullMethod::Reliable) {
                    EXPECT_EQ(clustered, 0u) << name << " frame " << f;
                }
            }
        }
    }
}

// Trap: groups (or their order, hence the command lists) that depend on the thread count: the
// rectangles are computed in parallel, the union-find is not. The same PCS and per-call counts
// for 1, 2 and 4 threads, fixed and adaptive resolution, modified and reliable.
TEST(CullideViews, DeterministicAcrossThreads) {
    const Scene s = sceneOf({{icosphere(3), rotation(0.2, 0.3, 0.1)},
                             {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                             {icosphere(2), rotation(0.4, 0.2, 0.6, Vec3f(8, 1, 0))},
                             {selfCrossingRibbon(81), rotation(0.31, 0.47, 0.23, Vec3f(8.5f, 0, 0))}});
    for (CullMethod m : {CullMethod::Modified, CullMethod::Reliable})
        for (double adaptive : {0.0, 4.0}) {
            const CullideResult one = pruneViews(s, m, ViewMode::Clustered, 64, 1, adaptive, 8);
            uint32_t maxViews = 0;
            for (const PassStats& p : one.passes) maxViews = std::max(maxViews, p.views);
            EXPECT_GT(maxViews, 1u) << toString(m) << ": the case should split";
            for (int threads : {2, 4}) {
                const CullideResult r = pruneViews(s, m, ViewMode::Clustered, 64, threads, adaptive, 8);
                EXPECT_EQ(r.pcs, one.pcs) << toString(m) << " " << threads << " threads, auto " << adaptive;
                ASSERT_EQ(r.passes.size(), one.passes.size());
                for (size_t i = 0; i < r.passes.size(); ++i) {
                    EXPECT_EQ(r.passes[i].views, one.passes[i].views) << i;
                    EXPECT_EQ(r.passes[i].width, one.passes[i].width) << i;
                    EXPECT_EQ(r.passes[i].nodesOut, one.passes[i].nodesOut) << i;
                    EXPECT_EQ(r.passes[i].trianglesRendered, one.passes[i].trianglesRendered) << i;
                }
            }
        }
}

// Trap: touching nodes split into two groups (open rectangles, or no allowance for the rounding
// of the projection), which would never test a touching pair against each other. Two triangles
// that share only a vertex, and a third whose vertex lies on the second's edge (a T-junction),
// in a generic direction and in an axis direction where the touching point is the extreme of
// both rectangles: one group. Moved 1e-3 apart, the first pair is two groups (the test can fail
// both ways), and the groups come in order of their first item.
TEST(CullideViews, TouchingNodesShareAGroup) {
    Mesh m;
    // Triangle 0 ends at x = 1 (its vertex (1, 0.5, 0.25)); triangle 1 starts there. Triangle 2
    // has its vertex at the midpoint of triangle 1's edge (2, 0)-(2, 1): exact in float.
    m.positions = {{0, 0, 0},    {0, 1, 0.5f},    {1, 0.5f, 0.25f}, {2, 0, 0.1f},
                   {2, 1, 0.3f}, {2, 0.5f, 0.2f}, {3, 0.2f, 0},     {3, 0.9f, 0.4f}};
    m.triangles = {{0, 1, 2}, {2, 3, 4}, {5, 6, 7}};
    const std::vector<TriangleRange> ranges = {{0, 1}, {1, 1}, {2, 1}};
    for (const Vec3d& dir : {Vec3d(0, 0, 1), Vec3d(0, 0, -1), Vec3d(0.3, -0.2, 0.9).normalized()}) {
        const auto groups = viewGroups(m.positions, m.triangles, ranges, dir);
        ASSERT_EQ(groups.size(), 1u) << dir.transpose();
        EXPECT_EQ(groups[0], (std::vector<uint32_t>{0, 1, 2}));
    }
    Mesh apart = m;
    apart.positions.push_back(Vec3f(1.001f, 0.5f, 0.25f));  // triangle 1 moved off triangle 0's corner
    apart.triangles[1] = {8, 3, 4};
    const auto groups = viewGroups(apart.positions, apart.triangles, ranges, Vec3d(0, 0, 1));
    ASSERT_EQ(groups.size(), 2u);
    EXPECT_EQ(groups[0], (std::vector<uint32_t>{0}));
    EXPECT_EQ(groups[1], (std::vector<uint32_t>{1, 2}));
    EXPECT_EQ(toString(parseViewMode("clustered")), std::string("clustered"));
    EXPECT_THROW(parseViewMode("clusters"), InputError);
}

// Bad option values are refused with a message naming the option, before any work.
// Trap: a view fitted to every vertex of the geometry rather than to the triangles drawn (the
// first levels, which draw everything, fit their view from the vertices once each): a vertex no
// triangle uses, far away, would stretch the view and make every triangle sub-pixel. The same
// meshes with such a vertex give the same PCS and calls as without it.
TEST(Cullide, UnusedVerticesDoNotWidenTheView) {
    const Scene clean = sceneOf(
        {{icosphere(2), rotation(0.2, 0.3, 0.1)}, {icosphere(2), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))}});
    Mesh far = icosphere(2);
    far.positions.push_back(Vec3f(1000, -800, 600));  // used by no triangle
    const Scene withFar =
        sceneOf({{far, rotation(0.2, 0.3, 0.1)}, {icosphere(2), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))}});
    const CullideResult want = prune(clean, CullMethod::Modified, 8), got = prune(withFar, CullMethod::Modified, 8);
    EXPECT_FALSE(want.pcs.empty());
    EXPECT_EQ(got.pcs, want.pcs);
    ASSERT_EQ(got.passes.size(), want.passes.size());
    for (size_t i = 0; i < got.passes.size(); ++i) EXPECT_EQ(got.passes[i].nodesOut, want.passes[i].nodesOut) << i;
}

// --- Tiles: a call whose viewport exceeds the backend's largest side ---

// Trap: a backend whose largest viewport is smaller than a call's (a GPU's limits under
// `--resolution auto`, or a fixed size) must not change the PCS: clamping the viewport (coarser
// pixels), tiles that sample another grid, results of the tiles not added (or ANY_SAMPLES_PASSED
// added instead of or-ed), or a list that depends on the state the previous tile left would all
// change it. Every method, fixed and adaptive resolution, fit and clustered views: the PCS and
// every call's statistics equal the whole-view run's, and the calls really were tiled.
TEST(CullideTiles, TiledCallsKeepTheWholeViewsPcs) {
    {  // The limit itself: an absurd side is refused, and so is a view beyond it.
        auto cpu = raster::makeCpuBackend();
        EXPECT_THROW(raster::ViewportLimit(*cpu, 0), InputError);
        EXPECT_THROW(raster::ViewportLimit(*cpu, kMaxViewportSide + 1), InputError);
        raster::ViewportLimit limit(*cpu, 64);
        OrthoView v;
        v.width = 65, v.height = 10;
        EXPECT_THROW(limit.setView(v), InputError);
    }
    const Scene s = sceneOf({{icosphere(2), rotation(0.2, 0.3, 0.1)},
                             {icosphere(2), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                             {selfCrossingRibbon(41), rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
    for (CullMethod method : {CullMethod::Original, CullMethod::Modified, CullMethod::Reliable})
        for (double autoCoverage : {0.0, 4.0})
            for (ViewMode views : {ViewMode::Fit, ViewMode::Clustered}) {
                CullideOptions o;
                o.method = method;
                o.views = views;
                o.width = o.height = autoCoverage > 0 ? 48 : 150;
                o.autoCoverage = autoCoverage;
                o.hierarchy.leafSize = 8;
                auto cpu = raster::makeCpuBackend();
                const CullideResult want = runCullide(s, *cpu, o);
                raster::ViewportLimit small(*cpu, 64);  // refuses larger views: Cullide must tile
                const CullideResult got = runCullide(s, small, o);
                const std::string what =
                    std::string(toString(method)) + (autoCoverage > 0 ? " auto " : " 150 ") + toString(views);
                EXPECT_EQ(got.pcs, want.pcs) << what;
                EXPECT_GT(small.tilesSet(), 0u) << what << ": nothing was tiled";
                ASSERT_EQ(got.passes.size(), want.passes.size()) << what;
                size_t tiledCalls = 0;
                for (size_t i = 0; i < got.passes.size(); ++i) {
                    EXPECT_EQ(got.passes[i].nodesOut, want.passes[i].nodesOut) << what << " call " << i;
                    EXPECT_EQ(got.passes[i].width, want.passes[i].width) << what << " call " << i;
                    EXPECT_EQ(got.passes[i].views, want.passes[i].views) << what << " call " << i;
                    EXPECT_EQ(want.passes[i].tiles, want.passes[i].views) << what << " call " << i;
                    tiledCalls += got.passes[i].tiles > got.passes[i].views;
                }
                EXPECT_GT(tiledCalls, 0u) << what << ": no call counts its tiles";
            }
}

// Which false prunes break a method's promise (`prune --check` exits 1 on them): reliable keeps every
// intersecting pair, modified the crossing ones, original those between two objects.
TEST(Cullide, PromisesToKeepFollowTheMethods) {
    for (bool crossing : {false, true})
        for (bool sameObject : {false, true}) {
            EXPECT_TRUE(promisesToKeep(CullMethod::Reliable, crossing, sameObject));
            EXPECT_EQ(promisesToKeep(CullMethod::Modified, crossing, sameObject), crossing);
            EXPECT_EQ(promisesToKeep(CullMethod::Original, crossing, sameObject), !sameObject);
        }
}

TEST(Cullide, BadOptionsRefused) {
    EXPECT_THROW(parseCullMethod("reliable-ish"), InputError);
    EXPECT_THROW(parseDirections(""), InputError);
    EXPECT_THROW(parseDirections("0"), InputError);
    EXPECT_THROW(parseDirections("x,q"), InputError);
    EXPECT_THROW(parseDirections("0 0 0"), InputError);
    EXPECT_THROW(parseDirections("1 nan 0"), InputError);
    EXPECT_EQ(parseDirections("x,-y,+z").size(), 3u);
    EXPECT_EQ(parseDirections("1 0 0;0 1 1").size(), 2u);
    EXPECT_EQ(parseDirections("14").size(), 14u);
    EXPECT_EQ(parseDirections("axes").size(), 6u);
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Transform::Identity()}});
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.width = 0;
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.directions.clear();
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.hierarchy.branching = 1;
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.autoCoverage = -1;  // adaptive K must be positive
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.autoCoverage = 4;
    o.autoBudget = 499 * 500;  // a budget below the base viewport could go coarser than the base
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
}

// ---- Chosen directions (docs/cullide.md#chosen-directions) ----------------------------------

namespace {

// The triangles of `s` as one geometry and one range over all of them (pcaFrame's input).
struct Flat {
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    std::vector<TriangleRange> all() const { return {{0, uint32_t(triangles.size())}}; }
};
Flat flatOf(const Scene& s) {
    Flat f;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const Mesh m = s.worldMesh(i);
        const uint32_t base = uint32_t(f.positions.size());
        f.positions.insert(f.positions.end(), m.positions.begin(), m.positions.end());
        for (const Triangle& t : m.triangles) f.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    return f;
}

// |a . b| for unit vectors: 1 when they are the same line.
double sameLine(const Vec3d& a, const Vec3d& b) {
    return std::abs(a.normalized().dot(b.normalized()));
}

// Two boxes apart along x and a bar along x through both: every object crosses another.
Scene piercedBoxes() {
    return sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.05, 0.1, 0.02)},
                    {box(Vec3f(2, 0, 0), Vec3f(3, 1, 1)), rotation(0.03, -0.08, 0.04)},
                    {box(Vec3f(-0.5f, 0.4f, 0.45f), Vec3f(3.5f, 0.6f, 0.55f)), Transform::Identity()}});
}

CullideOptions coherentOptions(std::shared_ptr<DirectionHistory> history) {
    CullideOptions o;
    o.directionMode = DirectionMode::Coherent;
    o.directionHistory = std::move(history);
    o.hierarchy.leafSize = 1;
    o.width = o.height = 128;
    return o;
}

}  // namespace

// Trap: principal axes taken from the vertices (a box's vertex cloud is spread along its long
// side) or in Eigen's increasing order, or an eigenvector with an arbitrary sign. A 4 x 2 x 1 box
// turned by a known rotation: its face areas make the orientation tensor's axes the box's short
// side (faces of area 8), middle (4) and long side (2), in that order, each with its largest
// component positive.
TEST(CullideDirections, PcaFrameIsTheBoxsPrincipalAxes) {
    const Transform t = rotation(0.4, -0.7, 1.1, Vec3f(0.3f, -0.2f, 0.5f));
    const Scene s = sceneOf({{box(Vec3f(-2, -1, -0.5f), Vec3f(2, 1, 0.5f)), t}});
    const Flat f = flatOf(s);
    const std::vector<Vec3d> frame = pcaFrame(f.positions, f.triangles, f.all());
    ASSERT_EQ(frame.size(), 3u);
    const Eigen::Matrix3d r = t.linear().cast<double>();
    const Vec3d expected[3] = {r.col(2), r.col(1), r.col(0)};  // short, middle, long side
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(sameLine(frame[size_t(k)], expected[k]), 1.0, 1e-6) << k;
        EXPECT_NEAR(frame[size_t(k)].norm(), 1.0, 1e-12);
        int big = 0;
        for (int i = 1; i < 3; ++i)
            if (std::abs(frame[size_t(k)][i]) > std::abs(frame[size_t(k)][big])) big = i;
        EXPECT_GT(frame[size_t(k)][big], 0) << "sign fixed: largest component positive";
    }
    // The six directions: an orthonormal frame, both signs of each axis.
    const std::vector<Vec3d> dirs = pcaDirections(f.positions, f.triangles, f.all());
    ASSERT_EQ(dirs.size(), 6u);
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(dirs[size_t(2 * k + 1)], Vec3d(-dirs[size_t(2 * k)]));
        for (int j = 0; j < k; ++j) EXPECT_NEAR(dirs[size_t(2 * k)].dot(dirs[size_t(2 * j)]), 0.0, 1e-9);
    }
    // No area: the axes.
    const std::vector<Vec3f> flatPoints{Vec3f(0, 0, 0), Vec3f(1, 1, 1), Vec3f(2, 2, 2)};
    const std::vector<Triangle> degenerate{{0, 1, 2}};
    const std::vector<TriangleRange> one{{0, 1}};
    EXPECT_TRUE(pcaFrame(flatPoints, degenerate, one).empty());
    EXPECT_EQ(pcaDirections(flatPoints, degenerate, one), axisDirections());
}

// Trap: taking the principal axes themselves as views. For axis-aligned boxes (the frame is the
// axes) that is exactly the axis set, which sees every face edge-on from four directions and
// loses every crossing (Cullide.AxisAlignedBoxesLoseCrossingEdgeOn). pca turns the frame so
// that every face is seen at a slant from every view, and keeps them all.
TEST(CullideDirections, PcaKeepsTheCrossingsAxesLoseEdgeOn) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(2, 2, 2)), Transform::Identity()},
                             {box(Vec3f(1.1f, 1.3f, 0.7f), Vec3f(3, 3, 3)), Transform::Identity()}});
    const std::set<PcsTriangle> truth = crossingTriangles(s);
    ASSERT_GE(truth.size(), 4u);
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.hierarchy.leafSize = 1;
    EXPECT_TRUE(runCullide(s, *backend, o).pcs.empty()) << "axes lose them";
    o.directionMode = DirectionMode::Pca;
    const CullideResult r = runCullide(s, *backend, o);
    EXPECT_TRUE(contains(r, truth)) << "PCS " << r.pcs.size() << ", crossing " << truth.size();
    for (const PassStats& p : r.passes) {
        EXPECT_LT(p.direction, 6u);
        EXPECT_NEAR(p.dirVector.norm(), 1.0, 1e-12);
        double worst = 1;  // how near edge-on the boxes' faces are seen, over the axes
        for (int a = 0; a < 3; ++a) worst = std::min(worst, std::abs(p.dirVector[a]));
        EXPECT_GT(worst, 0.2) << "a view nearly in a face's plane";
    }
}

// Trap: the same loss on tilted flat geometry: two 4 x 4-cell sheets tilted +-3 degrees about x
// from the xy plane, crossing along the x axis. Both contain x, so from +-x both are segments:
// no fragments, "fully visible", pruned, whatever the resolution. Their normals are near z, and
// pca's views all face them at a slant.
TEST(CullideDirections, PcaKeepsTiltedSheetsAxesLoseEdgeOn) {
    auto sheet = [](double degrees) {
        const double a = degrees * std::numbers::pi / 180;
        Mesh m;
        for (int j = 0; j <= 4; ++j)
            for (int k = 0; k <= 4; ++k) {
                const double x = k / 4.0 - 0.5, t = j / 4.0 - 0.5;
                m.positions.push_back(Vec3f(float(x), float(t * std::cos(a)), float(t * std::sin(a))));
            }
        for (uint32_t j = 0; j < 4; ++j)
            for (uint32_t k = 0; k < 4; ++k) {
                const uint32_t c = j * 5 + k;
                m.triangles.push_back({c, c + 1, c + 6});
                m.triangles.push_back({c, c + 6, c + 5});
            }
        return m;
    };
    // B moved by (0.03, 0.02, 0.01): the crossing line (still along x) between A's grid rows and
    // B's edges off A's, so that the pairs cross generically.
    const Scene s =
        sceneOf({{sheet(3), Transform::Identity()}, {sheet(-3), rotation(0, 0, 0, Vec3f(0.03f, 0.02f, 0.01f))}});
    const std::set<PcsTriangle> truth = crossingTriangles(s);
    ASSERT_GE(truth.size(), 4u) << "the sheets must cross";
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.hierarchy.leafSize = 1;
    const CullideResult axes = runCullide(s, *backend, o);
    EXPECT_FALSE(contains(axes, truth)) << "axes keep every crossing: the trap is gone";
    o.directionMode = DirectionMode::Pca;
    const CullideResult pca = runCullide(s, *backend, o);
    EXPECT_TRUE(contains(pca, truth)) << "PCS " << pca.pcs.size() << ", crossing " << truth.size();
}

// Trap: pca's sums gathered in the order threads finish would turn the frame per thread count.
// The same PCS and the same directions, bit for bit, with 1 and with every thread.
TEST(CullideDirections, PcaDeterministicAcrossThreads) {
    SceneRequest q;
    q.triangles = 20000;
    const Scene s = makeSheets(6, 3.0, q).scene;
    auto run = [&](int threads) {
        raster::CpuBackendOptions bo;
        bo.threads = threads;
        auto backend = raster::makeCpuBackend(bo);
        CullideOptions o;
        o.directionMode = DirectionMode::Pca;
        CullideResult r;
        tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
        arena.execute([&] { r = runCullide(s, *backend, o); });
        return r;
    };
    const CullideResult one = run(1), all = run(0);
    EXPECT_EQ(one.pcs, all.pcs);
    ASSERT_EQ(one.passes.size(), all.passes.size());
    for (size_t i = 0; i < one.passes.size(); ++i) EXPECT_EQ(one.passes[i].dirVector, all.passes[i].dirVector) << i;
}

// Trap: a history that starts empty and prunes with no directions (or an arbitrary subset).
// The first frame, and a run without a history, use the whole list in the given order.
TEST(CullideDirections, CoherentFirstFrameIsTheFullList) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.2, 0.3, 0.1)},
                             {box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.5, 0.1, 0.3, Vec3f(0.6f, 0.2f, 0))}});
    auto backend = raster::makeCpuBackend();
    for (bool withHistory : {false, true}) {
        auto history = withHistory ? std::make_shared<DirectionHistory>() : nullptr;
        const CullideResult r = runCullide(s, *backend, coherentOptions(history));
        std::vector<uint32_t> level0;
        for (const PassStats& p : r.passes)
            if (p.level == 0) level0.push_back(p.direction);
        EXPECT_EQ(level0, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
        CullideOptions fixed = coherentOptions(nullptr);
        fixed.directionMode = DirectionMode::Fixed;
        EXPECT_EQ(r.pcs, runCullide(s, *backend, fixed).pcs);
        if (history) {
            EXPECT_EQ(history->frames, 1u);
        }
    }
}

// Trap: a direction that pruned nothing kept next frame (no saving), or one that pruned dropped.
// Two boxes pierced by a bar: at the object level nothing can be pruned from any direction (the
// bar crosses both), so the next frame makes no object-level call; at every level below, the
// next frame makes exactly the calls that pruned something, in the given order; the PCS stays.
TEST(CullideDirections, CoherentDropsADirectionThatPrunedNothing) {
    const Scene s = piercedBoxes();
    auto backend = raster::makeCpuBackend();
    auto history = std::make_shared<DirectionHistory>();
    const CullideResult first = runCullide(s, *backend, coherentOptions(history));
    std::map<uint32_t, std::vector<uint32_t>> pruning;  // level -> directions that pruned
    for (const PassStats& p : first.passes) {
        if (p.level == 0) {
            EXPECT_EQ(p.trianglesOut, p.trianglesIn) << "the object level prunes nothing";
        }
        if (p.trianglesOut < p.trianglesIn) pruning[p.level].push_back(p.direction);
    }
    ASSERT_FALSE(pruning.empty());
    ASSERT_EQ(history->pruned.size(), first.levels);
    const CullideResult second = runCullide(s, *backend, coherentOptions(history));
    std::map<uint32_t, std::vector<uint32_t>> made;
    for (const PassStats& p : second.passes) made[p.level].push_back(p.direction);
    EXPECT_EQ(made.count(0), 0u) << "no object-level call";
    for (const auto& [level, dirs] : made) EXPECT_EQ(dirs, pruning[level]) << "level " << level;
    EXPECT_LT(second.passes.size(), first.passes.size());
    EXPECT_EQ(second.pcs, first.pcs);
}

// Trap: a direction once dropped never coming back. Every period-th frame (here 3) is a full
// check: frames 0 and 3 make the six object-level calls, frames 1, 2 and 4 none.
TEST(CullideDirections, CoherentFullCheckEveryPeriodFrames) {
    const Scene s = piercedBoxes();
    auto backend = raster::makeCpuBackend();
    auto history = std::make_shared<DirectionHistory>();
    history->period = 3;
    std::vector<size_t> calls;
    for (int f = 0; f < 5; ++f) {
        const CullideResult r = runCullide(s, *backend, coherentOptions(history));
        calls.push_back(
            size_t(std::count_if(r.passes.begin(), r.passes.end(), [](const PassStats& p) { return p.level == 0; })));
    }
    EXPECT_EQ(calls, (std::vector<size_t>{6, 0, 0, 6, 0}));
    // The plan itself: a level the last run did not reach, or another list length, is a full check.
    DirectionHistory h;
    h.frames = 1, h.count = 3, h.pruned = {{0, 5, 2}};
    EXPECT_EQ(h.plan(0, 3), (std::vector<uint32_t>{1, 2})) << "the given order, not most first";
    EXPECT_EQ(h.plan(1, 3), (std::vector<uint32_t>{0, 1, 2}));
    EXPECT_EQ(h.plan(0, 4), (std::vector<uint32_t>{0, 1, 2, 3}));
    h.pruned = {{0, 0, 0}};
    EXPECT_TRUE(h.plan(0, 3).empty()) << "nothing pruned at that level: no call";
}

// Trap: coherent that only reorders or drops calls but, where last frame's prediction holds,
// changes the PCS: dropping calls that would prune nothing must leave the PCS of the full list.
// Over a cylinders animation, with 1 and with every thread: the same PCS as axes on each frame
// where it made fewer calls and no call it skipped would have pruned (checked by the full run).
TEST(CullideDirections, CoherentSkipsOnlyCallsAndKeepsTheirPcs) {
    SceneRequest q;
    q.triangles = 3000;
    q.frames = 6;
    const Animation a = makeCylinders(12, q);
    auto backend = raster::makeCpuBackend();
    auto history = std::make_shared<DirectionHistory>();
    size_t coherentCalls = 0, fixedCalls = 0;
    for (size_t f = 0; f < a.frameCount(); ++f) {
        const Scene s = a.sceneAt(f);
        CullideOptions o = coherentOptions(history);
        o.hierarchy.leafSize = 16;
        const CullideResult c = runCullide(s, *backend, o);
        o.directionMode = DirectionMode::Fixed;
        const CullideResult full = runCullide(s, *backend, o);
        coherentCalls += c.passes.size(), fixedCalls += full.passes.size();
        // The skipped calls of the full run pruned nothing here: then the PCS must be the same.
        std::set<std::pair<uint32_t, uint32_t>> made;
        for (const PassStats& p : c.passes) made.insert({p.level, p.direction});
        bool predicted = true;
        for (const PassStats& p : full.passes)
            if (!made.count({p.level, p.direction}) && p.trianglesOut != p.trianglesIn) predicted = false;
        if (predicted) {
            EXPECT_EQ(c.pcs, full.pcs) << "frame " << f;
        }
    }
    EXPECT_LT(coherentCalls, fixedCalls);
}

namespace {

// Three overlapping objects with a deep hierarchy (leaf 8, branching 2): many levels to stop in.
Scene switchScene() {
    return sceneOf({{icosphere(3), rotation(0.2, 0.3, 0.1)},
                    {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                    {selfCrossingRibbon(81), rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
}

CullideResult pruneWithSwitch(const Scene& scene, CullMethod method, const ExactSwitch& sw, int threads = 0) {
    raster::CpuBackendOptions bo;
    bo.threads = threads;
    auto backend = raster::makeCpuBackend(bo);
    CullideOptions o;
    o.method = method;
    o.width = o.height = 256;
    o.hierarchy.leafSize = 8;
    o.hierarchy.branching = 2;
    o.exactSwitch = sw;
    return runCullide(scene, *backend, o);
}

bool isSuperset(const std::vector<PcsTriangle>& big, const std::vector<PcsTriangle>& small) {
    return std::includes(big.begin(), big.end(), small.begin(), small.end());
}

}  // namespace

// Trap: a switch that is not checked before every call (only per level), that counts nodes
// instead of triangles, or that drops nodes when it stops (instead of keeping the PCS as it
// stands) would stop late or lose triangles. Switch N: the loop stops at the first call whose PCS
// holds fewer than N triangles (every call before it had at least N), and its PCS is a superset of
// the whole loop's (it only stops pruning early).
TEST(CullideExactSwitch, BelowNStopsBeforeTheFirstSmallPcsAndKeepsASuperset) {
    const Scene s = switchScene();
    for (CullMethod method : {CullMethod::Original, CullMethod::Modified, CullMethod::Reliable}) {
        const CullideResult never = pruneWithSwitch(s, method, {});
        EXPECT_EQ(never.switchedAtLevel, -1);
        ASSERT_GT(never.passes.size(), 2u) << toString(method);
        // N between the PCS before the second call and the PCS the loop ends with: it must stop.
        const size_t n = never.passes[1].trianglesIn;
        ExactSwitch sw;
        sw.kind = ExactSwitchKind::Below;
        sw.triangles = n;
        const CullideResult r = pruneWithSwitch(s, method, sw);
        ASSERT_GE(r.switchedAtLevel, 0) << toString(method);
        EXPECT_LT(r.switchedAtTriangles, n);
        EXPECT_EQ(r.pcs.size(), r.switchedAtTriangles);
        for (const PassStats& p : r.passes) EXPECT_GE(p.trianglesIn, n) << toString(method);
        EXPECT_LT(r.passes.size(), never.passes.size());
        EXPECT_TRUE(isSuperset(r.pcs, never.pcs)) << toString(method);
        EXPECT_GT(r.pcs.size(), never.pcs.size()) << toString(method);
        // N = 1: nothing is ever below it but an empty PCS, so the same run as never.
        sw.triangles = 1;
        EXPECT_EQ(pruneWithSwitch(s, method, sw).pcs, never.pcs) << toString(method);
    }
}

// Trap: auto's decision inverted, or taken before level 0 has measured anything (no calls to
// scale). A cost model that says the exact stage is always cheaper stops at the start of level 1
// (after level 0's calls, all directions); one that says it never is cheaper runs the whole loop,
// the same PCS and calls as never.
TEST(CullideExactSwitch, AutoFollowsTheCostModel) {
    const Scene s = switchScene();
    const CullideResult never = pruneWithSwitch(s, CullMethod::Modified, {});
    ExactSwitch sw;
    sw.kind = ExactSwitchKind::Auto;
    sw.exactCost = [](size_t) { return 0.0; };  // free: any level costs more
    const CullideResult cheap = pruneWithSwitch(s, CullMethod::Modified, sw);
    EXPECT_EQ(cheap.switchedAtLevel, 1);
    EXPECT_EQ(cheap.levels, 1u);
    for (const PassStats& p : cheap.passes) EXPECT_EQ(p.level, 0u);
    EXPECT_EQ(cheap.passes.size(), 6u);
    EXPECT_TRUE(isSuperset(cheap.pcs, never.pcs));
    sw.exactCost = [](size_t) { return std::numeric_limits<double>::infinity(); };
    const CullideResult dear = pruneWithSwitch(s, CullMethod::Modified, sw);
    EXPECT_EQ(dear.switchedAtLevel, -1);
    EXPECT_EQ(dear.pcs, never.pcs);
    EXPECT_EQ(dear.passes.size(), never.passes.size());
    // The default model (no exactCost) gives a sound PCS whatever the timings decide.
    sw.exactCost = nullptr;
    EXPECT_TRUE(isSuperset(pruneWithSwitch(s, CullMethod::Modified, sw).pcs, never.pcs));
}

// Trap: a switch whose threshold is compared against a count gathered per thread would stop at
// a different call per thread count. Switch N: the same PCS and calls for 1, 2 and 4 threads.
TEST(CullideExactSwitch, BelowNDeterministicAcrossThreads) {
    const Scene s = switchScene();
    const CullideResult never = pruneWithSwitch(s, CullMethod::Modified, {}, 1);
    ExactSwitch sw;
    sw.kind = ExactSwitchKind::Below;
    sw.triangles = never.passes[never.passes.size() / 2].trianglesIn;  // stops midway
    const CullideResult one = pruneWithSwitch(s, CullMethod::Modified, sw, 1);
    ASSERT_GE(one.switchedAtLevel, 0);
    for (int threads : {2, 4}) {
        const CullideResult r = pruneWithSwitch(s, CullMethod::Modified, sw, threads);
        EXPECT_EQ(r.pcs, one.pcs) << threads;
        EXPECT_EQ(r.passes.size(), one.passes.size()) << threads;
        EXPECT_EQ(r.switchedAtLevel, one.switchedAtLevel) << threads;
    }
}

// Trap: a switch below 1 triangle (never true, so a silent no-op) accepted by validate().
TEST(CullideExactSwitch, ZeroTrianglesRefused) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Transform::Identity()}});
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.exactSwitch.kind = ExactSwitchKind::Below;
    o.exactSwitch.triangles = 0;
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
}
