// Tests for mesh_stats: counts on hand-built meshes, and degeneracy decided exactly.
#include "cullide/mesh_io.h"
#include "cullide/mesh_stats.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace cullide {
namespace {

using test::testData;

// Trap: duplicates decided by value (== would merge -0.0 and 0.0) or by a hash map's order;
// duplicate triangles that differ only in orientation; unreferenced vertices counted in bounds.
TEST(MeshStats, CountsDuplicatesUnreferencedAndBoundsOnDupVertsFile) {
    const MeshStats s = computeStats(loadMesh(testData("good/dup_verts.off")));
    EXPECT_EQ(s.vertices, 6u);
    EXPECT_EQ(s.triangles, 3u);
    EXPECT_EQ(s.duplicateVertices, 2u);  // 3 repeats 0, 5 repeats 1; 4 is -0.0 (other bits)
    EXPECT_EQ(s.duplicateTriangles, 1u);  // (2 1 0) is (0 1 2) reversed
    EXPECT_EQ(s.unreferencedVertices, 1u);
    EXPECT_EQ(s.components, 1u);  // triangle 1 shares vertex 2 with triangle 0
    EXPECT_EQ(s.degenerateTriangles, 0u);
    EXPECT_EQ(s.bounds.lo, Vec3f(0, 0, 0));
    EXPECT_EQ(s.bounds.hi, Vec3f(1, 1, 0));
}

// Trap: an epsilon test. Repeated index, coincident corners and exactly collinear corners are
// degenerate; (0,0,0) (1,1,1) (2,2,2.00000024) is not, though any tolerance would say so.
TEST(MeshStats, DegenerateTrianglesOnDegenerateFile) {
    const Mesh m = loadMesh(testData("good/degenerate.off"));
    const bool expected[] = {false, true, true, true, false};
    ASSERT_EQ(m.triangleCount(), std::size(expected));
    for (size_t i = 0; i < m.triangleCount(); ++i) EXPECT_EQ(isDegenerate(m, i), expected[i]) << "triangle " << i;
    const MeshStats s = computeStats(m);
    EXPECT_EQ(s.degenerateTriangles, 3u);
    EXPECT_EQ(s.unreferencedVertices, 2u);
    EXPECT_EQ(s.components, 1u);
}

// Trap: floating-point cross products that round to zero or away from it. Points on a small
// integer grid, scaled by 2^-29 and offset by 2^-6 (all exact in float), are collinear exactly
// when the integer cross product is zero; 2000 random triangles with a fixed seed.
TEST(MeshStats, CollinearityIsExactAgainstIntegerCrossProduct) {
    std::mt19937 rng(42);
    const float scale = std::ldexp(1.0f, -29);
    size_t degenerate = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        long long q[3][3];
        Mesh m;
        for (auto& p : q) {
            for (long long& c : p) c = static_cast<long long>(rng() % 3) * 4194301;  // < 2^23: exact in float
            m.positions.push_back(
                Vec3f(float(p[0]) * scale + 0.015625f, float(p[1]) * scale, float(p[2]) * scale - 0.015625f));
        }
        m.triangles = {{0, 1, 2}};
        const long long u[3] = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
        const long long v[3] = {q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
        const bool collinear =
            u[1] * v[2] - u[2] * v[1] == 0 && u[2] * v[0] - u[0] * v[2] == 0 && u[0] * v[1] - u[1] * v[0] == 0;
        // q * 2^-29 < 2^-6 has no bits below 2^-29, nor has the sum with 2^-6: all exact.
        EXPECT_EQ(isDegenerate(m, 0), collinear) << "trial " << trial;
        degenerate += collinear;
    }
    EXPECT_GT(degenerate, 20u);  // the grid is coarse enough that both answers occur
}

// Trap: components counted over all vertices (unreferenced ones would count as components) or
// over positions (a soup with duplicated vertices must fall apart: that is what its indices say).
TEST(MeshStats, ComponentsFollowIndicesNotPositions) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {9, 9, 9}};
    m.triangles = {{0, 1, 2}, {3, 5, 4}};  // same corners by position, separate by index
    MeshStats s = computeStats(m);
    EXPECT_EQ(s.components, 2u);
    EXPECT_EQ(s.unreferencedVertices, 1u);
    EXPECT_EQ(s.duplicateVertices, 2u);
    EXPECT_EQ(s.bounds.hi, Vec3f(1, 1, 0));  // the unreferenced (9,9,9) is not in the bounds
    m.triangles.push_back({2, 6, 4});  // bridges them
    s = computeStats(m);
    EXPECT_EQ(s.components, 1u);
    EXPECT_EQ(s.unreferencedVertices, 0u);
}

// Trap: results that depend on iteration order of hash containers or on earlier calls.
TEST(MeshStats, IsDeterministic) {
    const Mesh m = loadMesh(testData("good/cube_binary.stl"));
    const MeshStats a = computeStats(m), b = computeStats(m);
    EXPECT_EQ(a.components, 1u);
    EXPECT_EQ(a.duplicateVertices, 0u);  // welded on load
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.components, b.components);
    EXPECT_EQ(a.duplicateVertices, b.duplicateVertices);
    EXPECT_EQ(a.duplicateTriangles, b.duplicateTriangles);
    EXPECT_EQ(a.degenerateTriangles, b.degenerateTriangles);
}

}  // namespace
}  // namespace cullide
