// Tests for oracle/src/oracle.cpp (and the sharing rules of cullide/predicates.h, end to end):
// hand-built traps, determinism across thread counts, the exact stage, bad input, the setup's
// paths (Morton order, stored planes) and its memory (a Workspace, the call's own arena). The
// broad phase: broad_phase_test.cpp; the narrow phase's batches and fans: narrow_phase_test.cpp;
// the cross-check with CGAL: cgal_reference_test.cpp.
#include "cullide/oracle/oracle.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/predicates.h"

#include "oracle_test_util.h"
#include "test_util.h"

#include "../oracle/src/narrow_phase.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

namespace cullide::oracle {
namespace {

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
