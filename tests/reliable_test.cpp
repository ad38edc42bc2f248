// The reliable method (CullMethod::Reliable, docs/reliable.md): its one-way contract "pruned
// implies the exact oracle sees no intersection", at every resolution, depth format and view
// tested, for contacts, self-intersections, edge-on and coplanar configurations; its pieces
// (unit adjacency, distance-2 colouring, the exact pair rules); determinism; and that it still
// prunes what is clearly apart. Fixed seeds throughout.
#include "cullide/cullide.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene_io.h"
#include "cullide/study/measures.h"

#include "../core/src/reliable.h"

#include "test_util.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>

using namespace cullide;
using cullide::test::box;
using cullide::test::sceneOf;

namespace {

// A UV sphere (closed, no self-intersection).
Mesh sphere(int rings, int sectors, float r = 1) {
    Mesh m;
    m.positions.push_back(Vec3f(0, 0, r));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < sectors; ++j) {
            const double th = M_PI * i / rings, ph = 2 * M_PI * j / sectors;
            m.positions.push_back(Vec3f(float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)),
                                        float(r * std::cos(th))));
        }
    m.positions.push_back(Vec3f(0, 0, -r));
    const uint32_t south = uint32_t(m.positions.size() - 1);
    auto at = [&](int i, int j) { return uint32_t(1 + (i - 1) * sectors + (j % sectors)); };
    for (int j = 0; j < sectors; ++j) m.triangles.push_back({0, at(1, j), at(1, j + 1)});
    for (int i = 1; i + 1 < rings; ++i)
        for (int j = 0; j < sectors; ++j) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    for (int j = 0; j < sectors; ++j) m.triangles.push_back({south, at(rings - 1, j + 1), at(rings - 1, j)});
    return m;
}

// A ribbon along a planar curve that crosses itself (x = s^2 - 1, y = s^3 - s crosses at s = +-1),
// extruded along z.
Mesh selfCrossingRibbon(int segments) {
    Mesh m;
    for (int i = 0; i <= segments; ++i) {
        const float s = -1.5f + 3.0f * float(i) / float(segments);
        m.positions.push_back(Vec3f(s * s - 1, s * s * s - s, -0.4f));
        m.positions.push_back(Vec3f(s * s - 1, s * s * s - s, 0.4f));
    }
    for (uint32_t i = 0; i < uint32_t(segments); ++i) {
        m.triangles.push_back({2 * i, 2 * i + 2, 2 * i + 3});
        m.triangles.push_back({2 * i, 2 * i + 3, 2 * i + 1});
    }
    return m;
}

struct Outcome {
    CullideResult result;
    study::PcsReport report;
};

Outcome reliable(const Scene& scene, int resolution, DepthFormat depth, uint32_t leafSize = 16,
                 std::vector<Vec3d> directions = axisDirections(), int threads = 0, double autoCoverage = 0) {
    raster::CpuBackendOptions bo;
    bo.threads = threads;
    auto backend = raster::makeCpuBackend(bo);
    CullideOptions o;
    o.method = CullMethod::Reliable;
    o.width = o.height = resolution;
    o.depth = depth;
    o.hierarchy.leafSize = leafSize;
    o.directions = std::move(directions);
    o.autoCoverage = autoCoverage;
    Outcome r;
    r.result = runCullide(scene, *backend, o);
    r.report = study::measurePcs(scene, oracle::findIntersections(scene), r.result.pcs, o);
    return r;
}

std::string describe(const study::PcsReport& r) {
    return "false prunes " + std::to_string(r.falsePruneCount()) + " (crossing " + std::to_string(r.falsePrunes[0]) +
        ", touching " + std::to_string(r.falsePrunes[1]) + "), PCS " + std::to_string(r.pcsTriangles) + ", colliding " +
        std::to_string(r.collidingTriangles);
}

const std::vector<DepthFormat>& allFormats() {
    static const std::vector<DepthFormat> f{DepthFormat::unorm(8), DepthFormat::unorm(16), DepthFormat::unorm(24),
                                            DepthFormat::unorm(32), DepthFormat::float32()};
    return f;
}

// ---------------------------------------------------------------------------------------------
// The pieces

// Trap: units that share only a vertex (not an edge) are adjacent too; units of different
// objects never are (their indices are disjoint in the uploaded geometry).
TEST(ReliablePieces, UnitAdjacencyBySharedVertexIndex) {
    const std::vector<Triangle> tris{{0, 1, 2}, {2, 3, 4}, {5, 6, 7}, {4, 8, 9}};
    const std::vector<TriangleRange> units{{0, 1}, {1, 1}, {2, 1}, {3, 1}};
    const detail::UnitGraph g = detail::unitAdjacency(tris, units);
    EXPECT_EQ(std::vector<uint32_t>(g.neighbours(0).begin(), g.neighbours(0).end()), (std::vector<uint32_t>{1}));
    EXPECT_EQ(std::vector<uint32_t>(g.neighbours(1).begin(), g.neighbours(1).end()), (std::vector<uint32_t>{0, 3}));
    EXPECT_TRUE(g.neighbours(2).empty());
}

// Trap: a proper colouring is not enough: a unit with two neighbours of one class could not be
// tested against that class (both would have to be left out). Distance 2 gives one at most.
TEST(ReliablePieces, DistanceTwoColouringGivesAtMostOneNeighbourPerClass) {
    const Mesh m = sphere(12, 16);
    auto h = buildHierarchy(m, {HierarchyKind::Connectivity, 4, 4, 1});
    std::vector<Triangle> tris;
    for (uint32_t t : h.order) tris.push_back(m.triangles[t]);
    std::vector<TriangleRange> units;
    for (const HierarchyNode& n : h.nodes)
        if (n.isLeaf()) units.push_back({n.first, n.count});
    const detail::UnitGraph g = detail::unitAdjacency(tris, units);
    const std::vector<uint32_t> c = detail::distanceTwoColouring(g);
    for (uint32_t u = 0; u < units.size(); ++u) {
        std::map<uint32_t, int> perClass;
        for (uint32_t v : g.neighbours(u)) {
            EXPECT_NE(c[u], c[v]);
            EXPECT_EQ(++perClass[c[v]], 1) << "unit " << u;
        }
    }
}

// Random fans, one mesh, fans on a grid 3 apart: around each centre 4 to 8 rim triangles, each
// sharing an edge with the next and the centre with all, their rim vertices in random directions
// (so in random order around the centre): in 3D (folds, faces through a neighbour's opposite
// edge) or, every other fan, all exactly on the centre's plane (coplanar fold-overs, wedges that
// overlap at the centre). Now and then a duplicated face and a degenerate one (two corners at one
// point); two free triangles through each fan share no vertex with it.
Mesh randomFans(uint32_t seed, int fans) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::uniform_int_distribution<int> pick(0, 9);
    Mesh m;
    for (int fan = 0; fan < fans; ++fan) {
        const uint32_t centre = uint32_t(m.positions.size());
        const Vec3f c(float(fan % 6) * 3, float(fan / 6) * 3, 0.5f);
        const bool planar = fan % 2 == 1;
        m.positions.push_back(c);
        const uint32_t k = 5 + uint32_t(fan % 5);  // rim vertices
        for (uint32_t i = 0; i < k; ++i) m.positions.push_back(c + Vec3f(u(rng), u(rng), planar ? 0.0f : u(rng)));
        for (uint32_t i = 1; i < k; ++i) m.triangles.push_back({centre, centre + i, centre + i + 1});
        if (pick(rng) < 3) {
            const Triangle twin = m.triangles[m.triangles.size() - 1 - uint32_t(pick(rng)) % (k - 1)];
            m.triangles.push_back(twin);  // a duplicated rim face
        }
        if (pick(rng) < 3) {
            m.positions.push_back(m.positions[centre + 1]);  // coincides with the first rim vertex
            m.triangles.push_back({centre, centre + 1, uint32_t(m.positions.size() - 1)});
        }
        for (int extra = 0; extra < 2; ++extra) {
            const uint32_t a = uint32_t(m.positions.size());
            for (int corner = 0; corner < 3; ++corner)
                m.positions.push_back(c + Vec3f(u(rng), u(rng), planar && pick(rng) < 5 ? 0.0f : 0.3f * u(rng)));
            m.triangles.push_back({a, a + 1, a + 2});
        }
    }
    return m;
}

// The one-way promise of the exact pair rule: on every pair of the mesh, never "no"
// (mayIntersect false) where the oracle (its whole pipeline, fast paths included) reports a pair.
// Returns, by the number of shared vertices (0..3), how many pairs the oracle reports and how many
// the rule answers "no" (so that both answers are exercised).
struct RuleCounts {
    std::array<size_t, 4> contacts{}, no{};
};
RuleCounts expectNeverNoWhereTheOracleSeesContact(const Mesh& m, const char* what) {
    Scene scene;
    scene.objects.push_back({"fans", m, Transform::Identity()});
    std::set<std::pair<uint32_t, uint32_t>> contacts;
    for (const oracle::IntersectingPair& p : oracle::findIntersections(scene).pairs)
        contacts.insert({p.triangleA, p.triangleB});
    RuleCounts counts;
    const uint32_t n = uint32_t(m.triangles.size());
    for (uint32_t a = 0; a < n; ++a)
        for (uint32_t b = a + 1; b < n; ++b) {
            const Triangle &ta = m.triangles[a], &tb = m.triangles[b];
            int shared = 0;
            for (uint32_t v : ta) shared += int(std::count(tb.begin(), tb.end(), v) > 0);
            const bool contact = contacts.count({a, b}) > 0;
            const bool may = detail::mayIntersect(m.positions, ta, tb);
            EXPECT_FALSE(contact && !may) << what << ": triangles " << a << ", " << b << " (" << shared << " shared)";
            counts.contacts[shared] += contact;
            counts.no[shared] += !may;
        }
    return counts;
}

// Trap: the rules for faces sharing vertices, on random fans. Neighbours sharing an edge meet only
// in a coplanar fold-over; sharing the centre, when one passes through the other's opposite edge
// or (coplanar) their wedges overlap; a duplicated face meets itself; a degenerate face is in no
// pair. A rule that says "no" to any of these would let the reliable method prune a true pair.
TEST(ReliablePieces, ExactPairRuleNeverNoWhereTheOracleSeesContactOnRandomFans) {
    RuleCounts total;
    for (uint32_t seed : {1u, 2u, 3u}) {
        const RuleCounts c = expectNeverNoWhereTheOracleSeesContact(randomFans(seed, 30), "random fans");
        for (int k = 0; k < 4; ++k) total.contacts[k] += c.contacts[k], total.no[k] += c.no[k];
    }
    EXPECT_GT(total.contacts[0], 50u);  // free triangles through the fans
    EXPECT_GT(total.contacts[1], 50u);  // through the opposite edge, or overlapping coplanar wedges
    EXPECT_GT(total.contacts[2], 20u);  // coplanar fold-overs
    EXPECT_GT(total.contacts[3], 5u);  // duplicated faces
    EXPECT_GT(total.no[1], 200u);  // neighbours that merely touch at the centre
    EXPECT_GT(total.no[2], 200u);  // bent or flat neighbours
}

// Trap: neighbours the float filter cannot decide. Fans whose rim vertices lie within a few ulps
// of the centre's plane (subdivided flat faces, rounded midpoints), some exactly on it, some
// folded back through it: the exact signs must agree with the oracle's fast paths (its integer
// plane signs and one-orientation shared-vertex rule) wherever those find contact.
TEST(ReliablePieces, ExactPairRuleNeverNoWhereTheOracleSeesContactOnNearlyCoplanarFans) {
    RuleCounts total;
    for (uint32_t seed : {11u, 12u, 13u}) {
        const Mesh m = test::nearlyCoplanarFans(seed, 30);
        const RuleCounts c = expectNeverNoWhereTheOracleSeesContact(m, "nearly coplanar fans");
        for (int k = 0; k < 4; ++k) total.contacts[k] += c.contacts[k], total.no[k] += c.no[k];
    }
    EXPECT_GT(total.contacts[1], 20u);  // the extra triangles across a fan, through it or on it
    EXPECT_GT(total.no[1], 500u);  // rim triangles that meet only at the centre
    EXPECT_GT(total.no[2], 300u);  // rim neighbours, flat within ulps or bent
}

// Trap: the GL backend has no conservative rasterization; asking for the reliable method there
// must be a clear error naming the cause, never a silent fallback.
TEST(ReliableMethod, RefusedByABackendWithoutConservativeRasterization) {
    struct NoConservative : DepthBackend {
        std::string describe() const override { return "test backend"; }
        void setGeometry(std::span<const Vec3f>, std::span<const Triangle>) override {}
        void setView(const OrthoView&) override {}
        std::vector<uint64_t> execute(const CommandList& l) override {
            return std::vector<uint64_t>(l.queryCount(), 0);
        }
        DepthImage readDepth() override { return {}; }
    } backend;
    CullideOptions o;
    o.method = CullMethod::Reliable;
    try {
        runCullide(sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Transform::Identity()}}), backend, o);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("CPU-only"), std::string::npos) << e.what();
    }
    EXPECT_EQ(parseCullMethod("reliable"), CullMethod::Reliable);
    EXPECT_STREQ(toString(CullMethod::Reliable), "reliable");
}

// ---------------------------------------------------------------------------------------------
// Hand-built traps

// Trap: axis-aligned boxes seen along the axes put every crossing face edge-on; the GL-like
// methods prune them all (cullide_test: AxisAlignedBoxesLoseCrossingEdgeOn). Conservatively an
// edge-on face covers its segment with its whole depth range, so the crossings are kept.
TEST(ReliableMethod, EdgeOnAxisAlignedBoxesAreKept) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(2, 2, 2)), Transform::Identity()},
                             {box(Vec3f(1.1f, 1.3f, 0.7f), Vec3f(3, 3, 3)), Transform::Identity()}});
    for (int res : {16, 64, 256})
        for (const DepthFormat& f : allFormats())
            for (uint32_t leaf : {1u, 4u}) {
                const Outcome r = reliable(s, res, f, leaf);
                ASSERT_GT(r.report.collidingTriangles, 0u);
                EXPECT_EQ(r.report.falsePruneCount(), 0u)
                    << res << " " << f.name() << " leaf " << leaf << ": " << describe(r.report);
            }
}

// Trap: contacts: face-to-face (coplanar overlap), edge-on-face and vertex-on-face touching have
// no penetration at all; GREATER loses them all, the interval test must keep them.
TEST(ReliableMethod, TouchingContactsAreKept) {
    const Scene faceToFace = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Transform::Identity()},
                                      {box(Vec3f(0.3f, 0.2f, 1), Vec3f(1.5f, 1.4f, 2)), Transform::Identity()}});
    const Scene tilted = sceneOf(
        {{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Transform::Identity()},
         {box(Vec3f(-0.5f, -0.5f, -0.5f), Vec3f(0.5f, 0.5f, 0.5f)), test::rotation(0.3, 0.5, 0.1, Vec3f(3, 3, 3))}});
    // The second box's lowest vertex moved to rest exactly on the first box's top face is hard to
    // make in float; a box sharing the first one's corner position exactly is a vertex contact.
    const Scene corner = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Transform::Identity()},
                                  {box(Vec3f(1, 1, 1), Vec3f(2, 2.5f, 1.7f)), Transform::Identity()}});
    for (const Scene* s : {&faceToFace, &corner})
        for (int res : {16, 100})
            for (const DepthFormat& f : {DepthFormat::unorm(8), DepthFormat::unorm(24), DepthFormat::float32()}) {
                const Outcome r = reliable(*s, res, f, 2);
                ASSERT_GT(r.report.collidingTriangles, 0u);
                EXPECT_EQ(r.report.falsePruneCount(), 0u) << res << " " << f.name() << ": " << describe(r.report);
            }
    // Apart: everything pruned at a fair resolution.
    const Outcome apart = reliable(tilted, 128, DepthFormat::unorm(24), 2);
    EXPECT_EQ(apart.report.collidingTriangles, 0u);
    EXPECT_TRUE(apart.result.pcs.empty()) << apart.result.pcs.size();
}

// Trap: a lone self-crossing object: there is no other object to test against; the crossing
// lies between non-adjacent units of one object, and the mesh's own adjacency must not keep
// everything.
TEST(ReliableMethod, SelfCrossingRibbonsAreKeptAndTheRestPruned) {
    const Scene s = sceneOf({{selfCrossingRibbon(120), test::rotation(0.31, 0.47, 0.23)}});
    for (int res : {16, 64, 256})
        for (const DepthFormat& f : allFormats()) {
            const Outcome r = reliable(s, res, f, 4);
            ASSERT_GT(r.report.collidingTriangles, 0u);
            EXPECT_EQ(r.report.falsePruneCount(), 0u) << res << " " << f.name() << ": " << describe(r.report);
            if (res == 256 && f == DepthFormat::unorm(24)) {
                EXPECT_LT(r.result.pcs.size(), s.triangleCount() / 2) << "the PCS should stay useful";
            }
        }
}

// Trap: two spheres far apart, and a sphere alone (closed surface: every unit sees units behind it
// in every direction): nothing intersects, and the PCS must become empty at a fair resolution.
TEST(ReliableMethod, SeparatedClosedSurfacesArePruned) {
    const Scene s = sceneOf(
        {{sphere(16, 24), Transform::Identity()}, {sphere(16, 24), test::rotation(0.1, 0.2, 0.3, Vec3f(3, 0.5f, 0))}});
    const Outcome r = reliable(s, 256, DepthFormat::unorm(24), 8);
    EXPECT_EQ(r.report.collidingTriangles, 0u);
    EXPECT_TRUE(r.result.pcs.empty()) << r.result.pcs.size() << " of " << s.triangleCount();
}

// ---------------------------------------------------------------------------------------------
// Acceptance at small sizes: the paper's generated scenes and the bundled ones, resolutions
// 16..256, depth formats 8..32 and float, random rotations (fixed seeds). Zero false prunes.

struct SceneCase {
    std::string name;
    Scene scene;
};

std::vector<SceneCase> acceptanceScenes() {
    const Mesh bunny = loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/bunny.off");
    const Mesh cow = loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/cow.off");
    std::vector<SceneCase> out;
    out.push_back({"deformed bunny 1k", makeDeformedBunny(bunny, {1000, 1, 0}).scene});
    out.push_back({"two cows 1.5k", makeTwoCows(cow, {1500, 1, 0}).scene});
    out.push_back({"cylinders 1.2k", makeCylinders(12, {1200, 1, 0}).scene});
    const Animation bowed = makeCylinders(12, {900, 1, 4});
    out.push_back({"bowed cylinders frame 1", bowed.sceneAt(1)});
    return out;
}

TEST(ReliableAcceptance, ZeroFalsePrunesOnGeneratedScenesAcrossResolutionsAndFormats) {
    for (const SceneCase& c : acceptanceScenes()) {
        const oracle::Truth truth = oracle::findIntersections(c.scene);
        EXPECT_GT(truth.pairs.size(), 0u) << c.name << ": the scene should intersect";
        for (int res : {16, 64, 256})
            for (const DepthFormat& f : allFormats()) {
                if (res == 256 && !(f == DepthFormat::unorm(24) || f == DepthFormat::unorm(8))) continue;  // CI time
                auto backend = raster::makeCpuBackend();
                CullideOptions o;
                o.method = CullMethod::Reliable;
                o.width = o.height = res;
                o.depth = f;
                const CullideResult r = runCullide(c.scene, *backend, o);
                const study::PcsReport rep = study::measurePcs(c.scene, truth, r.pcs, o);
                EXPECT_EQ(rep.falsePruneCount(), 0u)
                    << c.name << " " << res << " " << f.name() << ": " << describe(rep);
            }
    }
}

TEST(ReliableAcceptance, ZeroFalsePrunesUnderRandomRotationsAndDirections) {
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> angle(-M_PI, M_PI);
    const std::vector<SceneCase> scenes = acceptanceScenes();
    for (int trial = 0; trial < 6; ++trial) {
        const SceneCase& c = scenes[size_t(trial) % scenes.size()];
        Scene s = c.scene;
        const Transform t = test::rotation(angle(rng), angle(rng), angle(rng), Vec3f(0.1f, -0.2f, 0.3f));
        for (Object& o : s.objects) o.transform = t * o.transform;
        const int res = trial % 2 ? 48 : 128;
        const DepthFormat f = allFormats()[size_t(trial) % allFormats().size()];
        const std::vector<Vec3d> dirs = trial % 3 == 0 ? spreadDirections(5) : axisDirections();
        const Outcome r = reliable(s, res, f, trial % 2 ? 8 : 16, dirs);
        EXPECT_EQ(r.report.falsePruneCount(), 0u) << c.name << " trial " << trial << ": " << describe(r.report);
    }
}

// Under the sanitizers the middle frame only (the three took 121 s of the ThreadSanitizer stage).
TEST(ReliableAcceptance, ZeroFalsePrunesOnBundledScenes) {
    for (const char* name : {"bunny_through_cow.json", "two_cows_and_bunny.json"}) {
        const Animation a = loadScene(std::string(CULLIDE_DATA_DIR) + "/scenes/" + name);
        std::vector<size_t> frames = {0, a.frameCount() / 2, a.frameCount() - 1};
        if (CULLIDE_SANITIZED) frames = {a.frameCount() / 2};
        for (size_t f : frames) {
            const Scene s = a.sceneAt(f);
            const Outcome r = reliable(s, 64, DepthFormat::unorm(16));
            EXPECT_EQ(r.report.falsePruneCount(), 0u) << name << " frame " << f << ": " << describe(r.report);
        }
    }
}

// Trap: refitted views and repeated rounds (adaptive resolution) losing a pair: each call must be
// sound on its own PCS, whatever the PCS was shrunk to by the calls before. The acceptance scenes
// and bundled frames with --resolution auto from coarse bases: zero false prunes; the rounds go
// on until one prunes nothing (the last round's calls keep what they are given), and the PCS is
// never larger than the fixed base's.
TEST(ReliableAcceptance, ZeroFalsePrunesWithAdaptiveResolution) {
    std::vector<SceneCase> scenes = acceptanceScenes();
    const Animation a = loadScene(std::string(CULLIDE_DATA_DIR) + "/scenes/bunny_through_cow.json");
    scenes.push_back({"bunny through cow, middle frame", a.sceneAt(a.frameCount() / 2)});
    for (const SceneCase& c : scenes)
        for (int base : {16, 64}) {
            const Outcome r = reliable(c.scene, base, DepthFormat::unorm(16), 16, axisDirections(), 0, 4);
            EXPECT_EQ(r.report.falsePruneCount(), 0u) << c.name << " base " << base << ": " << describe(r.report);
            ASSERT_FALSE(r.result.passes.empty());
            const uint32_t last = r.result.passes.back().round;
            size_t lastIn = 0, lastOut = 0;
            for (const PassStats& p : r.result.passes) {
                EXPECT_GE(std::max(p.width, p.height), base) << c.name;
                if (p.round == last) lastIn = std::max(lastIn, p.nodesIn), lastOut = p.nodesOut;
            }
            if (!r.result.pcs.empty()) {
                EXPECT_EQ(lastIn, lastOut) << c.name << ": the last round pruned something";
            }
            const Outcome fixed = reliable(c.scene, base, DepthFormat::unorm(16));
            EXPECT_LE(r.result.pcs.size(), fixed.result.pcs.size()) << c.name << " base " << base;
        }
}

// Same scene and options: the same PCS and the same per-pass counts for 1, 2 and 4 threads.
TEST(ReliableMethod, DeterministicAcrossThreads) {
    const Scene s = sceneOf({{sphere(10, 14), Transform::Identity()},
                             {sphere(10, 14), test::rotation(0.1, 0.2, 0.3, Vec3f(1.3f, 0.2f, 0))},
                             {selfCrossingRibbon(60), test::rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
    const Outcome one = reliable(s, 96, DepthFormat::unorm(24), 8, axisDirections(), 1);
    for (int threads : {2, 4}) {
        const Outcome r = reliable(s, 96, DepthFormat::unorm(24), 8, axisDirections(), threads);
        EXPECT_EQ(r.result.pcs, one.result.pcs) << threads;
        ASSERT_EQ(r.result.passes.size(), one.result.passes.size());
        for (size_t i = 0; i < r.result.passes.size(); ++i)
            EXPECT_EQ(r.result.passes[i].nodesOut, one.result.passes[i].nodesOut);
    }
    EXPECT_EQ(one.report.falsePruneCount(), 0u) << describe(one.report);
    // Adaptive resolution: the same rounds, viewports and PCS for every thread count.
    const Outcome adaptiveOne = reliable(s, 32, DepthFormat::unorm(24), 8, axisDirections(), 1, 4);
    for (int threads : {2, 4}) {
        const Outcome r = reliable(s, 32, DepthFormat::unorm(24), 8, axisDirections(), threads, 4);
        EXPECT_EQ(r.result.pcs, adaptiveOne.result.pcs) << threads;
        ASSERT_EQ(r.result.passes.size(), adaptiveOne.result.passes.size());
        for (size_t i = 0; i < r.result.passes.size(); ++i) {
            EXPECT_EQ(r.result.passes[i].width, adaptiveOne.result.passes[i].width);
            EXPECT_EQ(r.result.passes[i].round, adaptiveOne.result.passes[i].round);
        }
    }
}

}  // namespace
