// Tests for core/src/predicates.cpp: the filtered orient3d and orient2d against CGAL's exact predicates, the
// triangle-triangle contact and its class against an exact-construction reference (Epeck), and
// the exact integer unit of float coordinates.
#include "cullide/predicates.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace cullide {
namespace {

using EK = CGAL::Exact_predicates_exact_constructions_kernel;

EK::Point_3 ep(const Vec3d& p) {
    return {p.x(), p.y(), p.z()};
}
EK::Triangle_3 et(const TrianglePoints& t) {
    return {ep(t[0]), ep(t[1]), ep(t[2])};
}

// Relative interior of a non-degenerate triangle: on it, and on none of its edges.
bool inRelativeInterior(const EK::Triangle_3& t, const EK::Point_3& p) {
    if (!t.has_on(p)) return false;
    for (int i = 0; i < 3; ++i)
        if (EK::Segment_3(t.vertex(i), t.vertex((i + 1) % 3)).has_on(p)) return false;
    return true;
}

// The definition, computed with exact constructions: None if no contact; Crossing iff not
// coplanar and the relative interiors meet (tested at the midpoint of the intersection
// segment, which lies in both relative interiors whenever they meet); else Touching.
Contact reference(const TrianglePoints& a, const TrianglePoints& b) {
    const EK::Triangle_3 ta = et(a), tb = et(b);
    if (!CGAL::do_intersect(ta, tb)) return Contact::None;
    bool coplanar = true;
    for (const Vec3d& p : b) coplanar = coplanar && CGAL::coplanar(ta.vertex(0), ta.vertex(1), ta.vertex(2), ep(p));
    if (coplanar) return Contact::Touching;
    const auto inter = CGAL::intersection(ta, tb);
    if (const EK::Segment_3* s = inter ? boost::get<EK::Segment_3>(&*inter) : nullptr) {
        const EK::Point_3 m = CGAL::midpoint(s->source(), s->target());
        if (inRelativeInterior(ta, m) && inRelativeInterior(tb, m)) return Contact::Crossing;
    }
    return Contact::Touching;
}

Vec3d v(double x, double y, double z) {
    return Vec3d(x, y, z);
}

// Trap: a float orient3d that returns a sign for points that are exactly coplanar, or zero for
// points a few ulps off the plane. Points on the plane x + y + z = 1 (exactly, in binary) and
// the same points nudged by one ulp; CGAL's exact predicate is the reference.
TEST(Predicates, Orient3dMatchesExactOnNearlyCoplanarPoints) {
    std::mt19937_64 rng(7);
    std::uniform_int_distribution<int> coord(-1 << 20, 1 << 20);
    int zeros = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        Vec3d p[4];
        for (Vec3d& q : p) {
            const double x = std::ldexp(double(coord(rng)), -20), y = std::ldexp(double(coord(rng)), -20);
            q = v(x, y, 1 - x - y);  // exact: small dyadic numbers
        }
        if (trial % 2) p[3].z() = std::nextafter(p[3].z(), trial % 4 == 1 ? 10.0 : -10.0);
        const auto e = CGAL::orientation(ep(p[0]), ep(p[1]), ep(p[2]), ep(p[3]));
        const int expected = e == CGAL::POSITIVE ? 1 : e == CGAL::NEGATIVE ? -1 : 0;
        ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), expected) << "trial " << trial;
        zeros += expected == 0;
    }
    EXPECT_GT(zeros, 5000);  // the coplanar half really was coplanar
}

// Trap: collinearity by a tolerance; coincident points; tiny and huge magnitudes.
TEST(Predicates, CollinearIsExact) {
    EXPECT_TRUE(collinear(v(0, 0, 0), v(1, 1, 1), v(2, 2, 2)));
    EXPECT_FALSE(collinear(v(0, 0, 0), v(1, 1, 1), v(2, 2, std::nextafter(2.0f, 3.0f))));
    EXPECT_TRUE(collinear(v(1, 2, 3), v(1, 2, 3), v(5, 6, 7)));
    EXPECT_TRUE(collinear(v(0x1p-140, 0, 0), v(0x1p-139, 0, 0), v(0x1p-138, 0, 0)));
    EXPECT_FALSE(collinear(v(0x1p-140, 0, 0), v(0x1p-139, 0, 0), v(0x1p-138, 0x1p-149, 0)));
    EXPECT_TRUE(collinear(v(0x1p59, 0x1p59, 0), v(-0x1p59, -0x1p59, 0), v(0, 0, 0)));
}

// Trap: orient2d on an axis pair (the oracle's fan turns): a float sign for points that are
// exactly collinear in the projection or a few ulps off it, the axes taken in the wrong order,
// and the three paths (filter, integers, CGAL for magnitudes the integers cannot hold). Points on
// the line x + y = 1 of the projection (exactly, in binary), nudged by one ulp in every other
// trial, each projection of the three axis pairs, against CGAL's exact orientation; then the
// sign of a counterclockwise triangle per axis pair, and magnitudes from 2^-140 to 2^59.
TEST(Predicates, Orient2dMatchesExactOnNearlyCollinearPoints) {
    std::mt19937_64 rng(9);
    std::uniform_int_distribution<int> coord(-1 << 20, 1 << 20);
    int zeros = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const int i = trial % 3, j = (i + 1) % 3, k = (i + 2) % 3;
        Vec3d p[3];
        for (Vec3d& q : p) {
            const double x = std::ldexp(double(coord(rng)), -20);
            q[i] = x, q[j] = 1 - x, q[k] = double(coord(rng));  // exact: small dyadic numbers
        }
        if (trial % 2) p[2][j] = std::nextafter(p[2][j], trial % 4 == 1 ? 10.0 : -10.0);
        using P2 = EK::Point_2;
        const auto e = CGAL::orientation(P2(p[0][i], p[0][j]), P2(p[1][i], p[1][j]), P2(p[2][i], p[2][j]));
        const int expected = e == CGAL::POSITIVE ? 1 : e == CGAL::NEGATIVE ? -1 : 0;
        ASSERT_EQ(orient2d(p[0], p[1], p[2], i, j), expected) << "trial " << trial;
        ASSERT_EQ(orient2d(p[0], p[1], p[2], j, i), -expected) << "trial " << trial;
        zeros += expected == 0;
    }
    EXPECT_GT(zeros, 5000);  // the collinear half really was collinear
    // Counterclockwise in (x, y), (y, z) and (z, x): the signs of the normal's z, x and y.
    const Vec3d a = v(0, 0, 0), b = v(1, 0, 0), c = v(0, 1, 0), d = v(0, 0, 1);
    EXPECT_EQ(orient2d(a, b, c, 0, 1), 1);
    EXPECT_EQ(orient2d(a, c, d, 1, 2), 1);
    EXPECT_EQ(orient2d(a, d, b, 2, 0), 1);
    EXPECT_EQ(orient2d(a, c, b, 0, 1), -1);
    EXPECT_EQ(orient2d(v(0x1p-140, 0, 5), v(0x1p-139, 0, 6), v(0x1p-138, 0x1p-149, 7), 0, 1), 1);
    EXPECT_EQ(orient2d(v(0x1p-140, 0, 5), v(0x1p-139, 0, 6), v(0x1p-138, 0, 7), 0, 1), 0);
    EXPECT_EQ(orient2d(v(0x1p59, 0x1p59, 0), v(-0x1p59, -0x1p59, 1), v(1, 1, 2), 0, 1), 0);
    EXPECT_EQ(orient2d(v(0x1p59, 0x1p59, 0), v(-0x1p59, -0x1p59, 1), v(0x1p-20, 0, 2), 0, 1), 1);  // 2^40
}

// Trap: the degenerate configurations of Guigue-Devillers (corners on the other plane, shared
// edges and corners, chords that share an end, coplanar pairs) that a float implementation or a
// sloppy classification gets wrong: triangles with corners on a 3x3x3 integer grid (so that
// such coincidences are frequent), 20000 pairs with a fixed seed, against the exact reference.
// Also checks symmetry and that the contact is CGAL's do_intersect.
TEST(Predicates, ContactAndClassMatchExactReferenceOnGridTriangles) {
    std::mt19937 rng(11);
    auto tri = [&] {
        for (;;) {
            TrianglePoints t;
            for (Vec3d& p : t) p = v(double(rng() % 3), double(rng() % 3), double(rng() % 3));
            if (!collinear(t[0], t[1], t[2])) return t;
        }
    };
    int counts[3] = {0, 0, 0};
    for (int trial = 0; trial < 20000; ++trial) {
        const TrianglePoints a = tri(), b = tri();
        const Contact expected = reference(a, b);
        ASSERT_EQ(triangleContact(a, b), expected) << "trial " << trial;
        ASSERT_EQ(triangleContact(b, a), expected) << "trial " << trial;
        const TrianglePoints rotated{a[1], a[2], a[0]}, flipped{b[0], b[2], b[1]};
        ASSERT_EQ(triangleContact(rotated, flipped), expected) << "trial " << trial;
        ++counts[int(expected)];
    }
    // Every class occurs often enough for the comparison to mean something.
    EXPECT_GT(counts[int(Contact::None)], 1000);
    EXPECT_GT(counts[int(Contact::Touching)], 1000);
    EXPECT_GT(counts[int(Contact::Crossing)], 1000);
}

// Trap: segment-triangle through a corner, along an edge, in the plane, one ulp short.
TEST(Predicates, SegmentTriangleOnBoundaries) {
    const TrianglePoints t{v(0, 0, 0), v(4, 0, 0), v(0, 4, 0)};
    EXPECT_TRUE(triangleSegmentIntersect(t, v(0, 0, -1), v(0, 0, 1)));  // through a corner
    EXPECT_TRUE(triangleSegmentIntersect(t, v(2, 2, -1), v(2, 2, 1)));  // through the hypotenuse
    EXPECT_FALSE(
        triangleSegmentIntersect(t, v(2, std::nextafter(2.0f, 3.0f), -1), v(2, std::nextafter(2.0f, 3.0f), 1)));
    EXPECT_TRUE(triangleSegmentIntersect(t, v(1, 1, 0), v(9, 9, 0)));  // coplanar, inside
    EXPECT_FALSE(triangleSegmentIntersect(t, v(3, 3, 0), v(9, 9, 0)));  // coplanar, outside
    EXPECT_TRUE(triangleSegmentIntersect(t, v(1, 1, 0), v(1, 1, 5)));  // ends on the face
    EXPECT_FALSE(triangleSegmentIntersect(t, v(1, 1, 0x1p-149), v(1, 1, 5)));  // one denormal above
}

// Random triangles on the grid against CGAL's do_intersect for segments (the shared-vertex rule
// relies on it).
TEST(Predicates, SegmentTriangleMatchesExactReferenceOnGrid) {
    std::mt19937 rng(5);
    for (int trial = 0; trial < 20000; ++trial) {
        TrianglePoints t;
        do {
            for (Vec3d& p : t) p = v(double(rng() % 3), double(rng() % 3), double(rng() % 3));
        } while (collinear(t[0], t[1], t[2]));
        const Vec3d s0 = v(double(rng() % 3), double(rng() % 3), double(rng() % 3));
        const Vec3d s1 = v(double(rng() % 3), double(rng() % 3), double(rng() % 3));
        if (s0 == s1) continue;  // the oracle never passes a degenerate segment
        const bool expected = CGAL::do_intersect(et(t), EK::Segment_3(ep(s0), ep(s1)));
        ASSERT_EQ(triangleSegmentIntersect(t, s0, s1), expected) << "trial " << trial;
    }
}

// Trap: an integer unit that drops bits (subnormals, mixed magnitudes, negative values) or claims
// a span over 62 bits fits: every coordinate must come back exactly as an integer of 2^unit.
TEST(Predicates, IntegerUnitIsExactOrRefused) {
    const float all[] = {0.0f, -0.0f};
    EXPECT_EQ(integerUnit(all, 2), 0);  // all zero
    const float mixed[] = {1.5f, -0.25f, 0.0f, 0x1p40f};
    EXPECT_EQ(integerUnit(mixed, 4), -2);
    const float tiny[] = {0x1p-149f, -0x1p-130f};  // subnormal and normal
    EXPECT_EQ(integerUnit(tiny, 2), -149);
    const float wide[] = {0x1p-2f, 0x1p60f};  // 63 bits apart
    EXPECT_EQ(integerUnit(wide, 2), kNoUnit);
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> exponent(-140, 40), bits(0, (1 << 24) - 1);
    for (int trial = 0; trial < 2000; ++trial) {
        float x[6];
        const int base = exponent(rng);
        for (float& f : x) f = std::ldexp(float(bits(rng) - (1 << 23)), base + int(rng() % 16));
        const int32_t unit = integerUnit(x, 6);
        ASSERT_NE(unit, kNoUnit) << "trial " << trial;  // at most 24 + 15 bits apart
        for (float f : x) {
            const int64_t q = toUnit(f, unitScale(unit));
            ASSERT_EQ(std::ldexp(double(q), unit), double(f)) << "trial " << trial;
        }
    }
}

}  // namespace
}  // namespace cullide
