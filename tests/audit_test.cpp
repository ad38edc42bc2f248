// The audit: a pair list judged against the oracle's truth, each missed and spurious pair with the
// first cause that holds (audit.h).
#include "cullide/oracle/audit.h"

#include "cullide/error.h"

#include "oracle_test_util.h"

#include <gtest/gtest.h>

#include <vector>

using namespace cullide;
using namespace cullide::oracle;

namespace {

// One triangle (a, b, c).
Mesh tri(Vec3f a, Vec3f b, Vec3f c) {
    return meshOf({a, b, c}, {{0, 1, 2}});
}

// A right triangle with legs `leg` in the plane z = 0 at (x, 0).
Mesh floorAt(float x, float leg = 2) {
    return tri({x, 0, 0}, {x + leg, 0, 0}, {x, leg, 0});
}

// A vertical triangle in the plane x = xv whose tip, at y = 1, reaches down to z = -below and
// whose top edge is at z = above: through a floor at (x < xv) it has the penetration depth
// min(below, above).
Mesh spike(float xv, float below, float above) {
    return tri({xv, 1, -below}, {xv, 0.5f, above}, {xv, 1.5f, above});
}

TriangleRef ref(uint32_t object, uint32_t triangle = 0) {
    return {object, triangle};
}

TrianglePair pairOf(uint32_t oa, uint32_t ta, uint32_t ob, uint32_t tb) {
    return TrianglePair::make(ref(oa, ta), ref(ob, tb));
}

// Each object (or two) gives one case, far from the others (10 apart in x).
//   0: a fold (triangles 0, 1 share an edge, coplanar, folded over: intersecting), and triangle 2
//      hinged on triangle 0's edge (shares it with 0, a vertex with 1: neither intersects)
//   1: two triangles sharing a vertex, the second through the first's opposite edge (crossing)
//   2, 3: coplanar overlap (touching); 4, 5: a corner on a face (touching)
//   6, 7: crossing 1e-4 deep; 8, 9: crossing 0.25 deep
//   10: a degenerate triangle and a good one; 12, 13: coplanar, 1e-4 apart; 14, 15: 1e-4 apart
//   16, 17: two faces of a thin solid, 0.5 apart, facing away from each other (each behind the other)
Scene auditScene() {
    std::vector<Mesh> m;
    m.push_back(meshOf({{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, 0.5f, 0}, {1, 1, 1}}, {{0, 1, 2}, {0, 1, 3}, {1, 2, 4}}));
    m.push_back(meshOf({{10, 0, 0}, {12, 0, 0}, {10, 2, 0}, {11.5f, 1.5f, -1}, {11.5f, 1.5f, 1}}, {{0, 1, 2}, {0, 3, 4}}));
    m.push_back(floorAt(20));
    m.push_back(tri({20.5f, 0.5f, 0}, {22.5f, 0.5f, 0}, {20.5f, 2.5f, 0}));
    m.push_back(floorAt(30));
    m.push_back(tri({30.5f, 0.5f, 0}, {31, 0.5f, 1}, {30.5f, 1, 1}));
    m.push_back(floorAt(40, 4));
    m.push_back(spike(41, 1e-4f, 3));
    m.push_back(floorAt(50, 4));
    m.push_back(spike(51, 0.25f, 3));
    m.push_back(meshOf({{60, 0, 0}, {61, 0, 0}, {62, 0, 0}, {60, 0, 1}, {61, 0, 1}, {60, 1, 1}}, {{0, 1, 2}, {3, 4, 5}}));
    m.push_back(floorAt(65));
    m.push_back(floorAt(70));
    m.push_back(tri({72.0001f, 0, 0}, {74, 0, 0}, {72.0001f, 2, 0}));
    m.push_back(floorAt(80));
    m.push_back(tri({80.5f, 0.5f, 1e-4f}, {81, 0.5f, 1}, {80.5f, 1, 1}));
    m.push_back(floorAt(90));
    m.push_back(tri({90.5f, 0.5f, -0.5f}, {90.5f, 1, -0.5f}, {91, 0.5f, -0.5f}));
    return sceneOf(std::move(m));
}

std::vector<TrianglePair> pairsOfTruth(const Truth& t) {
    std::vector<TrianglePair> out;
    for (const IntersectingPair& p : t.pairs) out.push_back({p.a(), p.b()});
    return out;
}

AuditOptions withTolerance(double tolerance, bool selfPairsTested = true) {
    AuditOptions o;
    o.tolerance = tolerance;
    o.selfPairsTested = selfPairsTested;
    return o;
}

}  // namespace

// Trap: the fixture must hold the pairs the other cases count on; the truth's own list, reversed
// within pairs and given twice, must agree (pairs are unordered, duplicates counted once).
TEST(Audit, TheTruthsOwnListAgrees) {
    const Scene s = auditScene();
    const Truth t = findIntersections(s);
    const std::vector<TrianglePair> expected = {pairOf(0, 0, 0, 1), pairOf(1, 0, 1, 1), pairOf(2, 0, 3, 0),
                                                pairOf(4, 0, 5, 0), pairOf(6, 0, 7, 0), pairOf(8, 0, 9, 0)};
    ASSERT_EQ(pairsOfTruth(t), expected);
    ASSERT_EQ(t.degenerate, std::vector<TriangleRef>{ref(10, 0)});
    std::vector<TrianglePair> list = expected;
    for (const TrianglePair& p : expected) list.push_back({p.b, p.a});
    const Audit a = audit(s, t, list);
    EXPECT_TRUE(a.agrees());
    EXPECT_EQ(a.reported, 6u);
    EXPECT_EQ(a.found, 6u);
}

// Trap: every disagreement must get the first cause that holds, not a later one (a fold is
// coplanar and touching, but it is missed because it shares an edge; a degenerate triangle's pair
// is not judged by distance), and the distances must be the ones each cause is decided on.
TEST(Audit, RemovedAndAddedPairsReportedWithTheirCauses) {
    const Scene s = auditScene();
    const Truth t = findIntersections(s);
    const std::vector<TrianglePair> list = {pairOf(0, 0, 0, 2),   pairOf(0, 1, 0, 2),   pairOf(10, 0, 10, 1),
                                            pairOf(12, 0, 13, 0), pairOf(14, 0, 15, 0), pairOf(2, 0, 11, 0),
                                            pairOf(16, 0, 17, 0)};
    const Audit a = audit(s, t, list, withTolerance(1e-3));
    EXPECT_EQ(a.found, 0u);
    const std::vector<std::pair<TrianglePair, AuditCause>> missed = {
        {pairOf(0, 0, 0, 1), AuditCause::SharedEdge}, {pairOf(1, 0, 1, 1), AuditCause::SharedVertex},
        {pairOf(2, 0, 3, 0), AuditCause::Coplanar},   {pairOf(4, 0, 5, 0), AuditCause::Touching},
        {pairOf(6, 0, 7, 0), AuditCause::WithinTolerance}, {pairOf(8, 0, 9, 0), AuditCause::Unexplained}};
    ASSERT_EQ(a.missed.size(), missed.size());
    for (size_t i = 0; i < missed.size(); ++i) {
        EXPECT_EQ(a.missed[i].pair, missed[i].first) << i;
        EXPECT_EQ(a.missed[i].cause, missed[i].second) << i;
    }
    EXPECT_EQ(a.missedByClass[size_t(PairClass::Crossing)], 3u);
    EXPECT_NEAR(a.missed[4].distance, 1e-4, 1e-8);
    EXPECT_DOUBLE_EQ(a.missed[5].distance, 0.25);
    const std::vector<std::pair<TrianglePair, AuditCause>> spurious = {
        {pairOf(0, 0, 0, 2), AuditCause::SharedEdge},   {pairOf(0, 1, 0, 2), AuditCause::SharedVertex},
        {pairOf(2, 0, 11, 0), AuditCause::Unexplained}, {pairOf(10, 0, 10, 1), AuditCause::Degenerate},
        {pairOf(12, 0, 13, 0), AuditCause::Coplanar},   {pairOf(14, 0, 15, 0), AuditCause::WithinTolerance},
        {pairOf(16, 0, 17, 0), AuditCause::BehindFace}};
    ASSERT_EQ(a.spurious.size(), spurious.size());
    for (size_t i = 0; i < spurious.size(); ++i) {
        EXPECT_EQ(a.spurious[i].pair, spurious[i].first) << i;
        EXPECT_EQ(a.spurious[i].cause, spurious[i].second) << i;
    }
    EXPECT_NEAR(a.spurious[4].distance, 1e-4, 1e-5);
    EXPECT_NEAR(a.spurious[5].distance, 1e-4, 1e-8);
    EXPECT_EQ(a.missedBy[size_t(AuditCause::SharedEdge)], 1u);
    EXPECT_EQ(a.spuriousBy[size_t(AuditCause::Unexplained)], 1u);
}

// Trap: a list that tests no self pairs misses them for that reason first (before sharing); pairs
// between objects keep their causes, and a tolerance of 0 leaves the shallow crossing unexplained.
TEST(Audit, SelfPairsOfAListThatTestsNoneAreUntested) {
    const Scene s = auditScene();
    const Audit a = audit(s, findIntersections(s), {}, withTolerance(0, false));
    ASSERT_EQ(a.missed.size(), 6u);
    EXPECT_EQ(a.missed[0].cause, AuditCause::Untested);
    EXPECT_EQ(a.missed[1].cause, AuditCause::Untested);
    EXPECT_EQ(a.missed[2].cause, AuditCause::Coplanar);
    EXPECT_EQ(a.missed[4].cause, AuditCause::Unexplained);
    EXPECT_EQ(a.missedBy[size_t(AuditCause::Untested)], 2u);
}

// Trap: the penetration depth is the shortest way out, not the way along a normal: a spike 1 deep
// below the floor and 0.5 above it comes out upward by 0.5 (worked by hand: the floor's normal
// gives min(1, 0.5); every other way is longer, the floor reaching 0.67 beyond the spike sideways).
TEST(Audit, PenetrationDepthIsTheShortestWayOut) {
    const Scene s = sceneOf({floorAt(0, 4), spike(1, 1, 0.5f)});
    const Audit a = audit(s, findIntersections(s), {});
    ASSERT_EQ(a.missed.size(), 1u);
    EXPECT_EQ(a.missed[0].cls, PairClass::Crossing);
    EXPECT_DOUBLE_EQ(a.missed[0].distance, 0.5);
}

// Trap: a pair naming a triangle the scene lacks, or a triangle with itself, must be refused with
// the pair's index and the source, not read out of bounds or counted.
TEST(Audit, BadPairsAreRefused) {
    const Scene s = sceneOf({floorAt(0), floorAt(5)});
    const Truth t = findIntersections(s);
    AuditOptions o;
    o.source = "list.csv";
    const auto message = [&](std::vector<TrianglePair> list) {
        try {
            (void)audit(s, t, list, o);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_EQ(message({pairOf(0, 0, 1, 0), pairOf(0, 0, 1, 1)}), "list.csv: pair 1: object 1 has no triangle 1");
    EXPECT_EQ(message({pairOf(0, 0, 2, 0)}), "list.csv: pair 0: the scene has no object 2 (it has 2)");
    EXPECT_EQ(message({pairOf(1, 0, 1, 0)}), "list.csv: pair 0 pairs a triangle with itself");
    o.tolerance = -1;
    EXPECT_EQ(message({}), "list.csv: tolerance -1 is not a distance (>= 0)");
}
