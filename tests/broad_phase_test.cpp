// Tests for the oracle's broad phases (oracle/src/broad_phase.cpp, broad_phase_grid.cpp): both
// against all pairs, the boxes' outward rounding, the radix sort, and the grid's two paths (few
// and many cells) against Embree.
#include "cullide/oracle/oracle.h"

#include "cullide/predicates.h"

#include "oracle_test_util.h"

#include "../oracle/src/broad_phase.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <random>

namespace cullide::oracle {
namespace {

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

}  // namespace
}  // namespace cullide::oracle
