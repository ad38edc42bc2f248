// Near contacts: pairs within a distance that do not intersect, and the triangle distance behind them.
#include "cullide/oracle/near_contacts.h"

#include "cullide/error.h"

#include "oracle_test_util.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>

using namespace cullide;
using namespace cullide::oracle;

namespace {

// A unit right triangle in the plane z, shifted by (dx, dy).
Mesh flatTriangle(float z, float dx = 0, float dy = 0) {
    return meshOf({{dx, dy, z}, {dx + 1, dy, z}, {dx, dy + 1, z}}, {{0, 1, 2}});
}

NearContacts near(const Scene& s, double d) {
    return countNearContacts(s, findIntersections(s), d);
}

}  // namespace

// Trap: the boxes must grow by the whole distance between them (half on each side): two parallel
// triangles 0.25 apart are a near contact at 0.25 and above, not at 0.2.
TEST(NearContacts, ParallelLayersCountFromTheirGapOn) {
    const Scene s = sceneOf({flatTriangle(0), flatTriangle(0.25f)});
    EXPECT_EQ(near(s, 0.2).total(), 0u);
    EXPECT_EQ(near(s, 0.25).objectPairs, 1u);
    EXPECT_EQ(near(s, 1.0).objectPairs, 1u);
    EXPECT_EQ(near(s, 1.0).selfPairs, 0u);
}

// Trap: a pair the oracle finds intersecting is a contact, not a near contact, however close; and
// two triangles of one mesh that share a vertex always touch, so they are not counted either,
// while the same mesh's non-neighbours within the distance are (self pairs).
TEST(NearContacts, IntersectingPairsAndNeighboursAreNotNearContacts) {
    const Mesh crossing = meshOf({{0, 0, -1}, {1, 0, 1}, {0, 1, 0}}, {{0, 1, 2}});
    EXPECT_EQ(near(sceneOf({flatTriangle(0, -0.2f, -0.2f), crossing}), 10.0).total(), 0u);

    // A strip of two triangles sharing an edge, and a third one 0.1 above the first, apart from both.
    const Mesh strip = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.1f, 0.1f, 0.1f}, {0.3f, 0.1f, 0.1f},
                               {0.1f, 0.3f, 0.1f}},
                              {{0, 1, 2}, {1, 3, 2}, {4, 5, 6}});
    const NearContacts n = near(sceneOf({strip}), 0.15);
    EXPECT_EQ(n.selfPairs, 1u);  // (0, 2): 0.1 apart; (1, 2) is farther than 0.15; (0, 1) share an edge
    EXPECT_EQ(n.objectPairs, 0u);
}

// Trap: the distance of non-intersecting triangles is reached between two edges (skew, crossing
// over each other), at a corner over a face, or corner to corner: all three must be looked at.
TEST(NearContacts, TriangleDistanceFindsEdgeFaceAndCornerCases) {
    // Edge-edge: a's edge along x at z = 0, b's edge along y at z = 0.5, crossing above it.
    EXPECT_NEAR(triangleDistance({-1, 0, 0}, {1, 0, 0}, {0, -1, -1}, {0, -1, 0.5}, {0, 1, 0.5}, {0, 0, 2}), 0.5,
                1e-12);
    // Corner over a face: b's lowest corner 0.3 above the middle of a.
    EXPECT_NEAR(triangleDistance({0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 0.3}, {0.5, 0.5, 2}, {1, 0.5, 2}), 0.3,
                1e-12);
    // Corner to corner: (1, 0, 0) to (2, 0, 0) is the closest, 1 apart.
    EXPECT_NEAR(triangleDistance({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {3, 0, 0}, {3, 1, 0}), 1.0, 1e-12);
}

// Trap: the count is summed from threads in no fixed order; it must not depend on their number.
TEST(NearContacts, CountDoesNotDependOnThreads) {
    const Scene s = sceneOf({bundled("bunny.off"), bundled("bunny.off")});
    Scene shifted = s;
    shifted.objects[1].transform = Transform(Eigen::Translation3f(0.002f, 0.001f, 0));
    const Truth truth = findIntersections(shifted);
    const double d = 0.003;
    NearContacts one;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = countNearContacts(shifted, truth, d);
    }
    const NearContacts all = countNearContacts(shifted, truth, d);
    EXPECT_GT(one.objectPairs, 0u);
    EXPECT_EQ(one.objectPairs, all.objectPairs);
    EXPECT_EQ(one.selfPairs, all.selfPairs);
}

// Trap: a negative, NaN or huge distance would grow boxes to nothing or overflow float: refused.
TEST(NearContacts, BadDistanceIsRefused) {
    const Scene s = sceneOf({flatTriangle(0)});
    const Truth t = findIntersections(s);
    EXPECT_THROW(countNearContacts(s, t, -1), InputError);
    EXPECT_THROW(countNearContacts(s, t, std::nan("")), InputError);
    EXPECT_THROW(countNearContacts(s, t, 1e30), InputError);
}
