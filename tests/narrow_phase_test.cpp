// Tests for the oracle's narrow phase (oracle/src/narrow_phase.cpp): the batches in sharing
// classes against one pair at a time, and the certified fans against faceContact.
#include "cullide/oracle/oracle.h"

#include "cullide/predicates.h"

#include "oracle_test_util.h"
#include "test_util.h"

#include "../oracle/src/narrow_phase.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace cullide::oracle {
namespace {

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

}  // namespace
}  // namespace cullide::oracle
