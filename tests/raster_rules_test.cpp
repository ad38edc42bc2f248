// Tests of the rules of the CPU reference rasterizer (cullide/raster/rules.h): snapping, depth
// encoding (scalar and four-lane), inclusive edges, the paper's precision cases (Figure 5) and the
// eight depth functions. Every random test uses a fixed seed.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/png.h"
#include "cullide/raster/rules.h"

#include "raster_test_util.h"
#include "test_util.h"
#include "window_geometry.h"

#include "../raster/src/setup/depth_simd.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

namespace cullide::raster {
namespace {

using test::alwaysQueries;
using test::backendFor;
using test::Geo;
using test::windowView;

// ---------------------------------------------------------------------------------------------
// Rules

// Trap: snapping with round-half-away-from-zero (not translation-invariant) or with v+0.5
// rounding up values just below a half.
TEST(RasterRules, SnapRoundsToNearestTiesUp) {
    EXPECT_EQ(snapToFixed(0.0, 8), 0);
    EXPECT_EQ(snapToFixed(1.0, 8), 256);
    EXPECT_EQ(snapToFixed(0.5 / 256, 8), 1);
    EXPECT_EQ(snapToFixed(-0.5 / 256, 8), 0);  // tie goes up, also below zero
    EXPECT_EQ(snapToFixed(-1.5 / 256, 8), -1);
    EXPECT_EQ(snapToFixed(std::nextafter(0.5 / 256, 0.0), 8), 0);
    EXPECT_EQ(snapToFixed(0.49999999999999994, 0 + 1), 1);  // 0.99999999999999989 -> 1
    EXPECT_EQ(snapToFixed(std::nextafter(0.25, 0.0), 1), 0);
    EXPECT_EQ(snapToFixed(-2.25, 2), -9);
    EXPECT_EQ(snapToFixed(guardBandPixels(8), 8), int64_t(1) << kGuardBandFixedBits);
}

// Exact round(z * (2^n - 1)), ties up, by 128-bit integers: z = m * 2^e exactly.
uint32_t exactUnorm(double z, int n) {
    if (z == 0) return 0;
    int e = 0;
    const double m = std::frexp(z, &e);  // z = m * 2^e, m in [0.5, 1)
    const auto M = (unsigned __int128)std::ldexp(m, 53);  // z = M * 2^(e-53)
    const int shift = 53 - e;  // z = M / 2^shift, shift >= 53
    const unsigned __int128 c = (unsigned __int128)((uint64_t(1) << n) - 1);
    if (shift >= 127) return 0;  // z < 2^-74: z*c < 1/2
    const unsigned __int128 p = M * c;  // z*c = p / 2^shift (p < 2^86)
    const unsigned __int128 half = (unsigned __int128)1 << (shift - 1);
    return uint32_t((p + half) >> shift);
}

// Trap: z*(2^n-1) rounded in double before rounding to an integer (double rounding at n = 32),
// and a wrong tie direction.
TEST(RasterRules, EncodeUnormIsExactForEveryBitCount) {
    std::mt19937_64 rng(12345);
    for (int n = 8; n <= 32; ++n) {
        const double c = std::ldexp(1.0, n) - 1;
        for (int i = 0; i < 20000; ++i) {
            double z;
            const int kind = i % 4;
            if (kind == 0) {
                z = double(rng() >> 11) * 0x1p-53;
            } else {  // near a rounding midpoint (k + 1/2)/c, a few ulps either side
                const double k = double(rng() % uint64_t(c));
                z = (k + 0.5) / c;
                const int steps = int(rng() % 7) - 3;
                for (int s = 0; s < std::abs(steps); ++s) z = std::nextafter(z, steps > 0 ? 2.0 : -1.0);
                if (kind == 3) z = std::ldexp(z, -int(rng() % 20));
            }
            z = clampDepth(z);
            ASSERT_EQ(encodeUnorm(z, n), exactUnorm(z, n)) << "n=" << n << " z=" << z;
        }
        EXPECT_EQ(encodeUnorm(0.0, n), 0u);
        EXPECT_EQ(encodeUnorm(1.0, n), uint32_t(c));
        EXPECT_EQ(encodeUnorm(0.5, n), uint32_t(1) << (n - 1));  // the only tie: up (= even)
    }
}

// Trap: -0.0 stored with its sign bit (it would compare above every positive float), NaN kept.
TEST(RasterRules, ClampAndFloatEncoding) {
    EXPECT_EQ(encodeDepth(-0.0, DepthFormat::float32()), 0u);
    EXPECT_EQ(encodeDepth(NAN, DepthFormat::float32()), 0u);
    EXPECT_EQ(encodeDepth(-3.0, DepthFormat::unorm(16)), 0u);
    EXPECT_EQ(encodeDepth(7.0, DepthFormat::unorm(16)), 65535u);
    EXPECT_EQ(encodeDepth(1.0, DepthFormat::float32()), 0x3F800000u);
    const double z = 0.1;
    EXPECT_EQ(encodeDepth(z, DepthFormat::float32()), std::bit_cast<uint32_t>(0.1f));
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// Trap: the fast paths' four-lane clamp and encoding (depth_simd.h) drifting from rule 7's scalar
// one: a tie taken the wrong way, r +- 1/2 decided on the wrong side, the clamp's max/min
// letting NaN or -0 through, the carry of f + 1 lost at 2^n (z = 1, n = 32). Midpoints a few ulps
// either side, tiny z (a < 1), out-of-range and non-finite z, every bit count and float; each value
// in each lane.
__attribute__((target("avx2"))) void encode4(const double z[4], const DepthFormat& f, uint32_t out[4]) {
    const __m256d v = _mm256_loadu_pd(z);
    const __m128i codes = f.kind == DepthFormat::Kind::Float32 ? raster::detail::clampEncode4<true>(v, f.bits)
                                                               : raster::detail::clampEncode4<false>(v, f.bits);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), codes);
}

TEST(RasterRules, FourLaneEncodingMatchesTheRule) {
    if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "no AVX2 on this CPU";
    std::mt19937_64 rng(4242);
    std::vector<double> zs = {0.0,
                              -0.0,
                              1.0,
                              0.5,
                              -1.0,
                              2.0,
                              NAN,
                              -NAN,
                              INFINITY,
                              -INFINITY,
                              std::nextafter(1.0, 0.0),
                              std::nextafter(0.0, 1.0),
                              0x1p-40,
                              1e-300};
    for (int i = 0; i < 4000; ++i) {
        const int n = 8 + int(rng() % 25);
        const double c = std::ldexp(1.0, n) - 1, k = double(rng() % uint64_t(c));
        double z = (k + 0.5) / c;
        const int steps = int(rng() % 7) - 3;
        for (int t = 0; t < std::abs(steps); ++t) z = std::nextafter(z, steps > 0 ? 2.0 : -1.0);
        if (i % 4 == 3) z = std::ldexp(z, -int(rng() % 40));
        if (i % 16 == 5) z = double(rng() >> 11) * 0x1p-53 * 3 - 1;  // [-1, 2)
        zs.push_back(z);
    }
    std::vector<DepthFormat> formats = {DepthFormat::float32()};
    for (int n = 8; n <= 32; ++n) formats.push_back(DepthFormat::unorm(n));
    for (const DepthFormat& f : formats)
        for (size_t i = 0; i < zs.size(); ++i) {
            const size_t j = (i * 7 + 3) % zs.size();
            const double lanes[4] = {zs[i], zs[j], zs[(i + 1) % zs.size()], zs[(j + 5) % zs.size()]};
            uint32_t got[4];
            encode4(lanes, f, got);
            for (int l = 0; l < 4; ++l)
                ASSERT_EQ(got[l], encodeDepth(lanes[l], f)) << f.name() << " z=" << lanes[l] << " lane " << l;
        }
}
#endif

// Trap: the edge classification inverted, which breaks the "exactly one owner" rule.
TEST(RasterRules, InclusiveEdges) {
    // CCW triangle: bottom edge goes +x, right edge goes up, left edge goes down.
    EXPECT_TRUE(isInclusiveEdge(FillRule::BottomLeft, 5, 0));  // bottom
    EXPECT_FALSE(isInclusiveEdge(FillRule::BottomLeft, -5, 0));  // top
    EXPECT_FALSE(isInclusiveEdge(FillRule::TopLeft, 5, 0));
    EXPECT_TRUE(isInclusiveEdge(FillRule::TopLeft, -5, 0));
    for (FillRule r : {FillRule::BottomLeft, FillRule::TopLeft}) {
        EXPECT_TRUE(isInclusiveEdge(r, 3, -1));  // left
        EXPECT_FALSE(isInclusiveEdge(r, 3, 1));  // right
        // A shared edge is seen in both directions: exactly one side owns it.
        for (int dx = -2; dx <= 2; ++dx)
            for (int dy = -2; dy <= 2; ++dy)
                if (dx || dy) {
                    EXPECT_NE(isInclusiveEdge(r, dx, dy), isInclusiveEdge(r, -dx, -dy));
                }
    }
}

// Trap: the trace reader and the Python module each parsing the rule's name their own way (they
// did): the one parser takes back exactly the names toString gives, and nothing near them.
TEST(RasterRules, FillRuleNamesRoundTrip) {
    for (FillRule r : {FillRule::BottomLeft, FillRule::TopLeft}) EXPECT_EQ(parseFillRule(toString(r)), r);
    EXPECT_NE(toString(FillRule::BottomLeft), std::string(toString(FillRule::TopLeft)));
    for (const char* bad : {"", "top-right", "Top-Left", "bottom-left ", "bottomleft", "top"})
        EXPECT_FALSE(parseFillRule(bad).has_value()) << bad;
}

// ---------------------------------------------------------------------------------------------
// The paper's Figure 5(a): depth rounding. Two flat quads over a 4x4 viewport: object 1 (drawn
// first) at s, object 2 at q. The forward pass of Figure 2 (Cullide: query GEQUAL against the
// objects drawn before) and of Figure 3 (self variant: draw with LESS, then query GREATER) is run;
// a non-zero query for object 2 means "reported" (kept in the PCS).

struct Reported {
    bool cullide, modified;
};

Reported figure5aForward(int n, double s, double q, double znear = 0, double zfar = 1) {
    Geo g;
    g.quad(0, 0, 4, 4, float(s));
    g.quad(0, 0, 4, 4, float(q));
    OrthoView view = windowView(4, 4, DepthFormat::unorm(n));
    view.znear = znear;
    view.zfar = zfar;
    auto b = backendFor(g, view);
    CommandList fig2;  // Figure 2, forward pass
    fig2.clear();
    for (uint32_t obj = 0; obj < 2; ++obj) {
        fig2.depthFunc(DepthFunc::GEqual);
        fig2.depthMask(false);
        fig2.beginQuery();
        fig2.draw(2 * obj, 2);
        fig2.endQuery();
        fig2.depthFunc(DepthFunc::Less);
        fig2.depthMask(true);
        fig2.draw(2 * obj, 2);
    }
    const auto r2 = b->execute(fig2);
    CommandList fig3;  // Figure 3, forward pass
    fig3.clear();
    for (uint32_t obj = 0; obj < 2; ++obj) {
        fig3.depthMask(true);
        fig3.depthFunc(DepthFunc::Less);
        fig3.draw(2 * obj, 2);
        fig3.depthMask(false);
        fig3.depthFunc(DepthFunc::Greater);
        fig3.beginQuery();
        fig3.draw(2 * obj, 2);
        fig3.endQuery();
    }
    const auto r3 = b->execute(fig3);
    EXPECT_EQ(r2[0], 0u);  // nothing drawn before object 1
    EXPECT_EQ(r3[0], 0u);  // a flat quad is fully self-visible
    return {r2[1] > 0, r3[1] > 0};
}

// Trap: the depth test done on unrounded values (then A and B would not be reported by Cullide,
// and B would be reported by GREATER). Cases of Figure 5(a) at cell m (stored value m):
//   A: q in front of s (no overlap), both round to m;   B: q behind s, both round to m;
//   C: q behind s, across the boundary m + 1/2.
TEST(Figure5a, CasesABCForDepthBits8_16_24) {
    for (int n : {8, 16, 24}) {
        const double c = std::ldexp(1.0, n) - 1;
        const double m = double((int64_t(c) >> 10) + 1);  // small depths: floats resolve 1/c well
        const double A_s = (m + 0.3) / c, A_q = (m - 0.3) / c;
        const double B_s = (m - 0.3) / c, B_q = (m + 0.3) / c;
        const double C_s = (m + 0.3) / c, C_q = (m + 0.7) / c;
        const Reported a = figure5aForward(n, A_s, A_q), b = figure5aForward(n, B_s, B_q),
                       cc = figure5aForward(n, C_s, C_q);
        EXPECT_TRUE(a.cullide) << "n=" << n;
        EXPECT_FALSE(a.modified) << "n=" << n;
        EXPECT_TRUE(b.cullide) << "n=" << n;
        EXPECT_FALSE(b.modified) << "n=" << n;
        EXPECT_TRUE(cc.cullide) << "n=" << n;
        EXPECT_TRUE(cc.modified) << "n=" << n;
        // And clearly separated objects (q in front by several steps) are reported by neither.
        const Reported sep = figure5aForward(n, (m + 6) / c, (m + 2) / c);
        EXPECT_FALSE(sep.cullide);
        EXPECT_FALSE(sep.modified);
    }
}

// The penetration the modified query is guaranteed to see: one stored step, (far-near)/(2^n-1).
// Trap: a rounding rule under which a full step can stay inside one cell. Sweeps random s (as
// floats in [1/1024, 1/2)) with q the first float at least one step behind.
TEST(Figure5a, PenetrationOfOneStoredStepIsAlwaysReported) {
    std::mt19937_64 rng(77);
    for (int n : {8, 16, 24}) {
        const double c = std::ldexp(1.0, n) - 1;
        for (int i = 0; i < 60; ++i) {
            const float s =
                float(std::ldexp(1.0 + double(rng() % 1000000) / 1e6, -2 - int(rng() % 9)));  // [2^-10, 1/2)
            float q = float(double(s) + 1.0 / c);
            while ((double(q) - double(s)) * c < 1.0) q = std::nextafter(q, 2.0f);  // exact in double here
            const Reported r = figure5aForward(n, s, q);
            ASSERT_TRUE(r.cullide && r.modified) << "n=" << n << " s=" << s << " q=" << q;
        }
    }
}

// The paper's bound (far-near)/2^n is 1/(2^n-1) short of a stored step: starting just above a
// rounding midpoint, a penetration of exactly 2^-n stays within one stored value and GREATER
// misses it. Trap: trusting the paper's bound literally. (Documents, does not excuse: Cullide's
// GEQUAL still reports it.)
TEST(Figure5a, PaperBoundOfTwoToMinusNCanBeMissedByGreater) {
    // Object 1 at z = 0, object 2 at z = 1, view depth range [znear, znear + 2^n]: window depths
    // zA = -znear/2^n and zB = zA + 2^-n exactly (power-of-two scaling), with zA just at or above
    // the rounding midpoint (m - 1/2)/(2^n - 1), where stored(zA) = stored(zB) = m.
    for (int n : {8, 16, 24}) {
        const double c = std::ldexp(1.0, n) - 1, range = std::ldexp(1.0, n);
        const double m = double(int64_t(c) / 3);
        double zA = (m - 0.5) / c;
        while (encodeUnorm(zA, n) < uint32_t(m)) zA = std::nextafter(zA, 1.0);
        OrthoView v = windowView(4, 4, DepthFormat::unorm(n));
        v.znear = -zA * range;
        v.zfar = v.znear + range;
        const double wA = v.toWindow(Vec3f(0, 0, 0)).z(), wB = v.toWindow(Vec3f(0, 0, 1)).z();
        ASSERT_EQ(wA, zA);
        ASSERT_GE(wB - wA, std::ldexp(1.0, -n)) << "penetration of at least (far-near)/2^n";
        ASSERT_EQ(encodeUnorm(wA, n), encodeUnorm(wB, n));
        const Reported r = figure5aForward(n, 0.0, 1.0, v.znear, v.zfar);
        EXPECT_TRUE(r.cullide) << "n=" << n;
        EXPECT_FALSE(r.modified) << "n=" << n;
    }
}

// ---------------------------------------------------------------------------------------------
// The paper's Figure 5(b): screen resolution, on a 4x3 viewport (12 pixels, as in the figure).
// Object 1 is triangle(s) drawn first, object 2 queried, as in figure5aForward.

// Cases B and C work at D16, near stored value 1000: depths are given in steps of 1/(2^16 - 1).
constexpr int kFigure5bBits = 16;
const double kD16Steps = std::ldexp(1.0, kFigure5bBits) - 1;

std::pair<uint64_t, uint64_t> queryBoth(const Geo& g, uint32_t first1, uint32_t n1, uint32_t first2, uint32_t n2,
                                        int bits = 16) {
    auto b = backendFor(g, windowView(4, 3, DepthFormat::unorm(bits)));
    CommandList l;
    l.clear();
    l.depthFunc(DepthFunc::Less);
    l.draw(first1, n1);
    l.depthMask(false);
    l.depthFunc(DepthFunc::GEqual);
    l.beginQuery();
    l.draw(first2, n2);
    l.endQuery();
    l.depthFunc(DepthFunc::Greater);
    l.beginQuery();
    l.draw(first2, n2);
    l.endQuery();
    const auto r = b->execute(l);
    return {r[0], r[1]};
}

// Case A. Trap: expecting overlap in screen space to be seen when it holds no pixel centre.
// Two triangles inside the square between the centres (0.5..1.5)^2 cross each other in depth
// (they intersect in 3D) but contain no centre: no fragment, both methods miss the intersection.
TEST(Figure5b, CaseA_OverlapWithoutAPixelCentreIsMissedByBoth) {
    Geo g;
    g.tri(Vec3f(0.6f, 0.6f, 0.2f), Vec3f(1.4f, 0.6f, 0.8f), Vec3f(1.0f, 1.4f, 0.5f));
    g.tri(Vec3f(0.6f, 0.7f, 0.8f), Vec3f(1.4f, 0.7f, 0.2f), Vec3f(1.0f, 1.45f, 0.5f));
    const auto [gequal, greater] = queryBoth(g, 0, 1, 1, 1);
    EXPECT_EQ(gequal, 0u);
    EXPECT_EQ(greater, 0u);
}

// Case B. Trap: sub-step penetration at a single shared centre. The triangles share only the
// centre P1 = (1.5, 1.5); object 2 is sloped and crosses object 1 near P1, where the two depths
// differ by a fraction of a step: Cullide (GEQUAL) reports it, GREATER does not.
TEST(Figure5b, CaseB_OneSharedCentreWithRoundedEqualDepth) {
    const double c = kD16Steps;
    const float s = float(1000.0 / c);
    const float q = float(1000.2 / c);  // behind s at P1, but the same stored value
    Geo g;
    g.tri(Vec3f(1.2f, 1.2f, s), Vec3f(1.8f, 1.2f, s), Vec3f(1.5f, 1.8f, s));
    // Object 2: crosses depth s along x (in front on the left, behind on the right), and at the
    // centre (1.5, 1.5) its depth is q. Its plane: z = q + (x - 1.5) * slope.
    const float slope = float(4.0 / c);
    auto z2 = [&](float x) { return float(double(q) + (double(x) - 1.5) * double(slope)); };
    g.tri(Vec3f(1.1f, 1.1f, z2(1.1f)), Vec3f(1.9f, 1.1f, z2(1.9f)), Vec3f(1.5f, 1.9f, z2(1.5f)));
    const auto [gequal, greater] = queryBoth(g, 0, 1, 1, 1, kFigure5bBits);
    EXPECT_EQ(gequal, 1u);
    EXPECT_EQ(greater, 0u);
}

// Case C. Trap: the intersection seen only through the centre where object 2 is behind. The
// triangles share P1 = (1.5, 1.5) and P2 = (2.5, 1.5); object 2 is in front at P1 and behind at P2.
// Cullide reports it whenever object 2 is behind-or-equal at P2; GREATER only when the depth
// difference at P2 reaches a stored step.
TEST(Figure5b, CaseC_TwoSharedCentresWithSeparatedDepths) {
    const double c = kD16Steps;
    const float s = float(1000.0 / c);
    for (const double behindSteps : {1.5, 0.2}) {
        Geo g;
        g.quad(1.2f, 1.2f, 2.8f, 1.8f, s);  // object 1: covers P1 and P2 only
        // Object 2 over the same two centres, depth -2 steps at P1 and +behindSteps at P2.
        const double zP1 = 1000.0 - 2.0, zP2 = 1000.0 + behindSteps;
        auto z2 = [&](double x) { return float((zP1 + (x - 1.5) * (zP2 - zP1)) / c); };
        const uint32_t a = g.add(1.1f, 1.1f, z2(1.1)), b = g.add(2.9f, 1.1f, z2(2.9)), d = g.add(1.1f, 1.9f, z2(1.1)),
                       e = g.add(2.9f, 1.9f, z2(2.9));
        g.tri(a, b, e);
        g.tri(a, e, d);
        const auto [gequal, greater] = queryBoth(g, 0, 2, 2, 2, kFigure5bBits);
        EXPECT_EQ(gequal, 1u) << behindSteps;  // P2 only
        EXPECT_EQ(greater, behindSteps >= 1.0 ? 1u : 0u) << behindSteps;
    }
}

// ---------------------------------------------------------------------------------------------
// Depth functions

// Trap: any function, the mask or the clear value implemented with the wrong comparison.
// Incoming 1/2 against stored clear values below, equal to and above it, for three formats.
TEST(DepthFunc, TruthTableForAllEightFunctionsMaskAndClearValues) {
    // Expected pass for (incoming < stored, ==, >), written out by hand.
    const struct {
        DepthFunc f;
        bool lt, eq, gt;
    } table[] = {{DepthFunc::Never, false, false, false},  {DepthFunc::Less, true, false, false},
                 {DepthFunc::Equal, false, true, false},   {DepthFunc::LEqual, true, true, false},
                 {DepthFunc::Greater, false, false, true}, {DepthFunc::NotEqual, true, false, true},
                 {DepthFunc::GEqual, false, true, true},   {DepthFunc::Always, true, true, true}};
    Geo g;
    g.quad(0, 0, 3, 2, 0.5f);
    for (const DepthFormat fmt : {DepthFormat::unorm(16), DepthFormat::unorm(24), DepthFormat::float32()})
        for (const auto& row : table)
            for (bool mask : {true, false})
                for (double clearZ : {0.0, 0.25, 0.5, 0.75, 1.0}) {
                    auto b = backendFor(g, windowView(3, 2, fmt));
                    CommandList l;
                    l.clear(clearZ);
                    l.depthFunc(row.f);
                    l.depthMask(mask);
                    l.beginQuery();
                    l.draw(0, 2);
                    l.endQuery();
                    l.beginQuery(QueryKind::AnySamplesPassed);
                    l.draw(0, 2);
                    l.endQuery();
                    const auto r = b->execute(l);
                    const bool pass = clearZ > 0.5 ? row.lt : clearZ == 0.5 ? row.eq : row.gt;
                    EXPECT_EQ(r[0], pass ? 6u : 0u) << toString(row.f) << " clear " << clearZ << " " << fmt.name();
                    const uint32_t after = encodeDepth(pass && mask ? 0.5 : clearZ, fmt);
                    const DepthImage img = b->readDepth();
                    for (uint32_t v : img.values) ASSERT_EQ(v, after) << toString(row.f) << " mask " << mask;
                    // The second query sees the buffer the first draw left.
                    const bool pass2 = mask && pass ? row.eq : pass;
                    EXPECT_EQ(r[1], pass2 ? 1u : 0u) << toString(row.f) << " clear " << clearZ;
                }
}

}  // namespace
}  // namespace cullide::raster
