// Tests for tools/study/src/measures.cpp: false prunes by class, false positives, efficiency, and the
// per-pair explanations (penetration along a direction, pixel centres, edge-on).
#include "cullide/study/measures.h"

#include "cullide/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cullide::study {
namespace {

using namespace cullide::oracle;

// Object 0: a big triangle in z = 0. Object 1: a triangle in the plane z = x that passes through
// it, reaching 0.5 below and 0.5 above it (seen along z). Object 2: a triangle touching object
// 0's face with one corner. Object 3: far away, touching nothing.
Scene crossingScene() {
    Scene s;
    auto add = [&](std::vector<Vec3f> p) {
        s.objects.push_back({std::string("o").append(std::to_string(s.objects.size())), Mesh{std::move(p), {{0, 1, 2}}},
                             Transform::Identity()});
    };
    add({{-1, -1, 0}, {3, -1, 0}, {-1, 3, 0}});
    add({{-0.5f, 0, -0.5f}, {0.5f, -0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}});
    add({{1, 1, 0}, {1.5f, 1, 1}, {1, 1.5f, 1}});
    add({{10, 10, 10}, {11, 10, 10}, {10, 11, 10}});
    return s;
}

CullideOptions zOnly(int resolution) {
    CullideOptions o;
    o.directions = {Vec3d(0, 0, 1), Vec3d(1, 0, 0)};
    o.width = o.height = resolution;
    return o;
}

// Trap: a PCS that holds every triangle has no false prune whatever the truth; the far triangle
// is a false positive.
TEST(Measures, FullPcsHasNoFalsePrune) {
    const Scene s = crossingScene();
    const Truth t = findIntersections(s);
    ASSERT_EQ(t.pairs.size(), 2u);
    EXPECT_EQ(t.pairs[0], (IntersectingPair{0, 0, 1, 0, PairClass::Crossing}));
    EXPECT_EQ(t.pairs[1], (IntersectingPair{0, 0, 2, 0, PairClass::Touching}));
    const std::vector<PcsTriangle> all{{0, 0}, {1, 0}, {2, 0}, {3, 0}};
    const PcsReport r = measurePcs(s, t, all, zOnly(64));
    EXPECT_EQ(r.falsePruneCount(), 0u);
    EXPECT_EQ(r.falsePositives, 1u);
    EXPECT_EQ(r.collidingTriangles, 3u);
    EXPECT_DOUBLE_EQ(r.efficiency, 0.75);
    EXPECT_TRUE(r.missed.empty());
}

// Trap: a triangle in a crossing pair and a touching pair counts as a crossing false prune; the
// touching partner only as touching. Duplicated PCS entries count once.
TEST(Measures, FalsePrunesByClass) {
    const Scene s = crossingScene();
    const Truth t = findIntersections(s);
    const std::vector<PcsTriangle> pcs{{3, 0}, {3, 0}};
    const PcsReport r = measurePcs(s, t, pcs, zOnly(64));
    EXPECT_EQ(r.pcsTriangles, 1u);
    EXPECT_EQ(r.falsePrunes[size_t(PairClass::Crossing)], 2u);  // objects 0 and 1
    EXPECT_EQ(r.falsePrunes[size_t(PairClass::Touching)], 1u);  // object 2
    EXPECT_EQ(r.missedPairs[size_t(PairClass::Crossing)], 1u);
    EXPECT_EQ(r.missedPairs[size_t(PairClass::Touching)], 1u);
    EXPECT_EQ(r.missedSelfPairs[0] + r.missedSelfPairs[1], 0u);
    EXPECT_EQ(r.falsePositives, 1u);
    EXPECT_DOUBLE_EQ(r.efficiency, 0.0);
    ASSERT_EQ(r.missed.size(), 2u);
    EXPECT_TRUE(r.missed[0].missingA && r.missed[0].missingB);
}

// The explanation of the crossing pair: along z, each reaches 0.5 behind the other (a depth
// test sees it); along x the big triangle is edge-on (no depth function: NaN, no pixel centre).
TEST(Measures, PenetrationPixelCentreAndEdgeOn) {
    const Scene s = crossingScene();
    const Truth t = findIntersections(s);
    const CullideOptions o = zOnly(64);
    const PcsReport r = measurePcs(s, t, std::vector<PcsTriangle>{}, o);
    const MissedPair& m = r.missed[0];
    ASSERT_EQ(m.directions.size(), 2u);
    EXPECT_NEAR(m.directions[0].penetration, 0.5, 1e-12);
    EXPECT_TRUE(m.directions[0].pixelCentre);
    EXPECT_GT(m.directions[0].depthUnit, 0);
    EXPECT_LT(m.directions[0].depthUnit, 1e-5);  // whole-scene depth extent (10) / 2^24
    EXPECT_TRUE(std::isnan(m.directions[1].penetration));
    EXPECT_FALSE(m.directions[1].pixelCentre);
    EXPECT_DOUBLE_EQ(m.edgeOnA, 0.0);  // the z = 0 triangle, seen along x
    EXPECT_NEAR(m.edgeOnB, std::sqrt(0.5), 1e-12);  // the z = x triangle: 45 degrees to both
    // The touching pair: the corner on the face does not reach behind it.
    EXPECT_LE(r.missed[1].directions[0].penetration, 1e-12);
}

// Trap: an overlap smaller than a pixel that misses every pixel centre. At 2x2 pixels over the
// whole scene (11 units), the crossing's projected overlap (1 x 1 unit near the origin) holds no
// pixel centre; at 64x64 it does.
TEST(Measures, SmallOverlapMissesPixelCentres) {
    const Scene s = crossingScene();
    const Truth t = findIntersections(s);
    EXPECT_FALSE(measurePcs(s, t, std::vector<PcsTriangle>{}, zOnly(2)).missed[0].directions[0].pixelCentre);
    EXPECT_TRUE(measurePcs(s, t, std::vector<PcsTriangle>{}, zOnly(64)).missed[0].directions[0].pixelCentre);
}

TEST(Measures, RefusesPcsEntriesOutsideTheScene) {
    const Scene s = crossingScene();
    const Truth t = findIntersections(s);
    EXPECT_THROW(measurePcs(s, t, std::vector<PcsTriangle>{{4, 0}}, zOnly(8)), InputError);
    EXPECT_THROW(measurePcs(s, t, std::vector<PcsTriangle>{{0, 1}}, zOnly(8)), InputError);
}

}  // namespace
}  // namespace cullide::study
