// Tests for oracle/src/oracle.cpp (and the sharing rules of cullide/predicates.h, end to end):
// hand-built traps, the broad phase against all pairs, determinism across thread counts, the exact
// stage, bad input, and the cross-check with CGAL's self_intersections pair for pair.
#include "cullide/oracle/oracle.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/cgal_reference.h"
#include "cullide/predicates.h"

#include "test_util.h"

#include "../oracle/src/broad_phase.h"
#include "../oracle/src/narrow_phase.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

namespace cullide::oracle {
namespace {

Scene sceneOf(std::vector<Mesh> meshes) {
    Scene s;
    for (size_t i = 0; i < meshes.size(); ++i)
        s.objects.push_back({std::string("m").append(std::to_string(i)), std::move(meshes[i]), Transform::Identity()});
    return s;
}

Mesh meshOf(std::vector<Vec3f> p, std::vector<Triangle> t) {
    return Mesh{std::move(p), std::move(t)};
}

// The pairs of a one-object scene as (a, b, class).
std::vector<std::tuple<uint32_t, uint32_t, PairClass>> pairsOf(const Mesh& m, const OracleOptions& o = {}) {
    std::vector<std::tuple<uint32_t, uint32_t, PairClass>> out;
    for (const IntersectingPair& p : findIntersections(sceneOf({m}), o).pairs)
        out.emplace_back(p.triangleA, p.triangleB, p.cls);
    return out;
}

using Pairs = std::vector<std::tuple<uint32_t, uint32_t, PairClass>>;
constexpr PairClass X = PairClass::Crossing, T = PairClass::Touching;

// Trap: coplanar overlap counted as a crossing (equal depths: only the original method sees it),
// or missed because the projection plane was chosen by a float normal.
TEST(Oracle, CoplanarOverlappingIsTouching) {
    const Mesh m = meshOf(
        {{0, 0, 0.25f}, {2, 0, 0.5f}, {0, 2, 0.75f}, {0.5f, 0.5f, 0.4375f}, {3, 0.5f, 0.75f}, {0.5f, 3, 1.0625f}},
        {{0, 1, 2}, {3, 4, 5}});
    // Both on the tilted plane z = 0.25 + 0.125 x + 0.25 y (exact in float at these points).
    EXPECT_EQ(pairsOf(m), (Pairs{{0, 1, T}}));
}

// Trap: coplanar triangles that meet only at one boundary point (corner on edge), and coplanar
// triangles one float ulp apart.
TEST(Oracle, CoplanarTouchingAndCoplanarApart) {
    const float gap = std::nextafter(1.0f, 2.0f);
    const Mesh touch =
        meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {1, 1, 0}, {3, 1, 0}, {1, 3, 0}}, {{0, 1, 2}, {3, 4, 5}});
    EXPECT_EQ(pairsOf(touch), (Pairs{{0, 1, T}}));
    const Mesh apart =
        meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {gap, gap, 0}, {3, 1, 0}, {1, 3, 0}}, {{0, 1, 2}, {3, 4, 5}});
    EXPECT_TRUE(pairsOf(apart).empty());
}

// Trap: shared-edge neighbours reported because they touch along the edge; a fold-over (coplanar,
// opposite corners on the same side) missed because they share an edge.
TEST(Oracle, SharedEdgeOnlyFoldOverCounts) {
    const Mesh flat = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, {{0, 1, 2}, {2, 1, 3}});
    EXPECT_TRUE(pairsOf(flat).empty());
    const Mesh bent = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}}, {{0, 1, 2}, {2, 1, 3}});
    EXPECT_TRUE(pairsOf(bent).empty());
    const Mesh fold = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25f, 0.25f, 0}}, {{0, 1, 2}, {1, 0, 3}});
    EXPECT_EQ(pairsOf(fold), (Pairs{{0, 1, T}}));
    // Folded flat onto the edge's line side, but the corner exactly on the edge line: no overlap.
    const Mesh onLine = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5f, 1, 0}}, {{0, 1, 2}, {2, 1, 3}});
    EXPECT_TRUE(pairsOf(onLine).empty());
}

// Trap: a shared vertex taken for a contact (fan neighbours), and a crossing through a shared
// vertex missed because pairs with a shared vertex are skipped (Embree's tutorial does that).
TEST(Oracle, SharedVertexTouchVersusCrossing) {
    const Mesh fan = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0.5f}, {0, -1, 0.5f}}, {{0, 1, 2}, {0, 3, 4}});
    EXPECT_TRUE(pairsOf(fan).empty());
    // The second triangle's opposite edge pierces the first's interior: a crossing.
    const Mesh pierce =
        meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, -1}, {0.5f, 0.5f, 1}}, {{0, 1, 2}, {0, 3, 4}});
    EXPECT_EQ(pairsOf(pierce), (Pairs{{0, 1, X}}));
    // The opposite edge passes through the first triangle's edge and the second triangle cuts
    // through the first along a segment from the shared vertex: still a crossing.
    const Mesh cut = meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {1, 1, -1}, {1, 1, 1}}, {{0, 1, 2}, {0, 3, 4}});
    EXPECT_EQ(pairsOf(cut), (Pairs{{0, 1, X}}));
    // Standing on the first triangle (an edge lying in it, the rest above): touching.
    const Mesh stand = meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {1, 1, 0}, {1, 1, 1}}, {{0, 1, 2}, {0, 3, 4}});
    EXPECT_EQ(pairsOf(stand), (Pairs{{0, 1, T}}));
}

// Trap: a T-junction (a corner inside another triangle's edge, no shared index) and a corner
// exactly on a face are contacts, not crossings; one float ulp away they are nothing.
TEST(Oracle, TJunctionAndVertexOnFace) {
    const Mesh tj = meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {1, 0, 0}, {1, -1, 0}, {1, 0, 1}}, {{0, 1, 2}, {3, 4, 5}});
    EXPECT_EQ(pairsOf(tj), (Pairs{{0, 1, T}}));
    const Mesh onFace =
        meshOf({{0, 0, 0}, {3, 0, 1}, {0, 3, 1}, {1, 1, 2.0f / 3.0f}, {1, 1, 5}, {2, 1, 5}}, {{0, 1, 2}, {3, 4, 5}});
    // (1, 1, 2/3) in float is not exactly on z = (x + y) / 3: a float test would call it on the face.
    const Mesh onFaceExact =
        meshOf({{0, 0, 0}, {4, 0, 1}, {0, 4, 1}, {1, 1, 0.5f}, {1, 1, 5}, {2, 1, 5}}, {{0, 1, 2}, {3, 4, 5}});
    EXPECT_EQ(pairsOf(onFaceExact), (Pairs{{0, 1, T}}));
    const float above = std::nextafter(0.5f, 1.0f);
    const Mesh justAbove =
        meshOf({{0, 0, 0}, {4, 0, 1}, {0, 4, 1}, {1, 1, above}, {1, 1, 5}, {2, 1, 5}}, {{0, 1, 2}, {3, 4, 5}});
    EXPECT_TRUE(pairsOf(justAbove).empty());
    // 2/3 rounded to float lies above or below the plane, never on it: crossing or nothing, not touching.
    for (const auto& [a, b, c] : pairsOf(onFace)) EXPECT_NE(c, T);
}

// Trap: degenerate (collinear, coincident, repeated-index) triangles paired with what they pass
// through; CGAL reports them as (f, f) and in no pair, and so do we. The last one's corners are
// exactly collinear (multiples of (1, 3, 5)), but their differences round in doubles and the
// cross product evaluated from them is not zero: a degeneracy filter without its error bound
// (detail::certainlyNotCollinear) takes it for a triangle.
TEST(Oracle, DegenerateTrianglesAreListedNotPaired) {
    const Mesh m = meshOf({{0, 0, 0},
                           {2, 0, 0},
                           {0, 2, 0},
                           {0.5f, 0.5f, -1},
                           {0.5f, 0.5f, 0},
                           {0.5f, 0.5f, 1},
                           {0x1.23eeap-24f, 0x1.b5e5fp-23f, 0x1.6cea48p-22f},
                           {0x1.b262cp+17f, 0x1.45ca1p+19f, 0x1.0f7db8p+20f},
                           {0x1.0630cp+15f, 0x1.89492p+16f, 0x1.47bcfp+17f}},
                          {{0, 1, 2}, {3, 4, 5}, {3, 3, 5}, {3, 5, 5}, {6, 7, 8}});
    const Truth t = findIntersections(sceneOf({m}));
    EXPECT_TRUE(t.pairs.empty());
    EXPECT_EQ(t.degenerate, (std::vector<TriangleRef>{{0, 1}, {0, 2}, {0, 3}, {0, 4}}));
    EXPECT_EQ(t.trianglesTested, 1u);
}

// Trap: duplicated faces (same three indices, either orientation) silently skipped as "sharing
// everything"; duplicated vertices in a soup.
TEST(Oracle, DuplicatedFacesAndDuplicatedVertices) {
    const Mesh dup = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {2, 1, 0}});
    EXPECT_EQ(pairsOf(dup), (Pairs{{0, 1, T}}));
    // Two flat neighbours whose shared edge uses duplicated vertices (3 = 1, 4 = 2 bit for bit):
    // by index they share nothing and touch along the edge; welded they are neighbours.
    const Mesh soup =
        meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, {{0, 1, 2}, {4, 3, 5}});
    EXPECT_EQ(pairsOf(soup), (Pairs{{0, 1, T}}));
    OracleOptions weld;
    weld.weldByPosition = true;
    EXPECT_TRUE(pairsOf(soup, weld).empty());
    // Welding is by world position: (1, 0, 0) and (1, 0, 0) weld, (0, 1, 0.5) stays apart, so
    // the triangles share one vertex and meet nowhere else.
    const Mesh partly =
        meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 1, 0.5f}, {1, 1, 0}}, {{0, 1, 2}, {4, 3, 5}});
    EXPECT_TRUE(pairsOf(partly, weld).empty());
}

// Trap: float tests lie at tiny and huge magnitudes and for near-parallel planes. The same
// crossing configuration scaled by 2^-100 and 2^55 (exact in float) keeps its answer; a triangle
// one denormal above a plane does not touch it; a nearly parallel triangle that dips one ulp
// below crosses.
TEST(Oracle, TinyHugeAndNearParallel) {
    for (float scale : {0x1p-100f, 1.0f, 0x1p55f}) {
        const Mesh m = meshOf({{0, 0, 0},
                               {2 * scale, 0, 0},
                               {0, 2 * scale, 0},
                               {0.5f * scale, 0.5f * scale, -scale},
                               {0.5f * scale, 0.5f * scale, scale},
                               {3 * scale, 3 * scale, scale}},
                              {{0, 1, 2}, {3, 4, 5}});
        EXPECT_EQ(pairsOf(m), (Pairs{{0, 1, X}})) << "scale " << scale;
    }
    const float tiny = std::numeric_limits<float>::denorm_min();
    const Mesh above =
        meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, tiny}, {1.5f, 0.2f, tiny}, {0.2f, 1.5f, tiny}},
               {{0, 1, 2}, {3, 4, 5}});
    EXPECT_TRUE(pairsOf(above).empty());
    const Mesh dips =
        meshOf({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, -tiny}, {1.5f, 0.2f, tiny}, {0.2f, 1.5f, tiny}},
               {{0, 1, 2}, {3, 4, 5}});
    EXPECT_EQ(pairsOf(dips), (Pairs{{0, 1, X}}));
}

// Between objects every contact counts, whatever the indices say (different vertex arrays).
TEST(Oracle, BetweenObjectsIndicesDoNotShare) {
    const Mesh a = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
    const Mesh b = meshOf({{0, 0, 0}, {1, 0, 0}, {0, -1, 0}}, {{0, 1, 2}});  // same indices, shared edge geometrically
    const Truth t = findIntersections(sceneOf({a, b}));
    ASSERT_EQ(t.pairs.size(), 1u);
    EXPECT_EQ(t.pairs[0], (IntersectingPair{0, 0, 1, 0, T}));
}

// Random triangles in three objects: both broad phases (the grid and Embree, with their float
// boxes) lose no pair that the all-pairs loop finds, and invent none.
TEST(Oracle, BroadPhaseMatchesAllPairs) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Mesh> meshes(3);
    for (Mesh& m : meshes)
        for (int t = 0; t < 150; ++t) {
            const Vec3f c(u(rng), u(rng), u(rng));
            const uint32_t base = uint32_t(m.positions.size());
            for (int k = 0; k < 3; ++k)
                m.positions.push_back(c + 0.15f * Vec3f(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
            // Every third triangle reuses a corner of the previous one: shared-vertex rules too.
            if (t % 3 == 2) m.triangles.push_back({base - 1, base + 1, base + 2});
            else m.triangles.push_back({base, base + 1, base + 2});
        }
    const Scene scene = sceneOf(meshes);
    std::vector<IntersectingPair> expected;
    auto pts = [&](uint32_t o, uint32_t t) {
        const Triangle& i = meshes[o].triangles[t];
        return TrianglePoints{meshes[o].positions[i[0]].cast<double>(), meshes[o].positions[i[1]].cast<double>(),
                              meshes[o].positions[i[2]].cast<double>()};
    };
    for (uint32_t oa = 0; oa < 3; ++oa)
        for (uint32_t ta = 0; ta < 150; ++ta)
            for (uint32_t ob = oa; ob < 3; ++ob)
                for (uint32_t tb = ob == oa ? ta + 1 : 0; tb < 150; ++tb) {
                    const Contact c = faceContact(pts(oa, ta), meshes[oa].triangles[ta], pts(ob, tb),
                                                  meshes[ob].triangles[tb], oa == ob);
                    if (c != Contact::None) expected.push_back({oa, ta, ob, tb, c == Contact::Crossing ? X : T});
                }
    EXPECT_GT(expected.size(), 100u);
    for (BroadPhase b : {BroadPhase::Grid, BroadPhase::Embree}) {
        OracleOptions o;
        o.broadPhase = b;
        const Truth t = findIntersections(scene, o);
        EXPECT_EQ(t.pairs, expected) << toString(b);
    }
}

// Trap: the box corners' outward rounding is written on the float's bits (std::nextafter was a
// libm call per corner): +0 and -0 must both step to the smallest denormal of the side asked
// for, a negative float must grow in magnitude going down, a denormal must step to zero; a slip
// lets boxes that only touch miss each other.
TEST(OracleBroadPhase, OutwardRoundingIsNextafter) {
    const float inf = std::numeric_limits<float>::infinity();
    const float denormal = std::numeric_limits<float>::denorm_min(), normal = std::numeric_limits<float>::min();
    std::vector<float> xs = {0.0f, -0.0f, denormal, -denormal, normal, -normal, 1, -1, 0x1p60f, -0x1p60f, 0.1f, -3.5f};
    std::mt19937 rng(5);
    while (xs.size() < 20000) {
        const float x = std::bit_cast<float>(uint32_t(rng()));
        if (std::isfinite(x) && std::abs(x) <= 0x1p60f) xs.push_back(x);
    }
    for (float x : xs) {
        EXPECT_EQ(std::bit_cast<uint32_t>(detail::roundDown(x)), std::bit_cast<uint32_t>(std::nextafter(x, -inf))) << x;
        EXPECT_EQ(std::bit_cast<uint32_t>(detail::roundUp(x)), std::bit_cast<uint32_t>(std::nextafter(x, inf))) << x;
    }
}

// Trap: radixSortHigh sorts small buckets by insertion and larger ones by LSD passes; both must
// be stable on bits [32, 32 + keyBits) only and leave every bucket in the array the returned
// pointer names (uniform keys: small buckets; keys below 2^(keyBits - 8): one bucket holds all).
TEST(OracleBroadPhase, RadixSortIsStableOnTheKey) {
    std::mt19937_64 rng(7);
    for (size_t n : {size_t(0), size_t(1), size_t(5), size_t(300), size_t(5000), size_t(200000)})
        for (int keyBits : {0, 7, 8, 13, 22, 30})
            for (bool skewed : {false, true}) {
                const int bits = skewed ? std::max(0, keyBits - 8) : keyBits;
                std::vector<uint64_t> v(n), tmp(n);
                // The low 32 bits count up: a stable sort on the key is the sort on the whole value.
                for (size_t i = 0; i < n; ++i) v[i] = (bits == 0 ? 0 : rng() >> (64 - bits)) << 32 | i;
                std::vector<uint64_t> expected = v;
                std::sort(expected.begin(), expected.end());
                const uint64_t* out = detail::radixSortHigh(v.data(), tmp.data(), n, keyBits);
                EXPECT_TRUE(std::equal(expected.begin(), expected.end(), out))
                    << "n " << n << ", keyBits " << keyBits << ", skewed " << skewed;
            }
}

// Random small triangles of two objects for the grid broad phase against Embree: `scattered` of
// size `size` over the unit cube, `cluster` in a dense cluster at its centre (size 0.01), four of
// size `aside` (large: set aside by the grid). Expects the same candidate pairs and truth.
void expectGridMatchesEmbree(uint32_t seed, int scattered, float size, int cluster, float aside) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Mesh> meshes(2);
    auto add = [&](Mesh& m, const Vec3f& c, float side) {
        const uint32_t base = uint32_t(m.positions.size());
        for (int k = 0; k < 3; ++k)
            m.positions.push_back(c + side * Vec3f(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
        m.triangles.push_back({base, base + 1, base + 2});
    };
    for (int t = 0; t < scattered; ++t) add(meshes[t % 2], Vec3f(u(rng), u(rng), u(rng)), size);
    for (int t = 0; t < cluster; ++t)
        add(meshes[t % 2], Vec3f(0.5f, 0.5f, 0.5f) + 0.01f * Vec3f(u(rng), u(rng), u(rng)), 0.01f);
    for (int t = 0; t < 4; ++t) add(meshes[t % 2], Vec3f(u(rng), u(rng), u(rng)), aside);
    const Scene scene = sceneOf(meshes);
    OracleOptions grid, embree;
    embree.broadPhase = BroadPhase::Embree;
    const Truth g = findIntersections(scene, grid), e = findIntersections(scene, embree);
    EXPECT_GT(g.pairs.size(), 10000u);
    EXPECT_EQ(g.candidatePairs, e.candidatePairs);
    EXPECT_EQ(g.pairs, e.pairs);
}

// Trap: the grid's entries are written straight into their top-digit buckets and its cells are
// walked per fixed block of entries: a cell that straddles a block boundary (a dense cluster
// puts thousands of entries in one cell), small and large buckets, a key over 16 bits (many
// cells), boxes set aside (over 64 cells) and two objects must still give exactly Embree's
// candidate pairs and truth.
TEST(OracleBroadPhase, GridMatchesEmbreeOnManyCells) {
    expectGridMatchesEmbree(11, 20000, 0.01f, 2500, 0.5f);
}

// Trap: up to 2^18 cells the grid takes another path, one counting sort by cell of the entries
// generated once: a dense cluster (cells straddling the walk's blocks), boxes set aside and two
// objects must still give exactly Embree's candidate pairs and truth there too.
TEST(OracleBroadPhase, GridMatchesEmbreeOnFewCells) {
    expectGridMatchesEmbree(12, 3000, 0.05f, 1500, 0.7f);  // ~20k cells
}

// Bad input is refused before it reaches Embree (which would drop it silently).
TEST(Oracle, RefusesNonFiniteAndHugeCoordinates) {
    Mesh m = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
    m.positions[1].x() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(findIntersections(sceneOf({m})), InputError);
    m.positions[1].x() = 0x1p61f;
    EXPECT_THROW(findIntersections(sceneOf({m})), InputError);
    m.positions[1].x() = 1;
    m.triangles[0][2] = 7;
    EXPECT_THROW(findIntersections(sceneOf({m})), InputError);
    EXPECT_THROW(
        exactStage(sceneOf({meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}})}), std::vector<TriangleRef>{{0, 1}}),
        InputError);
}

Mesh bundled(const char* name) {
    return loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/" + name);
}

// The callback runs concurrently in no fixed order: the result must not depend on the threads.
TEST(Oracle, DeterministicForOneAndTwoThreads) {
    SceneRequest req;
    req.triangles = 20000;
    const Scene scene = makeTwoCows(bundled("cow.off"), req).scene;
    std::vector<IntersectingPair> results[2];
    for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        results[threads - 1] = findIntersections(scene).pairs;
    }
    EXPECT_GT(results[0].size(), 100u);
    EXPECT_EQ(results[0], results[1]);
    EXPECT_TRUE(std::is_sorted(results[0].begin(), results[0].end()));
}

// The exact stage on a PCS: with every triangle it is the truth; on a subset, exactly the
// truth's pairs whose two triangles are in the subset.
TEST(Oracle, ExactStageIsTheTruthRestrictedToThePcs) {
    SceneRequest req;
    req.triangles = 6000;
    const Scene scene = makeTwoCows(bundled("cow.off"), req).scene;
    const Truth truth = findIntersections(scene);
    std::vector<TriangleRef> all, half;
    for (uint32_t t = 0; t < scene.objects[0].mesh.triangleCount(); ++t) {
        all.push_back({0, t});
        if (t % 2) half.push_back({0, t});
    }
    EXPECT_EQ(exactStage(scene, all).pairs, truth.pairs);
    std::vector<IntersectingPair> expected;
    for (const IntersectingPair& p : truth.pairs)
        if (p.triangleA % 2 && p.triangleB % 2) expected.push_back(p);
    EXPECT_EQ(exactStage(scene, half).pairs, expected);
}

// Pair for pair against CGAL's self_intersections.
// Both broad phases must give it.
void expectSameAsCgal(const Mesh& mesh, const std::string& what, size_t expectedCount = 0) {
    const std::vector<FacePair> cgal = CgalSelfIntersections(mesh, what).run();
    for (BroadPhase b : {BroadPhase::Grid, BroadPhase::Embree}) {
        OracleOptions o;
        o.broadPhase = b;
        EXPECT_EQ(selfPairsOf(findIntersections(sceneOf({mesh}), o), 0), cgal) << what << " (" << toString(b) << ")";
    }
    if (expectedCount) {
        EXPECT_EQ(cgal.size(), expectedCount) << what;
    }
}

// The bundled cow self-intersects: CGAL finds 101 pairs.
TEST(OracleCgal, CowSameAsCgal) {
    expectSameAsCgal(bundled("cow.off"), "cow", 101);
}
TEST(OracleCgal, BunnySameAsCgal) {
    expectSameAsCgal(bundled("bunny.off"), "bunny");
}

// The paper's generated scenes at a few thousand triangles (the deformation makes the crossings).
TEST(OracleCgal, GeneratedScenesSameAsCgal) {
    SceneRequest req;
    req.triangles = 4000;
    const Mesh bunny = makeDeformedBunny(bundled("bunny.off"), req).scene.objects[0].mesh;
    expectSameAsCgal(bunny, "deformed bunny");
    const Mesh cows = makeTwoCows(bundled("cow.off"), req).scene.objects[0].mesh;
    expectSameAsCgal(cows, "two cows");
}

// Trap: the fast paths for neighbours (one exact orientation decides a shared vertex; signs
// reused by Guigue-Devillers) must give faceContact's answer where the float filter cannot
// decide: fans of triangles around one vertex whose rims lie within a few ulps of one plane
// (subdivided flat faces with rounded midpoints), some corners exactly on it, some folded back
// through it. Every pair against faceContact on all pairs (the extra triangles at each centre
// make the mesh non-manifold, which CGAL's Surface_mesh refuses: the CGAL cross-check of the same
// paths is SubdividedCowSameAsCgal).
TEST(Oracle, NearlyCoplanarNeighboursMatchFaceContact) {
    const Mesh m = test::nearlyCoplanarFans(11, 30);
    std::vector<IntersectingPair> expected;
    auto pts = [&](uint32_t t) {
        const Triangle& i = m.triangles[t];
        return TrianglePoints{m.positions[i[0]].cast<double>(), m.positions[i[1]].cast<double>(),
                              m.positions[i[2]].cast<double>()};
    };
    const uint32_t n = uint32_t(m.triangles.size());
    for (uint32_t a = 0; a < n; ++a)
        for (uint32_t b = a + 1; b < n; ++b) {
            const Contact c = faceContact(pts(a), m.triangles[a], pts(b), m.triangles[b], true);
            if (c != Contact::None) expected.push_back({0, a, 0, b, c == Contact::Crossing ? X : T});
        }
    // Both classes occur, so that both answers are checked.
    EXPECT_GT(std::count_if(expected.begin(), expected.end(), [](const IntersectingPair& p) { return p.cls == X; }), 5);
    EXPECT_GT(std::count_if(expected.begin(), expected.end(), [](const IntersectingPair& p) { return p.cls == T; }), 5);
    EXPECT_EQ(findIntersections(sceneOf({m})).pairs, expected);
}

// The cow subdivided once: rounded midpoints make most neighbours nearly (not exactly)
// coplanar, the case the exact integer paths decide.
TEST(OracleCgal, SubdividedCowSameAsCgal) {
    expectSameAsCgal(subdivide(bundled("cow.off")), "subdivided cow");
}

// Two ways of computing one truth gave the same pairs (and some: two empty truths would compare
// equal without checking anything), degenerate triangles and candidate count.
void expectSameTruth(const Truth& a, const Truth& b) {
    EXPECT_FALSE(a.pairs.empty());
    EXPECT_EQ(a.pairs, b.pairs);
    EXPECT_EQ(a.degenerate, b.degenerate);
    EXPECT_EQ(a.candidatePairs, b.candidatePairs);
}

// Trap: objects of up to detail::spatialOrderMin triangles keep the mesh's own order, larger ones
// the Morton order; the truth must not depend on it (the pairs are put in triangle order, and the
// triangles come back from the records, not from their positions). Both orders on the same
// scenes: a subdivided cow (nearly coplanar neighbours), two cows (two objects, pairs between
// them) and the exact stage on a subset of one of them.
TEST(Oracle, SameTruthInMortonAndMeshOrder) {
    const size_t saved = detail::spatialOrderMin;
    auto both = [&](auto&& run) {
        detail::spatialOrderMin = 0;  // every object in Morton order
        const Truth morton = run();
        detail::spatialOrderMin = ~size_t(0);  // every object in its own order
        const Truth own = run();
        detail::spatialOrderMin = saved;
        expectSameTruth(morton, own);
    };
    const Mesh cow = subdivide(bundled("cow.off"));
    both([&] { return findIntersections(sceneOf({cow})); });
    Scene two = sceneOf({bundled("cow.off"), bundled("cow.off")});
    two.objects[1].transform.translate(Vec3f(0.25f, 0.02f, 0.05f));  // as the bench's two cows
    both([&] { return findIntersections(two); });
    std::vector<TriangleRef> pcs;
    for (uint32_t o = 0; o < 2; ++o)
        for (uint32_t t = 0; t < uint32_t(two.objects[o].mesh.triangleCount()); t += 1 + (o == 0))
            pcs.push_back({o, t});
    both([&] { return exactStage(two, pcs); });
}

// A PCS for the exact stage of the memory tests: object o's every (o + 1)-th triangle.
std::vector<TriangleRef> thinnedPcs(const Scene& scene) {
    std::vector<TriangleRef> pcs;
    for (uint32_t o = 0; o < uint32_t(scene.objects.size()); ++o)
        for (uint32_t t = 0; t < uint32_t(scene.objects[o].mesh.triangleCount()); t += 1 + o) pcs.push_back({o, t});
    return pcs;
}

OracleOptions welded() {
    OracleOptions o;
    o.weldByPosition = true;
    return o;
}

OracleOptions withEmbree() {
    OracleOptions o;
    o.broadPhase = BroadPhase::Embree;
    return o;
}

// Trap: scenes of up to detail::storedPlanesMax triangles store each triangle's plane and test
// their candidates a batch at a time in sharing classes (detail::primContacts), larger ones one
// pair at a time (detail::primContact); the truth must not depend on the path. Both on the same
// scenes: the subdivided cow (nearly coplanar neighbours), nearly coplanar fans (both classes of
// pair), two cows (pairs between objects), the exact stage on a subset, Embree's broad phase
// (its own batches) and a generated scene welded by position.
TEST(Oracle, SameTruthWithStoredAndComputedPlanes) {
    const size_t saved = detail::storedPlanesMax;
    auto both = [&](auto&& run) {
        detail::storedPlanesMax = ~size_t(0);  // planes stored, batches by class
        const Truth stored = run();
        detail::storedPlanesMax = 0;  // planes computed per pair, one pair at a time
        const Truth computed = run();
        detail::storedPlanesMax = saved;
        expectSameTruth(stored, computed);
    };
    const Mesh cow = bundled("cow.off");
    both([&] { return findIntersections(sceneOf({subdivide(cow)})); });
    both([&] { return findIntersections(sceneOf({test::nearlyCoplanarFans(11, 30)})); });
    Scene two = sceneOf({cow, cow});
    two.objects[1].transform.translate(Vec3f(0.25f, 0.02f, 0.05f));  // as the bench's two cows
    both([&] { return findIntersections(two); });
    both([&] { return exactStage(two, thinnedPcs(two)); });
    both([&] { return findIntersections(two, withEmbree()); });
    SceneRequest req;
    req.triangles = 6000;
    const Scene generated = makeTwoCows(cow, req).scene;
    both([&] { return findIntersections(generated, welded()); });
}

// Trap: detail::primContacts sorts a batch's pairs into sharing classes, 256 at a time, tests each
// class in its own loop (a vertex-sharing pair's first rejection in one more) and writes only the
// pairs that meet. A pair lost or tested twice at a chunk's end, one class given another's test,
// a survivor's signs or index shifted by the compaction, the other object's plane read, a pair
// in the wrong order tested or counted: other hits or another count than primContact one pair at
// a time. Pairs of one object that share an edge, a vertex, nothing and all three corners (a
// duplicated face), pairs between two objects (which share no vertex whatever their ids), pairs
// in the wrong order (reversed, or a triangle with itself), shuffled, all in one batch (chunks,
// the last one partial) and the first 100 (one partial chunk).
TEST(OracleNarrowPhase, BatchMatchesOnePairAtATime) {
    Mesh fans = test::nearlyCoplanarFans(7, 12);
    fans.triangles.insert(fans.triangles.begin() + 4, fans.triangles[3]);  // a duplicated face: three shared corners
    Mesh moved = fans;
    for (Vec3f& p : moved.positions) p += Vec3f(0.001f, -0.002f, 0.0005f);  // crosses the first
    struct Records {
        std::vector<detail::Prim> prims;
        std::vector<detail::Plane> planes;
    };
    auto recordsOf = [](const Mesh& m) {
        Records r;
        for (uint32_t t = 0; t < uint32_t(m.triangles.size()); ++t) {
            detail::Prim p{};
            for (int k = 0; k < 3; ++k)
                for (int c = 0; c < 3; ++c) p.p[k][c] = m.positions[m.triangles[t][k]][c];
            p.v = m.triangles[t];
            p.triangle = t;
            r.prims.push_back(p);
            r.planes.push_back(detail::planeOf(p));
        }
        return r;
    };
    const Records objects[2] = {recordsOf(fans), recordsOf(moved)};
    const detail::StoredPrims stored[2] = {{objects[0].prims.data(), objects[0].planes.data()},
                                           {objects[1].prims.data(), objects[1].planes.data()}};
    const uint32_t n = uint32_t(fans.triangles.size());
    std::vector<detail::Candidate> pairs;
    for (uint32_t a = 0; a < n; ++a)
        for (uint32_t b = 0; b < n; ++b) {
            if (a <= b && b < a + 40) pairs.push_back({0, a, 0, b});  // neighbours among them; a == b: wrong order
            if (b + 3 == a) pairs.push_back({0, a, 0, b});  // wrong order
            if ((a * 7 + b) % 29 == 0) pairs.push_back({0, a, 1, b});
            if ((a * 5 + b) % 61 == 0) pairs.push_back({1, a, 0, b});  // wrong order
        }
    std::shuffle(pairs.begin(), pairs.end(), std::mt19937(5));
    ASSERT_GT(pairs.size(), 2000u);
    ASSERT_NE(pairs.size() % 256, 0u);
    int sharing[4] = {0, 0, 0, 0};
    for (uint32_t count : {uint32_t(pairs.size()), 100u}) {
        std::vector<std::pair<uint32_t, Contact>> expected;
        size_t expectedTested = 0;
        for (uint32_t k = 0; k < count; ++k) {
            const detail::Candidate& c = pairs[k];
            if (c.object0 > c.object1 || (c.object0 == c.object1 && c.prim0 >= c.prim1)) continue;
            ++expectedTested;
            const detail::Prim &a = objects[c.object0].prims[c.prim0], &b = objects[c.object1].prims[c.prim1];
            if (c.object0 == c.object1)
                ++sharing[std::count_if(a.v.begin(), a.v.end(),
                                        [&](uint32_t v) { return std::find(b.v.begin(), b.v.end(), v) != b.v.end(); })];
            const Contact contact = detail::primContact(a, objects[c.object0].planes[c.prim0], b,
                                                        &objects[c.object1].planes[c.prim1], c.object0 == c.object1);
            if (contact != Contact::None) expected.emplace_back(k, contact);
        }
        std::vector<detail::Hit> hits(count);
        size_t tested = 0;
        const uint32_t found = detail::primContacts(stored, pairs.data(), count, hits.data(), tested);
        std::vector<std::pair<uint32_t, Contact>> got;
        for (uint32_t h = 0; h < found; ++h) got.emplace_back(hits[h].pair, hits[h].contact);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, expected) << count << " pairs";
        EXPECT_EQ(tested, expectedTested) << count << " pairs";
        if (count == pairs.size()) {
            // Both answers, between the objects and within the first.
            EXPECT_GT(
                std::count_if(expected.begin(), expected.end(), [](auto& e) { return e.second == Contact::Crossing; }),
                2);
            EXPECT_GT(
                std::count_if(expected.begin(), expected.end(), [](auto& e) { return e.second == Contact::Touching; }),
                2);
        }
    }
    for (int k = 0; k < 4; ++k) EXPECT_GT(sharing[k], 0) << "no tested pair shares " << k << " corners";
}

// Fans around one centre vertex each, for certifyFans: what kind each fan is.
enum class Fan {
    Star,  // tiles the plane around the centre once (along z): certified
    FlatStar,  // the same with its rim within 3 ulps of the centre's plane, some corners on it
    Twice,  // its rim winds twice around the centre (second turn crossing the first): not
    Open,  // an open rim over one and a half turns (the +x ray crossed once): not
    Folded,  // a star with two rim corners swapped: one triangle turns the other way
    Big,  // a star of 40 triangles, more than certifyFans looks at: not
};

// Fans of every kind (seeded), each around its own centre, half of them clockwise.
// centres[f] is fan f's centre vertex, kinds[f] its kind.
Mesh fanMesh(uint32_t seed, std::vector<uint32_t>& centres, std::vector<Fan>& kinds) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    constexpr float kPi = 3.14159265f;
    const Fan order[] = {Fan::Star, Fan::FlatStar, Fan::Twice, Fan::Open, Fan::Folded, Fan::Big};
    Mesh m;
    for (int f = 0; f < 60; ++f) {
        const Fan kind = order[f % 6];
        const uint32_t centre = uint32_t(m.positions.size());
        const Vec3f c(float(f % 8) * 4, float(f / 8) * 4, 0.5f);
        m.positions.push_back(c);
        const int k = kind == Fan::Big ? 40 : kind == Fan::Twice ? 10 + f % 7 : 3 + f % 10;
        const float total = kind == Fan::Twice ? 4 * kPi : kind == Fan::Open ? 3 * kPi : 2 * kPi;
        // Gaps below pi (each triangle turns one way), summing to `total`.
        std::vector<float> gap(static_cast<size_t>(k));
        float sum;
        do {
            sum = 0;
            for (float& g : gap) sum += g = 0.3f + u(rng);
        } while (*std::max_element(gap.begin(), gap.end()) * total / sum > 0.9f * kPi);
        const int rim = kind == Fan::Open ? k + 1 : k;
        float angle = kind == Fan::Open ? 0.1f + 0.4f * u(rng) : 2 * kPi * u(rng);
        // A closed fan's first corner now and then exactly on the centre's horizontal, on +x or -x
        // (where the winding's half-open rule decides).
        const int start = kind == Fan::Open ? 2 : int(rng() % 3);
        const bool onAxis = start < 2;
        if (onAxis) angle = start == 0 ? 0.0f : kPi;
        std::vector<Vec3f> corners;
        for (int i = 0; i < rim; ++i) {
            const bool inner = (kind == Fan::Twice && i >= k / 2) || (kind == Fan::Open && i > 2 * k / 3);
            const float r = inner ? 0.3f + 0.2f * u(rng) : 0.8f + 0.4f * u(rng);
            float z = c.z();
            if (inner) z += i % 2 ? 0.3f : -0.3f;  // through the outer turn's surface
            else if (kind == Fan::FlatStar) {
                for (int step = int(rng() % 7) - 3; step != 0; step += step > 0 ? -1 : 1)
                    z = std::nextafter(z, step > 0 ? 1.0f : 0.0f);
            } else z += 0.1f * (u(rng) - 0.5f);
            Vec3f p = c + Vec3f(r * std::cos(angle), r * std::sin(angle), z - c.z());
            if (i == 0 && onAxis) p.y() = c.y();
            corners.push_back(p);
            angle += gap[size_t(i % k)] * total / sum;
        }
        if (kind == Fan::Folded) std::swap(corners[0], corners[1]);
        for (const Vec3f& p : corners) m.positions.push_back(p);
        const bool clockwise = f % 12 >= 6;
        for (int i = 0; i < k; ++i) {
            const uint32_t a = centre + 1 + uint32_t(i),
                           b = centre + 1 + uint32_t(kind == Fan::Open ? i + 1 : (i + 1) % k);
            m.triangles.push_back(clockwise ? Triangle{centre, b, a} : Triangle{centre, a, b});
        }
        centres.push_back(centre);
        kinds.push_back(kind);
    }
    return m;
}

// Trap: detail::certifyFans lets the narrow phase skip a pair of one object that shares a vertex
// (or an edge through it) whose fan it certified, as meeting only there. A fan certified whose
// triangles meet elsewhere loses pairs: a rim winding twice (the turns alone agree), an open rim
// over one and a half turns (the winding count alone is one), a folded star, the half-open ray
// rule's boundary (rim corners exactly on the centre's horizontal), clockwise fans (the mirrored
// count), nearly flat fans (turns along x and y from differences of a few ulps), and a triangle
// whose turns the filter cannot decide (differences that round). Every pair against faceContact,
// one at a time and by batch, then end to end with stored and computed planes; and each kind
// certified or not as it should be (stars are, so that the skip is exercised at all).
TEST(OracleNarrowPhase, CertifiedFansMeetOnlyAtTheirVertex) {
    std::vector<uint32_t> centres;
    std::vector<Fan> kinds;
    const Mesh m = fanMesh(3, centres, kinds);
    const uint32_t n = uint32_t(m.triangles.size());
    std::vector<detail::Prim> prims(n);
    std::vector<detail::Plane> planes(n);
    for (uint32_t t = 0; t < n; ++t) {
        detail::Prim& p = prims[t];
        const Vec3f &p0 = m.positions[m.triangles[t][0]], &p1 = m.positions[m.triangles[t][1]],
                    &p2 = m.positions[m.triangles[t][2]];
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) p.p[k][c] = m.positions[m.triangles[t][k]][c];
        p.v = m.triangles[t];
        p.triangle = t;
        planes[t] = detail::planeOf(p);
        p.turns = detail::projectedTurns(p0, p1, p2, planes[t]);
        EXPECT_EQ(p.turns, detail::projectedTurnsExact(p0, p1, p2, planes[t])) << t;
    }
    // The turns' filter is not trusted where it cannot decide: exactly collinear corners whose
    // differences round in doubles (DegenerateTrianglesAreListedNotPaired's), the third moved off
    // the line along z only, so that the image along z is still a segment.
    {
        const Vec3f q0(0x1.23eeap-24f, 0x1.b5e5fp-23f, 0x1.6cea48p-22f),
            q1(0x1.b262cp+17f, 0x1.45ca1p+19f, 0x1.0f7db8p+20f),
            q2(0x1.0630cp+15f, 0x1.89492p+16f, std::nextafter(0x1.47bcfp+17f, 1e30f));
        const uint8_t turns = detail::projectedTurns(q0, q1, q2, detail::planeOf(q0, q1, q2));
        EXPECT_EQ(turns, detail::projectedTurnsExact(q0, q1, q2, detail::planeOf(q0, q1, q2)));
        EXPECT_EQ(turns & 0x24, 0);  // edge-on along z
        EXPECT_NE(turns & 0x1b, 0);  // not along x and y
    }
    detail::certifyFans(prims, m.positions.size(), nullptr);
    // Each centre certified (in every triangle of its fan) or not, as its kind says.
    for (size_t f = 0; f < centres.size(); ++f) {
        int certified = 0, fan = 0;
        for (const detail::Prim& p : prims)
            for (int c = 0; c < 3; ++c)
                if (p.v[c] == centres[f]) ++fan, certified += p.fans >> c & 1;
        const bool expected = kinds[f] == Fan::Star || kinds[f] == Fan::FlatStar;
        if (kinds[f] != Fan::Folded) EXPECT_EQ(certified, expected ? fan : 0) << "fan " << f;
        else EXPECT_TRUE(certified == 0 || certified == fan) << "fan " << f;
    }
    // No rim vertex (two triangles) is certified.
    for (const detail::Prim& p : prims)
        for (int c = 0; c < 3; ++c)
            if (std::find(centres.begin(), centres.end(), p.v[c]) == centres.end()) {
                EXPECT_FALSE(p.fans >> c & 1);
            }
    // Every pair, one at a time and by batch, against faceContact.
    auto pts = [&](uint32_t t) {
        const Triangle& i = m.triangles[t];
        return TrianglePoints{m.positions[i[0]].cast<double>(), m.positions[i[1]].cast<double>(),
                              m.positions[i[2]].cast<double>()};
    };
    std::vector<detail::Candidate> pairs;
    std::vector<std::pair<uint32_t, Contact>> expected;
    std::vector<IntersectingPair> expectedPairs;
    int skipped = 0;
    for (uint32_t a = 0; a < n; ++a)
        for (uint32_t b = a + 1; b < n; ++b) {
            const Contact c = faceContact(pts(a), m.triangles[a], pts(b), m.triangles[b], true);
            EXPECT_EQ(detail::primContact(prims[a], planes[a], prims[b], &planes[b], true), c) << a << " " << b;
            if (c != Contact::None) {
                expected.emplace_back(uint32_t(pairs.size()), c);
                expectedPairs.push_back({0, a, 0, b, c == Contact::Crossing ? X : T});
            }
            skipped += (prims[a].fans & 7) != 0 && c == Contact::None;
            pairs.push_back({0, a, 0, b});
        }
    // Both answers occur (the wound and open fans' inner turns cross their outer ones).
    EXPECT_GT(std::count_if(expected.begin(), expected.end(), [](auto& e) { return e.second == Contact::Crossing; }),
              20);
    EXPECT_GT(skipped, 200);
    const detail::StoredPrims stored[1] = {{prims.data(), planes.data()}};
    std::vector<detail::Hit> hits(pairs.size());
    size_t tested = 0;
    const uint32_t found = detail::primContacts(stored, pairs.data(), uint32_t(pairs.size()), hits.data(), tested);
    std::vector<std::pair<uint32_t, Contact>> got;
    for (uint32_t h = 0; h < found; ++h) got.emplace_back(hits[h].pair, hits[h].contact);
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected);
    EXPECT_EQ(tested, pairs.size());
    // End to end: the setup's turns and fans, both narrow-phase paths.
    const size_t saved = detail::storedPlanesMax;
    for (const size_t max : {~size_t(0), size_t(0)}) {
        detail::storedPlanesMax = max;
        EXPECT_EQ(findIntersections(sceneOf({m})).pairs, expectedPairs) << "stored planes up to " << max;
    }
    detail::storedPlanesMax = saved;
}

// Trap: a Workspace keeps the previous call's arrays; a call that reads one of them stale (a
// plane or record left from a larger scene, the grid's cell starts or entries not reset, the
// planes of a scene that stores them read by one that does not, another object's world
// positions) gives other pairs or counts than a fresh call. One workspace through scenes that
// grow, shrink, change their number of objects, the exact stage on a subset, the welding option,
// Embree's broad phase and a release, each against the same call without a workspace.
TEST(Oracle, WorkspaceReuseGivesTheSameTruth) {
    const Mesh cow = bundled("cow.off");
    // Under the sanitizers the cow stands in for the subdivided cow (23k triangles, a few seconds
    // there); the calls still grow and shrink (one cow, two, one).
    const Mesh subdivided = CULLIDE_SANITIZED ? cow : subdivide(cow);
    Scene two = sceneOf({cow, cow});
    two.objects[1].transform.translate(Vec3f(0.25f, 0.02f, 0.05f));
    SceneRequest req;
    req.triangles = 6000;
    const Scene generated = makeTwoCows(cow, req).scene;
    const std::vector<TriangleRef> pcs = thinnedPcs(two);
    const OracleOptions weld = welded(), embree = withEmbree();
    const std::vector<std::function<Truth(Workspace*)>> calls = {
        [&](Workspace* w) { return findIntersections(sceneOf({subdivided}), {}, w); },
        [&](Workspace* w) { return findIntersections(sceneOf({cow}), {}, w); },
        [&](Workspace* w) { return findIntersections(two, {}, w); },
        [&](Workspace* w) { return exactStage(two, pcs, {}, w); },
        [&](Workspace* w) { return findIntersections(generated, weld, w); },
        [&](Workspace* w) { return findIntersections(sceneOf({subdivided}), embree, w); },
        [&](Workspace* w) {
            return findIntersections(sceneOf({subdivided, cow}), {}, w);
        },
        [&](Workspace* w) { return findIntersections(sceneOf({cow}), {}, w); },
    };
    Workspace workspace;
    for (int round = 0; round < 2; ++round) {
        for (size_t k = 0; k < calls.size(); ++k) {
            const Truth fresh = calls[k](nullptr), reused = calls[k](&workspace);
            EXPECT_FALSE(fresh.pairs.empty()) << k;
            EXPECT_EQ(reused.pairs, fresh.pairs) << "call " << k << ", round " << round;
            EXPECT_EQ(reused.degenerate, fresh.degenerate) << k;
            EXPECT_EQ(reused.trianglesTested, fresh.trianglesTested) << k;
            EXPECT_EQ(reused.candidatePairs, fresh.candidatePairs) << k;
        }
        workspace.release();  // the second round starts from nothing again
    }
}

// Trap: without a Workspace a call takes its arrays from its own PageArena, handed out in order
// from shared 2 MiB chunks; one that overlaps another (the chunk's position not advanced, a
// freed array's space taken back while a later one still lives there, the alignment of the
// 64-byte records lost), or one freed through the wrong allocator, gives other pairs or counts
// than malloc's arrays (or a crash). Each call with the arena forced on and off: one object and
// several (arrays freed in the middle: world positions, the kept triangles), the exact stage,
// welding, the Morton order's keys (spatialOrderMin lowered), Embree's broad phase.
TEST(Oracle, CallArenaGivesTheSameTruth) {
    const Mesh cow = bundled("cow.off");
    const Mesh subdivided = CULLIDE_SANITIZED ? cow : subdivide(cow);
    Scene two = sceneOf({cow, subdivided, cow});
    two.objects[1].transform.translate(Vec3f(0.25f, 0.02f, 0.05f));
    two.objects[2].transform.translate(Vec3f(-0.2f, 0.05f, 0.0f));
    const std::vector<TriangleRef> pcs = thinnedPcs(two);
    const OracleOptions weld = welded(), embree = withEmbree();
    const std::vector<std::function<Truth()>> calls = {
        [&] { return findIntersections(sceneOf({subdivided})); },
        [&] { return findIntersections(two); },
        [&] { return exactStage(two, pcs); },
        [&] { return findIntersections(two, weld); },
        [&] { return findIntersections(two, embree); },
        [&] {
            const size_t keep = detail::spatialOrderMin;
            detail::spatialOrderMin = 0;
            Truth t = findIntersections(two);
            detail::spatialOrderMin = keep;
            return t;
        },
    };
    const detail::CallArena keep = detail::callArena;
    for (size_t k = 0; k < calls.size(); ++k) {
        detail::callArena = detail::CallArena::Never;
        const Truth plain = calls[k]();
        detail::callArena = detail::CallArena::Always;
        const Truth arena = calls[k]();
        EXPECT_FALSE(plain.pairs.empty()) << k;
        EXPECT_EQ(arena.pairs, plain.pairs) << "call " << k;
        EXPECT_EQ(arena.degenerate, plain.degenerate) << k;
        EXPECT_EQ(arena.trianglesTested, plain.trianglesTested) << k;
        EXPECT_EQ(arena.candidatePairs, plain.candidatePairs) << k;
    }
    detail::callArena = keep;
}

}  // namespace
}  // namespace cullide::oracle
