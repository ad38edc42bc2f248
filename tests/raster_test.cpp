// Tests of the CPU reference rasterizer (raster/): the rules of rules.h, the paper's precision
// cases (Figure 5), the fill rule on shared edges, depth functions, clipping, formats and
// resolutions, and the differential tests fast path vs scalar reference path and across thread
// counts. Every random test uses a fixed seed. On failure, debug PNGs go to the gtest temp folder.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/png.h"
#include "cullide/raster/rules.h"

#include "test_util.h"
#include "window_geometry.h"

#include "../raster/src/setup/depth_simd.h"

#include <gtest/gtest.h>
#include <oneapi/tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

namespace cullide::raster {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers

using test::backendFor;
using test::Geo;
using test::windowView;

// A command list that clears, then counts with ALWAYS the samples of each (first, count) range of
// triangles, one query per range.
CommandList alwaysQueries(std::initializer_list<std::pair<uint32_t, uint32_t>> ranges) {
    CommandList l;
    l.clear();
    l.depthFunc(DepthFunc::Always);
    for (const auto& [first, count] : ranges) {
        l.beginQuery();
        l.draw(first, count);
        l.endQuery();
    }
    return l;
}

std::string failPath(const std::string& name) {
    return ::testing::TempDir() + "cullide_raster_" + name + ".png";
}

// Writes both depth images and their difference mask for a failed comparison; returns a note.
std::string dumpDiff(const std::string& name, const DepthImage& a, const DepthImage& b) {
    if (a.width != b.width || a.height != b.height || a.values.empty()) return "(sizes differ)";
    std::vector<uint8_t> mask(a.values.size());
    for (size_t i = 0; i < mask.size(); ++i) mask[i] = a.values[i] == b.values[i] ? 0 : 2;
    try {
        writeDepthPng(a, failPath(name + "_a"));
        writeDepthPng(b, failPath(name + "_b"));
        writeMaskPng(a.width, a.height, mask, failPath(name + "_diff"));
    } catch (const InputError& e) {
        return std::string("(could not write pictures: ") + e.what() + ")";
    }
    return "pictures: " + failPath(name + "_{a,b,diff}");
}

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

// readDepthInto gives readDepth's image, shape and format included, into a buffer it reuses
// (traps: a stale size or format after the view changes; a fresh allocation per read, which made
// the study's cause attribution page-fault through every image).
TEST(CpuBackend, ReadDepthIntoReusesTheBuffer) {
    auto b = makeCpuBackend();
    DepthImage into;
    b->readDepthInto(into);
    EXPECT_TRUE(into.values.empty()) << "no view yet";
    OrthoView v = windowView(40, 30);
    const std::vector<Vec3f> positions{{2, 2, 0.25f}, {30, 3, 0.5f}, {5, 25, 0.75f}};
    const std::vector<Triangle> triangles{{0, 1, 2}};
    b->setGeometry(positions, triangles);
    b->setView(v);
    CommandList l;
    l.clear(1.0);
    l.depthFunc(DepthFunc::Less);
    l.draw(0, 1);
    b->execute(l);
    b->readDepthInto(into);
    const DepthImage want = b->readDepth();
    EXPECT_EQ(into.width, 40);
    EXPECT_EQ(into.height, 30);
    EXPECT_EQ(into.values, want.values);
    const uint32_t* buffer = into.values.data();
    b->execute(l);
    b->readDepthInto(into);
    EXPECT_EQ(into.values.data(), buffer) << "same size: the buffer is reused";
    v = windowView(20, 10);
    v.depth = DepthFormat::float32();
    b->setView(v);
    b->execute(l);
    b->readDepthInto(into);
    const DepthImage small = b->readDepth();
    EXPECT_EQ(into.width, 20);
    EXPECT_EQ(into.height, 10);
    EXPECT_TRUE(into.format == small.format);
    EXPECT_EQ(into.values, small.values);
}

// A new viewport size reads as cleared to 1.0, though the backend fills it only when a list does
// not start with a clear of its own (traps: a list without a clear, or a readDepth, after a
// resize seeing stale or zero depths; a list that starts with a clear losing it).
TEST(CpuBackend, ResizedViewReadsCleared) {
    auto b = makeCpuBackend();
    const std::vector<Vec3f> positions{{2, 2, 0.25f}, {30, 3, 0.5f}, {5, 25, 0.75f}};
    const std::vector<Triangle> triangles{{0, 1, 2}};
    b->setGeometry(positions, triangles);
    CommandList fill;
    fill.clear(0.0);  // leaves 0 everywhere: stale data for the next size
    b->setView(windowView(64, 64));
    b->execute(fill);
    const uint32_t one = encodeDepth(1.0, DepthFormat::unorm(24));
    b->setView(windowView(32, 32));  // smaller: reuses the buffer that holds zeros
    for (uint32_t v : b->readDepth().values) ASSERT_EQ(v, one);
    b->setView(windowView(64, 32));
    CommandList drawOnly;  // no clear: the pending clear must be applied first
    drawOnly.depthFunc(DepthFunc::Less);
    drawOnly.draw(0, 1);
    b->execute(drawOnly);
    const DepthImage img = b->readDepth();
    size_t drawn = 0, cleared = 0;
    for (uint32_t v : img.values) (v == one ? cleared : drawn) += 1;
    EXPECT_GT(drawn, 100u);
    EXPECT_GT(cleared, 1000u);
    EXPECT_EQ(drawn + cleared, img.values.size());
    b->setView(windowView(48, 48));
    CommandList halfClear;  // a list that starts with its own clear keeps that clear's value
    halfClear.clear(0.5);
    b->execute(halfClear);
    for (uint32_t v : b->readDepth().values) ASSERT_EQ(v, encodeDepth(0.5, DepthFormat::unorm(24)));
}

// Trap: bad options silently accepted.
TEST(CpuBackend, RejectsBadOptions) {
    CpuBackendOptions o;
    o.subpixelBits = 0;
    EXPECT_THROW(makeCpuBackend(o), InputError);
    o.subpixelBits = 13;
    EXPECT_THROW(makeCpuBackend(o), InputError);
    o = {};
    o.tileSize = 4;
    EXPECT_THROW(makeCpuBackend(o), InputError);
    o = {};
    o.threads = -1;
    EXPECT_THROW(makeCpuBackend(o), InputError);
    EXPECT_NE(makeCpuBackend()->describe().find("8 subpixel bits"), std::string::npos);
    // The thread count as a reader says it ("1 threads" once).
    for (const auto& [threads, words] : {std::pair{0, "default threads"}, {1, "1 thread)"}, {4, "4 threads)"}}) {
        o = {};
        o.threads = threads;
        EXPECT_NE(makeCpuBackend(o)->describe().find(words), std::string::npos) << makeCpuBackend(o)->describe();
    }
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
// Fill rule: meshes of triangles sharing edges cover every pixel centre inside them exactly once.
// Every mesh lies in the rectangle R = [X0, X1] x [Y0, Y1] and tiles it. All vertices lie on the
// 1/256 grid (so snapping is exact at S = 8) and many on pixel centres or half-pixel lines, so
// that edges and vertices hit centres exactly. The expected set is the centres inside R, with R's
// own boundary decided by the fill rule (left boundary inclusive, right exclusive, bottom inclusive
// for BottomLeft, top inclusive for TopLeft). Each mesh is drawn at depth 1/2 with ALWAYS and a
// query: the count must equal the expected number, and every expected pixel must be written.

struct Tiling {
    Geo geo;
    double X0, X1, Y0, Y1;
};

double gridValue(std::mt19937_64& rng, double lo, double hi) {
    // A random multiple of 1/256 in [lo, hi]; often exactly a pixel centre or a pixel edge.
    const int64_t a = int64_t(std::ceil(lo * 256)), b = int64_t(std::floor(hi * 256));
    int64_t v = a + int64_t(rng() % uint64_t(b - a + 1));
    if (rng() % 3 == 0) v = (v / 128) * 128;  // snap to a half-pixel multiple
    return std::clamp(double(v) / 256.0, double(a) / 256, double(b) / 256);
}

void addTri(Geo& g, std::mt19937_64& rng, uint32_t a, uint32_t b, uint32_t c) {
    if (rng() & 1) std::swap(b, c);  // both windings
    g.tri(a, b, c);
}

Tiling makeGrid(std::mt19937_64& rng, int W, int H) {
    Tiling t;
    const int nx = 2 + int(rng() % 6), ny = 2 + int(rng() % 6);
    t.X0 = gridValue(rng, 0.0, 3.0);
    t.Y0 = gridValue(rng, 0.0, 3.0);
    t.X1 = gridValue(rng, W - 3.0, W + 1.0);
    t.Y1 = gridValue(rng, H - 3.0, H + 1.0);
    std::vector<double> xs(nx + 1), ys(ny + 1);
    for (int i = 0; i <= nx; ++i) xs[i] = t.X0 + (t.X1 - t.X0) * i / nx;
    for (int j = 0; j <= ny; ++j) ys[j] = t.Y0 + (t.Y1 - t.Y0) * j / ny;
    const double hx = (t.X1 - t.X0) / nx / 4, hy = (t.Y1 - t.Y0) / ny / 4;
    std::vector<uint32_t> id((nx + 1) * (ny + 1));
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            double x = xs[i], y = ys[j];
            if (i > 0 && i < nx) x = gridValue(rng, x - hx, x + hx);
            if (j > 0 && j < ny) y = gridValue(rng, y - hy, y + hy);
            if (i == 0 || i == nx) x = xs[i];
            if (j == 0 || j == ny) y = ys[j];
            id[j * (nx + 1) + i] = t.geo.add(float(x), float(y), 0.5f);
        }
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const uint32_t a = id[j * (nx + 1) + i], b = id[j * (nx + 1) + i + 1], c = id[(j + 1) * (nx + 1) + i + 1],
                           d = id[(j + 1) * (nx + 1) + i];
            if (rng() & 1) {
                addTri(t.geo, rng, a, b, c);
                addTri(t.geo, rng, a, c, d);
            } else {
                addTri(t.geo, rng, a, b, d);
                addTri(t.geo, rng, b, c, d);
            }
        }
    // Boundary vertices must lie exactly on R: the grid values were computed from X0..Y1, so
    // re-read R from the stored floats (identical, since they are multiples of 1/256).
    return t;
}

Tiling makeFan(std::mt19937_64& rng, int W, int H) {
    Tiling t;
    t.X0 = gridValue(rng, 0.0, 2.0);
    t.Y0 = gridValue(rng, 0.0, 2.0);
    t.X1 = gridValue(rng, W - 2.0, W + 1.0);
    t.Y1 = gridValue(rng, H - 2.0, H + 1.0);
    const uint32_t centre =
        t.geo.add(float(gridValue(rng, t.X0 + 1, t.X1 - 1)), float(gridValue(rng, t.Y0 + 1, t.Y1 - 1)), 0.5f);
    // Ring: corners plus random points on each side, counter-clockwise.
    std::vector<uint32_t> ring;
    auto side = [&](double ax, double ay, double bx, double by) {
        ring.push_back(t.geo.add(float(ax), float(ay), 0.5f));
        const int k = int(rng() % 4);
        std::vector<double> ts;
        for (int i = 0; i < k; ++i) ts.push_back(double(1 + rng() % 255) / 256.0);
        std::sort(ts.begin(), ts.end());
        ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
        for (double s : ts) {
            // Points on the side, on the 1/256 grid along it (the side is axis-aligned).
            const double x = ax == bx ? ax : std::round((ax + s * (bx - ax)) * 256) / 256;
            const double y = ay == by ? ay : std::round((ay + s * (by - ay)) * 256) / 256;
            ring.push_back(t.geo.add(float(x), float(y), 0.5f));
        }
    };
    side(t.X0, t.Y0, t.X1, t.Y0);
    side(t.X1, t.Y0, t.X1, t.Y1);
    side(t.X1, t.Y1, t.X0, t.Y1);
    side(t.X0, t.Y1, t.X0, t.Y0);
    for (size_t k = 0; k < ring.size(); ++k) addTri(t.geo, rng, centre, ring[k], ring[(k + 1) % ring.size()]);
    return t;
}

// Random incremental triangulation: the rectangle's two triangles, then points inserted strictly
// inside random triangles (exact integer orientation tests on the 1/256 grid), each splitting a
// triangle into three: many slivers and vertices of high degree.
Tiling makeSoup(std::mt19937_64& rng, int W, int H, int inserts) {
    Tiling t;
    t.X0 = gridValue(rng, 0.0, 2.0);
    t.Y0 = gridValue(rng, 0.0, 2.0);
    t.X1 = gridValue(rng, W - 2.0, W + 1.0);
    t.Y1 = gridValue(rng, H - 2.0, H + 1.0);
    std::vector<std::array<int64_t, 2>> p;  // in 1/256 units
    auto addP = [&](double x, double y) {
        p.push_back({int64_t(std::llround(x * 256)), int64_t(std::llround(y * 256))});
        return uint32_t(p.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> tris;
    const uint32_t a = addP(t.X0, t.Y0), b = addP(t.X1, t.Y0), c = addP(t.X1, t.Y1), d = addP(t.X0, t.Y1);
    tris.push_back({a, b, c});
    tris.push_back({a, c, d});
    auto orient = [&](uint32_t i, uint32_t j, const std::array<int64_t, 2>& q) {
        return (p[j][0] - p[i][0]) * (q[1] - p[i][1]) - (p[j][1] - p[i][1]) * (q[0] - p[i][0]);
    };
    for (int k = 0; k < inserts; ++k) {
        const size_t ti = rng() % tris.size();
        const auto [i, j, l] = tris[ti];
        const int64_t minx = std::min({p[i][0], p[j][0], p[l][0]}), maxx = std::max({p[i][0], p[j][0], p[l][0]});
        const int64_t miny = std::min({p[i][1], p[j][1], p[l][1]}), maxy = std::max({p[i][1], p[j][1], p[l][1]});
        for (int attempt = 0; attempt < 20; ++attempt) {
            std::array<int64_t, 2> q{minx + int64_t(rng() % uint64_t(maxx - minx + 1)),
                                     miny + int64_t(rng() % uint64_t(maxy - miny + 1))};
            if (rng() % 2) {  // prefer pixel centres and half-pixel lines
                q[0] = (q[0] / 128) * 128;
                q[1] = (q[1] / 128) * 128;
            }
            if (orient(i, j, q) > 0 && orient(j, l, q) > 0 && orient(l, i, q) > 0) {
                p.push_back(q);
                const uint32_t m = uint32_t(p.size() - 1);
                tris[ti] = {i, j, m};
                tris.push_back({j, l, m});
                tris.push_back({l, i, m});
                break;
            }
        }
    }
    for (const auto& q : p) t.geo.add(float(double(q[0]) / 256), float(double(q[1]) / 256), 0.5f);
    for (const auto& tr : tris) addTri(t.geo, rng, tr[0], tr[1], tr[2]);
    return t;
}

// Checks a tiling; returns false (after reporting) on failure.
bool checkTiling(const Tiling& t, int W, int H, FillRule rule, int threads, const std::string& name, double offsetX = 0,
                 double offsetY = 0) {
    Geo g = t.geo;
    for (Vec3f& p : g.positions) p += Vec3f(float(offsetX), float(offsetY), 0);
    CpuBackendOptions o;
    o.fillRule = rule;
    o.threads = threads;
    o.tileSize = 16;
    auto b = backendFor(g, windowView(W, H), o);
    const CommandList l = alwaysQueries({{0, uint32_t(g.triangles.size())}});
    const uint64_t count = b->execute(l)[0];
    const DepthImage img = b->readDepth();
    // Expected, exactly in 1/256 units (centres at 256 i + 128).
    const int64_t X0 = std::llround((t.X0 + offsetX) * 256), X1 = std::llround((t.X1 + offsetX) * 256);
    const int64_t Y0 = std::llround((t.Y0 + offsetY) * 256), Y1 = std::llround((t.Y1 + offsetY) * 256);
    uint64_t expected = 0;
    std::vector<uint8_t> mask(size_t(W) * size_t(H));
    bool ok = true;
    const uint32_t half = encodeDepth(0.5, img.format);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const int64_t cx = 256 * i + 128, cy = 256 * j + 128;
            const bool inX = cx >= X0 && cx < X1;
            const bool inY = rule == FillRule::BottomLeft ? (cy >= Y0 && cy < Y1) : (cy > Y0 && cy <= Y1);
            const bool in = inX && inY;
            expected += in;
            const bool written = img.at(i, j) == half;
            mask[size_t(j) * size_t(W) + size_t(i)] = in == written ? uint8_t(in) : (in ? 2 : 3);
            ok = ok && in == written;
        }
    if (!ok || count != expected) {
        writeMaskPng(W, H, mask, failPath(name));
        ADD_FAILURE() << name << ": " << count << " fragments, " << expected
                      << " centres inside (count > expected: double hits; red: holes, green: outside)"
                      << "; picture: " << failPath(name);
        return false;
    }
    return true;
}

// Checks `cases` tilings make(rng, W, H) of random W x H viewports (sides minSide to
// minSide + spread - 1), each at a random sub-pixel offset, under both fill rules, case k with
// threads(k) workers.
template <typename Make, typename Threads>
void checkRandomTilings(uint64_t seed, int cases, int minSide, int spread, const std::string& name, Make make,
                        Threads threads) {
    std::mt19937_64 rng(seed);
    for (int k = 0; k < cases; ++k) {
        const int W = minSide + int(rng() % uint64_t(spread)), H = minSide + int(rng() % uint64_t(spread));
        const Tiling t = make(rng, W, H);
        const double ox = double(rng() % 256) / 256, oy = double(rng() % 256) / 256;
        for (FillRule r : {FillRule::BottomLeft, FillRule::TopLeft})
            ASSERT_TRUE(checkTiling(t, W, H, r, threads(k), name + std::to_string(k), ox, oy));
    }
}

// Trap: holes or double hits on shared edges and at shared vertices through pixel centres,
// for either fill rule and either winding, under a regular grid split by random diagonals.
TEST(FillRule, GridsCoverEachCentreOnce) {
    checkRandomTilings(2024, 60, 8, 40, "grid", makeGrid, [](int k) { return 1 + k % 2; });
}

// Trap: a vertex of high degree on a pixel centre (every fan triangle touches it: exactly one may
// own it), and boundary points splitting the outer edges.
TEST(FillRule, FansCoverEachCentreOnce) {
    checkRandomTilings(99, 60, 6, 30, "fan", makeFan, [](int) { return 2; });
}

// Trap: slivers, steep and nearly horizontal edges, and vertices of any degree in a random soup.
TEST(FillRule, RandomSoupsCoverEachCentreOnce) {
    auto soup = [](std::mt19937_64& rng, int W, int H) {
        const int inserts = 30 + int(rng() % 300);
        return makeSoup(rng, W, H, inserts);
    };
    checkRandomTilings(4242, 40, 10, 60, "soup", soup, [](int) { return 2; });
}

// Trap: the two rules differing anywhere but on horizontal edges through centres: a triangle
// with a horizontal bottom and a horizontal top on centre rows.
TEST(FillRule, BottomLeftAndTopLeftDifferOnlyOnHorizontalEdges) {
    Geo g;
    g.quad(0.5f, 0.5f, 3.5f, 2.5f, 0.5f);  // edges on centre rows and columns
    for (FillRule r : {FillRule::BottomLeft, FillRule::TopLeft}) {
        CpuBackendOptions o;
        o.fillRule = r;
        auto b = backendFor(g, windowView(5, 4), o);
        CommandList l;
        l.clear();
        l.draw(0, 2);
        b->execute(l);
        const DepthImage img = b->readDepth();
        // Columns 0..2 (x = 0.5 left edge inclusive, x = 3.5 right edge exclusive).
        const int rowIn = r == FillRule::BottomLeft ? 0 : 2, rowOut = r == FillRule::BottomLeft ? 2 : 0;
        for (int i = 0; i < 5; ++i) {
            EXPECT_EQ(img.at(i, rowIn) != 0xFFFFFFu, i <= 2) << toString(r) << " i=" << i;
            EXPECT_EQ(img.at(i, rowOut), 0xFFFFFFu);
            EXPECT_EQ(img.at(i, 1) != 0xFFFFFFu, i <= 2);
        }
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

// ---------------------------------------------------------------------------------------------
// Clipping, degenerate triangles, guard band

// Trap: depth clamped instead of clipped (GL clips against near/far): fragments beyond the far
// plane must not exist, fragments in range must keep their interpolated depth.
TEST(Clipping, TrianglesCrossingNearAndFarAreClippedNotClamped) {
    Geo g;
    // z goes from -0.5 at x = 0 to 1.5 at x = 16 (z = x/8 - 1/2): in range for x in [4, 12].
    const uint32_t a = g.add(0, 0, -0.5f), b = g.add(16, 0, 1.5f), c = g.add(16, 4, 1.5f), d = g.add(0, 4, -0.5f);
    g.tri(a, b, c);
    g.tri(a, c, d);
    for (bool ref : {false, true}) {
        CpuBackendOptions o;
        o.scalarReference = ref;
        auto bk = backendFor(g, windowView(16, 4, DepthFormat::float32()), o);
        const CommandList l = alwaysQueries({{0, 2}});
        const auto r = bk->execute(l);
        EXPECT_EQ(r[0], 8u * 4u);  // columns 4..11 (centres 4.5 .. 11.5)
        EXPECT_EQ(bk->lastStats().clipped, 2u);
        const DepthImage img = bk->readDepth();
        for (int i = 0; i < 16; ++i) {
            const bool in = i >= 4 && i <= 11;
            const double z = (i + 0.5) / 8 - 0.5;
            if (in) {
                EXPECT_NEAR(img.depth(i, 2), z, 1e-6) << i;
            } else {
                EXPECT_EQ(img.depth(i, 2), 1.0) << i;
            }
        }
    }
}

// Trap: a triangle beyond the depth range or the viewport costing anything or drawing anything.
TEST(Clipping, TrianglesOutsideAreRejected) {
    Geo g;
    g.tri(Vec3f(0, 0, 1.1f), Vec3f(4, 0, 1.2f), Vec3f(0, 4, 1.5f));
    g.tri(Vec3f(0, 0, -0.1f), Vec3f(4, 0, -0.2f), Vec3f(0, 4, -0.5f));
    g.tri(Vec3f(-5, 0, 0.5f), Vec3f(-1, 0, 0.5f), Vec3f(-1, 4, 0.5f));
    g.tri(Vec3f(0, 4.01f, 0.5f), Vec3f(4, 5, 0.5f), Vec3f(0, 9, 0.5f));
    auto b = backendFor(g, windowView(4, 4));
    const CommandList l = alwaysQueries({{0, 4}});
    EXPECT_EQ(b->execute(l)[0], 0u);
    EXPECT_EQ(b->lastStats().rejected, 4u);
    EXPECT_EQ(b->lastStats().fragments, 0u);
}

// Trap: integer overflow in edge functions for vertices millions of pixels away (UBSan would
// flag it; coverage would be garbage). Such triangles are clipped to the guard band in double.
TEST(Clipping, HugeTrianglesBeyondTheGuardBandStillCoverTheViewport) {
    Geo g;
    g.tri(Vec3f(-3e7f, -3e7f, 0.25f), Vec3f(3e7f, -3e7f, 0.25f), Vec3f(0, 3e7f, 0.25f));
    g.tri(Vec3f(-1e9f, 5.5f, 0.5f), Vec3f(1e9f, 5.5f, 0.5f), Vec3f(1e9f, 1e9f, 0.5f));
    for (bool ref : {false, true}) {
        CpuBackendOptions o;
        o.scalarReference = ref;
        auto b = backendFor(g, windowView(37, 23), o);
        const CommandList l = alwaysQueries({{0, 1}, {1, 1}});
        const auto r = b->execute(l);
        EXPECT_EQ(r[0], 37u * 23u);
        // Second: on or above the line y = 5.5 (the row-5 centres lie on it, and it is a bottom
        // edge: inclusive under the default rule) and below the diagonal from (-1e9, 5.5) to
        // (1e9, 1e9), which passes far above the viewport: rows 5..22.
        EXPECT_EQ(r[1], 37u * 18u);
        EXPECT_EQ(b->lastStats().clipped, 2u);
    }
}

// Trap: hiding the paper's edge-on blind spot. A triangle seen exactly edge-on, and one thinner
// than a subpixel, produce no fragment and are counted as zero-area.
TEST(Degenerate, EdgeOnTrianglesProduceNothingAndAreCounted) {
    Geo g;
    g.tri(Vec3f(1, 1, 0.2f), Vec3f(7, 7, 0.4f), Vec3f(4, 4, 0.9f));  // edge-on: collinear in x, y
    g.tri(Vec3f(1, 1, 0.2f), Vec3f(7, 1.001f, 0.4f), Vec3f(4, 1.0005f, 0.9f));  // collapses when snapped
    g.tri(Vec3f(2, 2, 0.5f), Vec3f(2, 2, 0.5f), Vec3f(5, 6, 0.5f));  // repeated vertex
    for (bool ref : {false, true}) {
        CpuBackendOptions o;
        o.scalarReference = ref;
        auto b = backendFor(g, windowView(8, 8), o);
        const CommandList l = alwaysQueries({{0, 3}});
        EXPECT_EQ(b->execute(l)[0], 0u);
        EXPECT_EQ(b->lastStats().zeroArea, 3u);
        EXPECT_EQ(b->lastStats().fragments, 0u);
    }
}

// ---------------------------------------------------------------------------------------------
// Random scenes: the differential tests

struct RandomScene {
    Geo geo;
    CommandList list;
};

// Random triangles of mixed sizes (sub-pixel to larger than the viewport), some crossing the
// depth range, some far outside, some degenerate; a random command list with every function,
// mask changes, clears, overlapping and repeated draw ranges and both query kinds.
RandomScene randomScene(uint64_t seed, int W, int H, int triangles, int commands, double bigSize = 0) {
    if (bigSize <= 0) bigSize = 3.0 * std::max(W, H);
    std::mt19937_64 rng(seed);
    auto uni = [&](double lo, double hi) { return lo + (hi - lo) * double(rng() >> 11) * 0x1p-53; };
    RandomScene s;
    for (int t = 0; t < triangles; ++t) {
        const int kind = int(rng() % 10);
        const double size = kind < 4 ? uni(0.2, 3) : kind < 8 ? uni(2, 20) : uni(20, bigSize);
        const double cx = uni(-0.2 * W, 1.2 * W), cy = uni(-0.2 * H, 1.2 * H);
        const double zc = kind == 9 ? uni(-0.5, 1.5) : uni(0, 1);
        Vec3f p[3];
        for (auto& v : p)
            v = Vec3f(float(cx + uni(-size, size)), float(cy + uni(-size, size)),
                      float(zc + uni(-0.3, 0.3) * (kind == 9 ? 3 : 1)));
        if (rng() % 25 == 0) p[2] = p[0] + (p[1] - p[0]) * 0.5f;  // degenerate
        if (rng() % 40 == 0) p[1].x() = float(uni(-1e8, 1e8));  // beyond the guard band
        if (rng() % 7 == 0) {  // on the subpixel grid / centres
            for (auto& v : p) {
                v.x() = std::round(v.x() * 2) / 2;
                v.y() = std::round(v.y() * 2) / 2;
            }
        } else if (rng() % 6 == 0) {  // on half subpixels of 4, 8 or 12 bits: snapping's ties
            const float grid = float(1 << (5 + 4 * int(rng() % 3)));
            for (auto& v : p) {
                v.x() = std::round(v.x() * grid) / grid;
                v.y() = std::round(v.y() * grid) / grid;
            }
        }
        s.geo.tri(p[0], p[1], p[2]);
    }
    const DepthFunc funcs[] = {DepthFunc::Never,   DepthFunc::Less,     DepthFunc::Equal,  DepthFunc::LEqual,
                               DepthFunc::Greater, DepthFunc::NotEqual, DepthFunc::GEqual, DepthFunc::Always};
    s.list.clear(uni(0.5, 1.0));
    bool open = false;
    for (int c = 0; c < commands; ++c) {
        const int op = int(rng() % 12);
        if (op < 6) {
            const uint32_t first = uint32_t(rng() % uint64_t(triangles));
            const uint32_t count =
                uint32_t(rng() % uint64_t(std::min<uint64_t>(triangles - first, 1 + rng() % 40) + 1));
            s.list.draw(first, count);
        } else if (op == 6) {
            s.list.depthFunc(funcs[rng() % 8]);
        } else if (op == 7) {
            s.list.depthFunc(rng() % 2 ? DepthFunc::Less : DepthFunc::GEqual);
        } else if (op == 8) {
            s.list.depthMask(rng() % 3 != 0);
        } else if (op == 9 || op == 10) {
            if (open) s.list.endQuery();
            else s.list.beginQuery(rng() % 4 == 0 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
            open = !open;
        } else if (rng() % 8 == 0) {
            s.list.clear(uni(0, 1));
        }
    }
    if (open) s.list.endQuery();
    return s;
}

struct Outcome {
    std::vector<uint64_t> results;
    DepthImage depth;
    RasterStats stats;
};

Outcome run(const RandomScene& s, const OrthoView& view, CpuBackendOptions o, int lists = 1) {
    auto b = backendFor(s.geo, view, o);
    Outcome out;
    for (int i = 0; i < lists; ++i) {  // later lists start from the previous state
        out.results = b->execute(s.list);
        out.stats = b->lastStats();
    }
    out.depth = b->readDepth();
    return out;
}

// The scalar reference path's options for a seeded test: the fill rule by the seed's parity (the
// seeds cover both), `subpixelBits` as given.
CpuBackendOptions scalarReference(uint64_t seed, int subpixelBits) {
    CpuBackendOptions o;
    o.scalarReference = true;
    o.fillRule = seed % 2 ? FillRule::BottomLeft : FillRule::TopLeft;
    o.subpixelBits = subpixelBits;
    return o;
}

void expectSame(const Outcome& a, const Outcome& b, const std::string& what) {
    EXPECT_EQ(a.results, b.results) << what;
    EXPECT_EQ(a.stats, b.stats) << what;
    if (a.depth.values != b.depth.values) {
        size_t diff = 0;
        for (size_t i = 0; i < a.depth.values.size(); ++i) diff += a.depth.values[i] != b.depth.values[i];
        ADD_FAILURE() << what << ": " << diff << " depth values differ; " << dumpDiff("diff", a.depth, b.depth);
    }
}

// The direct path on one and two threads against `expected` (the scalar path's outcome), each run
// checked to have taken it.
void expectDirectOnThreads(const RandomScene& s, const OrthoView& view, const CpuBackendOptions& ref,
                           const Outcome& expected, const std::string& what) {
    for (int threads : {1, 2}) {
        CpuBackendOptions o = ref;
        o.scalarReference = false;
        o.threads = threads;
        auto direct = backendFor(s.geo, view, o);
        Outcome got;
        got.results = direct->execute(s.list);
        got.stats = direct->lastStats();
        got.depth = direct->readDepth();
        EXPECT_TRUE(direct->lastRanDirect()) << what << " threads " << threads;
        expectSame(expected, got, what + " threads " + std::to_string(threads));
    }
}

// Trap: tiling, binning, edge stepping, galloping search, tile clipping, query bookkeeping or the
// four-pixel AVX2 loop (lane masks, unsigned compares, the unorm encoding in vector doubles)
// disagreeing with the obvious per-pixel loop; for every format, both fill rules, several
// subpixel precisions and tile sizes (including tiles that do not divide the viewport).
TEST(Differential, FastPathEqualsScalarReferenceOnRandomScenes) {
    const DepthFormat formats[] = {DepthFormat::unorm(8),  DepthFormat::unorm(16), DepthFormat::unorm(24),
                                   DepthFormat::unorm(31), DepthFormat::unorm(32), DepthFormat::float32()};
    for (uint64_t seed = 1; seed <= 24; ++seed) {
        std::mt19937_64 pick(seed * 7919);
        const int W = 1 + int(pick() % 70), H = 1 + int(pick() % 70);
        const RandomScene s = randomScene(seed, W, H, 150, 120);
        OrthoView view = windowView(W, H, formats[seed % 6]);
        const CpuBackendOptions ref = scalarReference(seed, seed % 3 == 0 ? 4 : seed % 5 == 0 ? 12 : 8);
        const Outcome expected = run(s, view, ref, 2);
        EXPECT_GT(expected.stats.fragments, 0u);
        for (int tile : {8, 24, 64})
            for (bool simd : {true, false}) {  // the AVX2 pixel loop (where the CPU has it) and the scalar one
                CpuBackendOptions fast = ref;
                fast.scalarReference = false;
                fast.tileSize = tile;
                fast.threads = 2;
                fast.simd = simd;
                expectSame(expected, run(s, view, fast, 2),
                           "seed " + std::to_string(seed) + " tile " + std::to_string(tile) +
                               (simd ? " simd " : " scalar ") + view.depth.name());
            }
    }
}

// Trap: many tiny draws and queries (Cullide's pattern): sparse per-tile query lists, queries with
// no fragment at all, query numbering, ANY_SAMPLES_PASSED folding.
TEST(Differential, ManySmallDrawsAndQueries) {
    const RandomScene base = randomScene(555, 48, 40, 400, 0);
    RandomScene s;
    s.geo = base.geo;
    std::mt19937_64 rng(556);
    s.list.clear();
    for (int k = 0; k < 3000; ++k) {
        const uint32_t first = uint32_t(rng() % 396);
        s.list.depthFunc(k % 2 ? DepthFunc::Less : DepthFunc::Greater);
        s.list.depthMask(k % 2 == 1);
        s.list.beginQuery(k % 5 == 0 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
        s.list.draw(first, uint32_t(rng() % 4));
        s.list.endQuery();
    }
    const OrthoView view = windowView(48, 40);
    CpuBackendOptions ref;
    ref.scalarReference = true;
    const Outcome expected = run(s, view, ref);
    CpuBackendOptions fast;
    fast.tileSize = 8;
    expectSame(expected, run(s, view, fast), "many small draws");
}

// Trap: the fast path replays a draw's recorded fragments when the tile's next draw has the same
// records (reducePCS's pattern). Replaying under a different function or mask, across a clear, after
// a draw too large to record, or mistaking a different range for the same one, must all match the
// plain per-pixel loop. Objects of mixed sizes (a few large enough to overflow the record buffer
// at 1024 px tiles), each drawn 2-3 times in a row with random state between, sometimes a clear.
TEST(Differential, RepeatedDrawsReplayTheirFragments) {
    const DepthFunc funcs[] = {DepthFunc::Never,   DepthFunc::Less,     DepthFunc::Equal,  DepthFunc::LEqual,
                               DepthFunc::Greater, DepthFunc::NotEqual, DepthFunc::GEqual, DepthFunc::Always};
    // Seed 32 holds a draw too large to record at 1024 px tiles; sanitizer builds run 31-32 only.
    for (uint64_t seed = 31; seed <= (CULLIDE_SANITIZED ? 32u : 34u); ++seed) {
        const int W = 170, H = 160;
        const RandomScene base = randomScene(seed, W, H, 600, 0, 250.0);
        RandomScene s;
        s.geo = base.geo;
        std::mt19937_64 rng(seed + 1000);
        s.list.clear(1.0);
        for (int k = 0; k < 120; ++k) {
            const uint32_t first = uint32_t(rng() % 590);
            const uint32_t count = k % 50 == 7 ? 600 - first : 1 + uint32_t(rng() % 10);  // sometimes to the end
            const int repeats = 2 + int(rng() % 2);
            for (int r = 0; r < repeats; ++r) {
                s.list.depthFunc(funcs[rng() % 8]);
                s.list.depthMask(rng() % 2 == 0);
                const bool query = rng() % 3 != 0;
                if (query) s.list.beginQuery();
                s.list.draw(first, count);
                if (query) s.list.endQuery();
                if (rng() % 10 == 0) s.list.clear(0.25 + 0.75 * double(rng() % 4) / 3);
            }
            if (rng() % 4 == 0) s.list.draw(first, count + (first + count < 600 ? 1 : 0));  // a different range
        }
        const OrthoView view = windowView(W, H, seed % 2 ? DepthFormat::unorm(24) : DepthFormat::float32());
        CpuBackendOptions ref;
        ref.scalarReference = true;
        const Outcome expected = run(s, view, ref, 2);
        EXPECT_GT(expected.stats.passed, 0u);
        for (int tile : {16, 64, 1024})
            for (bool simd : {true, false}) {
                CpuBackendOptions fast;
                fast.tileSize = tile;
                fast.threads = 2;
                fast.simd = simd;
                expectSame(
                    expected, run(s, view, fast, 2),
                    "seed " + std::to_string(seed) + " tile " + std::to_string(tile) + (simd ? " simd" : " scalar"));
            }
    }
}

// Trap: a list that draws every triangle leaves its fragments captured per view, and a later list
// under that view replays them instead of setting up (view_cache.h). A draw must replay exactly
// its triangles' fragments in each tile (the runs found by triangle id), in record order, under
// its own state and query, with the statistics of its triangles' flags (rejected, clipped, zero
// area: the random scenes have all three), whatever the clears between; a second view must not
// replay the first's; a new geometry or a budget too small must not replay at all. Every list's
// results and statistics, and the final depth buffer, against the scalar path run on the same
// sequence; tiles that do not divide the viewport, both pixel loops, both depth kinds.
TEST(Differential, ViewCacheReplaysLaterLists) {
    for (uint64_t seed = 61; seed <= (CULLIDE_SANITIZED ? 61u : 63u); ++seed) {
        const int W = 90 + int(seed % 3) * 17, H = 70 + int(seed % 2) * 9;
        const RandomScene s = randomScene(seed, W, H, 500, 160);
        const uint32_t n = uint32_t(s.geo.triangles.size());
        // Cullide's pattern: every triangle drawn in a few ranges, each twice, with queries.
        CommandList whole;
        whole.clear(1.0);
        const uint32_t cuts[] = {0, n / 5, n / 2, n / 2 + 3, n};
        for (int pass = 0; pass < 2; ++pass)
            for (int k = 0; k < 4; ++k) {
                const uint32_t first = cuts[pass ? 3 - k : k], count = cuts[(pass ? 3 - k : k) + 1] - first;
                whole.depthMask(false);
                whole.depthFunc(DepthFunc::GEqual);
                whole.beginQuery(k == 2 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
                whole.draw(first, count);
                whole.endQuery();
                whole.depthMask(true);
                whole.depthFunc(DepthFunc::Less);
                whole.draw(first, count);
            }
        // Every triangle drawn once: nothing recorded for replay, so the capture rasterizes again.
        CommandList once;
        once.clear(0.75);
        once.beginQuery();
        once.draw(n / 2, n - n / 2);
        once.endQuery();
        once.depthFunc(DepthFunc::Greater);
        once.draw(0, n / 2);
        const OrthoView v1 = windowView(W, H, seed % 2 ? DepthFormat::unorm(24) : DepthFormat::float32());
        OrthoView v2 = v1, v3 = v1;
        v2.xmin -= 3, v2.xmax -= 3;  // the same size, other pixels
        v3.ymin += 2, v3.ymax += 2;
        Geo moved = s.geo;
        for (Vec3f& p : moved.positions) p.y() += 0.75f;
        CpuBackendOptions ref;
        ref.scalarReference = true;
        for (int tile : {16, 64})
            for (bool simd : {true, false})
                for (size_t budget : {size_t(32) << 20, size_t(1)}) {
                    CpuBackendOptions fast;
                    fast.tileSize = tile;
                    fast.threads = 2;
                    fast.simd = simd;
                    fast.viewCacheBytes = budget;
                    const std::string what = "seed " + std::to_string(seed) + " tile " + std::to_string(tile) +
                        (simd ? " simd" : " scalar") + (budget > 1 ? "" : " no budget");
                    auto a = backendFor(s.geo, v1, ref), b = backendFor(s.geo, v1, fast);
                    // (view, list, replays when the budget allows)
                    const std::tuple<const OrthoView*, const CommandList*, bool> steps[] = {
                        {&v1, &whole, false}, {&v1, &s.list, true}, {&v2, &s.list, false}, {&v2, &whole, false},
                        {&v2, &s.list, true}, {&v1, &s.list, true}, {&v1, &whole, true},   {&v3, &once, false},
                        {&v3, &s.list, true}, {&v3, &whole, true},
                    };
                    for (size_t k = 0; k < std::size(steps); ++k) {
                        const auto& [view, list, replays] = steps[k];
                        a->setView(*view);
                        b->setView(*view);
                        const std::vector<uint64_t> expected = a->execute(*list), got = b->execute(*list);
                        EXPECT_EQ(expected, got) << what << " step " << k;
                        EXPECT_EQ(a->lastStats(), b->lastStats()) << what << " step " << k;
                        EXPECT_EQ(b->lastReplayedView(), replays && budget > 1) << what << " step " << k;
                    }
                    expectSame({{}, a->readDepth(), {}}, {{}, b->readDepth(), {}}, what);
                    // A new geometry: nothing captured for it yet.
                    a->setGeometry(moved.positions, moved.triangles);
                    b->setGeometry(moved.positions, moved.triangles);
                    EXPECT_EQ(a->execute(s.list), b->execute(s.list)) << what << " moved";
                    EXPECT_FALSE(b->lastReplayedView()) << what;
                    EXPECT_EQ(a->lastStats(), b->lastStats()) << what << " moved";
                    expectSame({{}, a->readDepth(), {}}, {{}, b->readDepth(), {}}, what + " moved");
                }
    }
}

// Trap: a captured fragment packs its triangle, depth code and place in 64 bits, the triangle on
// top, and a draw's run is found by comparing against (first << shift) and (end << shift): a
// draw ending at the last triangle must not overflow that. The place is the depth-buffer index
// from the tile's first pixel, its width following the tile's rows and the viewport's width, or,
// where that does not fit, x and y (FragLayout::axisBits). With float depth (32 bits):
// - 1024 x 520, 4096 triangles (13 bits): 512 px tiles fit the index exactly (511 * 1024 + 511 <
//   2^19: replay); 1024 px tiles, clipped to 1024 x 520, fit neither the index (519 * 1024 + 1023
//   >= 2^19) nor x and y (10 bits each): no capture;
// - 4096 x 64, 16384 triangles (15 bits), 64 px tiles: the index takes 18 bits, one too many, x and
//   y 12: replay from x and y.
// Small triangles, and the fast path without a view cache as the reference (the scalar path takes
// most of a minute on these viewports; the other Differential tests tie the two together).
TEST(Differential, ViewCacheAtTheLayoutsLimit) {
    struct Case {
        int W, H, triangles, tile;
        bool replays;
    };
    for (const Case& c :
         {Case{1024, 520, 4096, 512, true}, Case{1024, 520, 4096, 1024, false}, Case{4096, 64, 16384, 64, true}}) {
        const RandomScene s = randomScene(77, c.W, c.H, c.triangles, 0, 12.0);
        const uint32_t n = uint32_t(c.triangles), half = n / 2;
        CommandList whole, tail;
        whole.clear(1.0);
        for (int k = 0; k < 2; ++k) {
            whole.beginQuery();
            whole.draw(0, half);
            whole.endQuery();
            whole.beginQuery();
            whole.draw(half, n - half);
            whole.endQuery();
        }
        tail.clear(1.0);
        tail.depthFunc(DepthFunc::LEqual);
        for (uint32_t first : {n - 1, 100u, 0u}) {
            tail.beginQuery();
            tail.draw(first, n - first);
            tail.endQuery();
        }
        const OrthoView view = windowView(c.W, c.H, DepthFormat::float32());
        const std::string what = std::to_string(c.W) + " x " + std::to_string(c.H) + " tile " + std::to_string(c.tile);
        CpuBackendOptions ref, fast;
        ref.tileSize = fast.tileSize = c.tile;
        ref.viewCacheBytes = 0;
        auto a = backendFor(s.geo, view, ref), b = backendFor(s.geo, view, fast);
        for (const CommandList* list : {&whole, &tail, &whole}) {
            EXPECT_EQ(a->execute(*list), b->execute(*list)) << what;
            EXPECT_EQ(a->lastStats(), b->lastStats()) << what;
        }
        EXPECT_EQ(b->lastReplayedView(), c.replays) << what;
        expectSame({{}, a->readDepth(), {}}, {{}, b->readDepth(), {}}, what);
    }
}

// Trap: results depending on scheduling (shared counters, racing tiles, float sums) — identical
// depth buffers, results and stats for 1, 2 and 8 threads on larger random scenes.
TEST(Differential, ThreadCountInvariance) {
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);
    for (uint64_t seed = 100; seed < 104; ++seed) {
        const int W = CULLIDE_SANITIZED ? 200 : 512, H = CULLIDE_SANITIZED ? 150 : 384;
        const RandomScene s = randomScene(seed, W, H, CULLIDE_SANITIZED ? 3000 : 20000, 600, 80.0);
        const OrthoView view = windowView(W, H, seed % 2 ? DepthFormat::unorm(24) : DepthFormat::float32());
        CpuBackendOptions o;
        o.threads = 1;
        const Outcome one = run(s, view, o, 2);
        EXPECT_GT(one.stats.passed, 0u);
        for (int threads : {2, 8}) {
            o.threads = threads;
            expectSame(one, run(s, view, o, 2), "threads " + std::to_string(threads));
        }
    }
}

// Trap: the direct path (one thread, each range drawn once: raster/src/direct_path.h) sets up a
// block of triangles at a time and rasterizes them over the whole viewport in order. A record
// taken from the wrong lane of a batch, a clipped triangle's sub-triangles out of order or
// dropped, a block boundary (128 triangles) splitting a draw, statistics of rejected, clipped or
// edge-on triangles counted apart from the tiles', or the state of the draw taken wrongly would
// differ from the scalar path and from the tiles on the same thread. Random scenes with draws of
// up to a few hundred triangles, every format, both fill rules, with and without AVX2; then a
// list that draws a range twice must take the tiles (it replays there).
TEST(Differential, DirectPathEqualsScalarReferenceAndTiles) {
    const DepthFormat formats[] = {DepthFormat::unorm(8),  DepthFormat::unorm(16), DepthFormat::unorm(24),
                                   DepthFormat::unorm(31), DepthFormat::unorm(32), DepthFormat::float32()};
    for (uint64_t seed = 300; seed < (CULLIDE_SANITIZED ? 306u : 318u); ++seed) {
        std::mt19937_64 pick(seed * 31);
        const int W = 1 + int(pick() % 90), H = 1 + int(pick() % 90);
        RandomScene s = randomScene(seed, W, H, 700, 0, 150.0);
        // Disjoint draws of 0-300 triangles in a shuffled order, with state changes and queries.
        std::vector<std::pair<uint32_t, uint32_t>> ranges;
        for (uint32_t first = 0; first < 700;) {
            const uint32_t count = std::min<uint32_t>(700 - first, uint32_t(pick() % 301));
            ranges.emplace_back(first, count);
            first += std::max<uint32_t>(count, 1);
        }
        std::shuffle(ranges.begin(), ranges.end(), pick);
        const DepthFunc funcs[] = {DepthFunc::Never,   DepthFunc::Less,     DepthFunc::Equal,  DepthFunc::LEqual,
                                   DepthFunc::Greater, DepthFunc::NotEqual, DepthFunc::GEqual, DepthFunc::Always};
        s.list.clear(0.9);
        for (size_t k = 0; k < ranges.size(); ++k) {
            s.list.depthFunc(k % 3 == 0 ? funcs[pick() % 8] : DepthFunc::Less);
            s.list.depthMask(pick() % 4 != 0);
            if (pick() % 9 == 0) s.list.clear(0.7);
            const bool query = pick() % 2 == 0;
            if (query) s.list.beginQuery(pick() % 4 == 0 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
            s.list.draw(ranges[k].first, ranges[k].second);
            if (query) s.list.endQuery();
        }
        const OrthoView view = windowView(W, H, formats[seed % 6]);
        const CpuBackendOptions ref = scalarReference(seed, seed % 3 == 0 ? 4 : 8);
        const Outcome expected = run(s, view, ref, 2);
        EXPECT_GT(expected.stats.fragments, 0u);
        EXPECT_GT(expected.stats.clipped, 0u);
        for (bool simd : {true, false}) {
            CpuBackendOptions o = ref;
            o.scalarReference = false;
            o.threads = 1;
            o.simd = simd;
            const std::string what =
                "seed " + std::to_string(seed) + (simd ? " simd " : " scalar ") + view.depth.name();
            auto direct = backendFor(s.geo, view, o);
            for (int i = 0; i < 2; ++i) {  // the second list starts from the first's state, as run() does
                Outcome got;
                got.results = direct->execute(s.list);
                got.stats = direct->lastStats();
                EXPECT_TRUE(direct->lastRanDirect()) << what;
                if (i == 1) {
                    got.depth = direct->readDepth();
                    expectSame(expected, got, what + " direct");
                }
            }
            o.direct = false;
            const Outcome tiles = run(s, view, o, 2);
            expectSame(expected, tiles, what + " tiles");
        }
    }
    // A range drawn twice: the tiles, also on one thread; two threads go direct for small triangles
    // only (this scene's are mostly larger).
    const RandomScene s = randomScene(9, 40, 30, 50, 0);
    CommandList twice;
    twice.clear();
    twice.draw(3, 20);
    twice.depthFunc(DepthFunc::Equal);
    twice.draw(3, 20);
    CpuBackendOptions o;
    o.threads = 1;
    auto one = backendFor(s.geo, windowView(40, 30), o);
    one->execute(twice);
    EXPECT_FALSE(one->lastRanDirect());
    CommandList once;
    once.draw(3, 20);
    one->execute(once);
    EXPECT_TRUE(one->lastRanDirect());
    o.threads = 2;
    auto two = backendFor(s.geo, windowView(40, 30), o);
    two->execute(once);
    EXPECT_FALSE(two->lastRanDirect());
}

// Trap: on the direct path the four-wide setup computes the fragments and depth codes of records
// at most 2 x 2 pixels from its lanes (SmallFrags) and writes no record for them. A triangle
// collinear in window coordinates but not after snapping has no plane from its vertices
// (planeFrom's fallback, set up by the scalar step): a small form made from the lane's registers
// anyway would carry a NaN or wrong plane, and one left unmade would rasterize a record never
// written. With several threads such lists take the direct path too, their blocks set up in
// parallel a batch at a time (64 blocks of 128 triangles on two threads) and rasterized in order:
// a block rasterized before it is set up, or out of order, or a draw split wrongly between
// batches would differ. ~1 px triangles, a third of them collinear (their window coordinates are
// the positions: a 16 x 16 view of [0, 16]^2), in every lane of the batches of four; one scene
// long enough for several batches; unorm 16 and 24 and float, both fill rules; against the scalar path.
TEST(Differential, DirectPathSmallTrianglesWithoutAVertexPlane) {
    const DepthFormat formats[] = {DepthFormat::unorm(16), DepthFormat::unorm(24), DepthFormat::float32()};
    for (uint64_t seed = 0; seed < 6; ++seed) {
        std::mt19937_64 rng(seed + 700);
        auto ticks = [&](int n) { return float(int(rng() % uint64_t(n))) / 1024.0f; };  // exact in float
        RandomScene s;
        RandomScene collinearOnly;
        const int triangles = seed == 0 ? 20000 : 1200;
        for (int t = 0; t < triangles; ++t) {
            const float x = float(1 + rng() % 13) + ticks(1024), y = float(1 + rng() % 13) + ticks(1024);
            const float z = 0.1f + 0.8f * ticks(1024);
            if (rng() % 3 == 0) {  // p0, p0 + d, p0 + 2d: det = d.x * 2d.y - 2d.x * d.y = 0 exactly
                const float dx = ticks(768), dy = ticks(1536) - 0.75f, dz = ticks(64);
                const Vec3f p0(x, y, z), p1(x + dx, y + dy, z + dz), p2(x + 2 * dx, y + 2 * dy, z - dz);
                s.geo.tri(p0, p1, p2);
                collinearOnly.geo.tri(p0, p1, p2);
            } else {
                s.geo.tri({x, y, z}, {x + 1.5f - ticks(512), y + ticks(256), z + ticks(64)},
                          {x + ticks(256), y + 1.5f - ticks(512), z - ticks(64)});
            }
        }
        const uint32_t n = uint32_t(s.geo.triangles.size()), nc = uint32_t(collinearOnly.geo.triangles.size());
        s.list.clear();
        s.list.beginQuery(QueryKind::SamplesPassed);
        s.list.draw(0, n / 3);  // two draws, the second under another function
        s.list.depthFunc(DepthFunc::LEqual);
        s.list.draw(n / 3, n - n / 3);
        s.list.endQuery();
        collinearOnly.list.clear();
        collinearOnly.list.draw(0, nc);
        const OrthoView view = windowView(16, 16, formats[seed % 3]);
        // Coarse: snapping moves a vertex by up to 1/4 or 1/8 pixel.
        const CpuBackendOptions ref = scalarReference(seed, 1 + int(seed % 2));
        // The trap is armed: collinear triangles that snap to a non-zero area and cover a centre.
        EXPECT_GT(run(collinearOnly, view, ref).stats.fragments, 10u) << "seed " << seed;
        expectDirectOnThreads(s, view, ref, run(s, view, ref),
                              "seed " + std::to_string(seed) + " " + view.depth.name());
    }
}

// Trap: the direct path's small forms test edges in 32 bits from the pixel box's corner, exact only
// while the snapped triangle spans under three pixels; a box clipped to the viewport can be 1 x 1
// for a triangle thousands of pixels long (one vertex just inside a corner, the others far out
// but inside the guard band, so not clipped). Taking such a lane as small overflows the sums and
// loses or adds fragments. Slivers at all four corners among ~1 px triangles (so that two
// threads take the direct path too), S = 8 and 12, against the scalar path.
TEST(Differential, DirectPathLongTrianglesWithSmallBoxes) {
    for (uint64_t seed = 0; seed < 4; ++seed) {
        std::mt19937_64 rng(seed + 900);
        auto ticks = [&](int n) { return float(int(rng() % uint64_t(n))) / 1024.0f; };  // exact in float
        const float W = 16;
        RandomScene s;
        RandomScene longOnly;
        for (int t = 0; t < 7000; ++t) {
            const float z = 0.1f + 0.8f * ticks(1024);
            if (t % 7 == 3) {
                // Vertex a within 1.5 px of a corner, b and c 1000-4000 px beyond its two sides.
                const int corner = int(rng() % 4);
                const float sx = corner & 1 ? -1.0f : 1.0f, sy = corner & 2 ? -1.0f : 1.0f;
                const float cx = corner & 1 ? W : 0, cy = corner & 2 ? W : 0;
                const float far1 = 1000 + 3 * ticks(1024 * 1000), far2 = 1000 + 3 * ticks(1024 * 1000);
                const Vec3f a(cx + sx * (0.2f + ticks(1300)), cy + sy * (0.2f + ticks(1300)), z);
                const Vec3f b(cx - sx * far1, cy + sy * ticks(16 * 1024), z + ticks(64));
                const Vec3f c(cx + sx * ticks(16 * 1024), cy - sy * far2, z - ticks(64));
                s.geo.tri(a, b, c);
                longOnly.geo.tri(a, b, c);
            } else {
                const float x = float(1 + rng() % 13) + ticks(1024), y = float(1 + rng() % 13) + ticks(1024);
                s.geo.tri({x, y, z}, {x + 1.5f - ticks(512), y + ticks(256), z + ticks(64)},
                          {x + ticks(256), y + 1.5f - ticks(512), z - ticks(64)});
            }
        }
        const uint32_t n = uint32_t(s.geo.triangles.size());
        s.list.clear();
        s.list.beginQuery(QueryKind::SamplesPassed);
        s.list.draw(0, n);
        s.list.endQuery();
        longOnly.list.clear();
        longOnly.list.draw(0, uint32_t(longOnly.geo.triangles.size()));
        const OrthoView view = windowView(16, 16, seed % 2 ? DepthFormat::float32() : DepthFormat::unorm(24));
        const CpuBackendOptions ref = scalarReference(seed, seed < 2 ? 8 : 12);
        // Armed: the long triangles cover centres, unclipped (inside the guard band).
        const Outcome longs = run(longOnly, view, ref);
        EXPECT_GT(longs.stats.fragments, 50u) << "seed " << seed;
        EXPECT_EQ(longs.stats.clipped, 0u) << "seed " << seed;
        expectDirectOnThreads(s, view, ref, run(s, view, ref), "seed " + std::to_string(seed));
    }
}

// Trap: the direct path sets up groups of eight triangles at once where each is a small
// one-record triangle or has no record (setupSmallGroup8: the forms of the one-record lanes
// written one after another, the others' flags counted); the first group that is not such, and
// the rest of its block, go to the four-wide setup from the record the groups reached. A form
// written at the wrong place when lanes without a record come before it, a rejected lane counted
// as zero-area or the reverse, a group given up in its second half (a lane without a plane from
// its vertices) leaving the first half's forms counted, or the rest of a block set up from the
// wrong record would differ from the scalar path. ~1 px triangles and, in random lanes,
// triangles whose box holds no pixel centre, triangles of zero snapped area, triangles left of
// the viewport (rejected; some of them of zero area too), and, one in 40 or one in 400, one that
// ends the groups: clipped (a corner beyond the far plane), larger (a box of 4 x 4 pixels), or
// collinear in window coordinates but not after snapping; one and two threads against the
// scalar path, statistics included.
TEST(Differential, DirectPathGroupsOfEight) {
    const DepthFormat formats[] = {DepthFormat::unorm(24), DepthFormat::float32(), DepthFormat::unorm(16)};
    for (uint64_t seed = 0; seed < 6; ++seed) {
        std::mt19937_64 rng(seed + 1100);
        // Multiples of 1/256: exact in float and, at S = 8, on the subpixel grid (collinear corners stay so).
        auto ticks = [&](int n) { return float(int(rng() % uint64_t(n))) / 256.0f; };
        const uint64_t stopEvery = seed / 2 == 1 ? 40 : 400;  // seeds 2 and 3: both fill rules and precisions
        RandomScene s;
        for (int t = 0; t < 6000; ++t) {
            const float x = float(1 + rng() % 13) + ticks(256), y = float(1 + rng() % 13) + ticks(256);
            const float z = 0.1f + 0.8f * float(rng() % 1024) / 1024.0f;
            const uint64_t kind = rng() % 16;
            if (rng() % stopEvery == 0) {
                const uint64_t stop = rng() % 3;
                if (stop == 0) {  // clipped: one corner beyond the far plane
                    s.geo.tri({x, y, z}, {x + 1.5f, y, 1.5f}, {x, y + 1.5f, z});
                } else if (stop == 1) {  // larger: a box of 4 x 4 pixels
                    s.geo.tri({x - 1.6f, y - 1.6f, z}, {x + 1.6f, y - 1.6f, z}, {x, y + 1.6f, z});
                } else {  // collinear in window coordinates, not after snapping (S = 2)
                    const float dx = float(rng() % 768) / 1024.0f, dy = float(rng() % 1536) / 1024.0f - 0.75f;
                    s.geo.tri({x, y, z}, {x + dx, y + dy, z + 0.01f}, {x + 2 * dx, y + 2 * dy, z - 0.01f});
                }
            } else if (kind < 9) {  // ~1 px, one record
                s.geo.tri({x, y, z}, {x + 1.5f - ticks(128), y + ticks(64), z + 0.01f},
                          {x + ticks(64), y + 1.5f - ticks(128), z - 0.01f});
            } else if (kind < 11) {  // inside the square between four pixel centres: no centre in the box
                const float cx = std::floor(x) + 0.05f, cy = std::floor(y) + 0.05f;
                s.geo.tri({cx, cy, z}, {cx + 0.3f, cy + ticks(64), z}, {cx + ticks(64), cy + 0.3f, z});
            } else if (kind < 13) {  // zero snapped area at S = 8: three collinear corners on the grid
                const float dx = ticks(128), dy = ticks(128) - 0.25f;
                s.geo.tri({x, y, z}, {x + dx, y + dy, z}, {x + 2 * dx, y + 2 * dy, z});
            } else {  // left of the viewport, inside the guard band: rejected; a third of them flat too
                const float lx = -1.0f - ticks(512), d = kind == 15 ? 0.0f : 1.5f;
                s.geo.tri({lx, y, z}, {lx - 1.5f, y + d, z}, {lx - 0.75f, y + 1.5f - d / 2, z});
            }
        }
        const uint32_t n = uint32_t(s.geo.triangles.size());
        s.list.clear();
        s.list.beginQuery(QueryKind::SamplesPassed);
        s.list.draw(0, n / 2);  // two draws: the second starts inside a group of eight
        s.list.endQuery();
        s.list.depthFunc(DepthFunc::LEqual);
        s.list.draw(n / 2, n - n / 2);
        const OrthoView view = windowView(16, 16, formats[seed % 3]);
        const CpuBackendOptions ref = scalarReference(seed, seed < 3 ? 8 : 2);
        const Outcome expected = run(s, view, ref);
        // Armed: fragments, rejected and zero-area triangles; clipped ones where the groups stop often.
        EXPECT_GT(expected.stats.fragments, 2000u) << "seed " << seed;
        EXPECT_GT(expected.stats.rejected, 500u) << "seed " << seed;
        EXPECT_GT(expected.stats.zeroArea, 500u) << "seed " << seed;
        if (stopEvery == 40) {
            EXPECT_GT(expected.stats.clipped, 10u) << "seed " << seed;
        }
        expectDirectOnThreads(s, view, ref, expected, "seed " + std::to_string(seed) + " " + view.depth.name());
    }
}

// Trap: the tile kernel keeps a record's groups with fragments in batches (tile_kernels.cpp,
// rasterizeInTileAvx2: up to 512 groups, and the depth plane of up to 512 rows), running a batch
// when the next row might not fit. A batch run too late overflows them; one row's groups split
// between two batches, or a batch's rows taken from the wrong first row, would change fragments,
// depths or counts. Large triangles (many full rows of groups: a batch every few rows), tall
// slivers under a pixel wide across up to 1000 rows (most rows hold no fragment, so the rows,
// not the groups, fill a batch; 1024 px tiles hold them whole), drawn twice (written, then
// tested: the tiles, not the direct path), against the scalar path; 64 and 1024 px tiles, one and
// two threads, both depth kinds. Both kinds of batch end happen here (counted once: 2156 by
// groups, 192 by rows); a batch run too late writes past the kernel's stack arrays, which the
// ASan stage reports.
TEST(Differential, TileKernelBatchesOfTallAndWideRecords) {
    const int W = 300, H = 1100;
    std::mt19937_64 rng(31);
    auto uni = [&](double lo, double hi) { return lo + (hi - lo) * double(rng() >> 11) * 0x1p-53; };
    RandomScene s;
    for (int t = 0; t < 24; ++t) {
        const float z = float(uni(0.1, 0.9));
        if (t % 3 == 0) {  // large: a few hundred pixels across
            const double x = uni(0, W), y = uni(0, H);
            s.geo.tri(Vec3f(float(x), float(y), z), Vec3f(float(x + uni(150, 400)), float(y + uni(-50, 50)), z + 0.05f),
                      Vec3f(float(x + uni(-50, 50)), float(y + uni(150, 600)), z - 0.05f));
        } else {  // a sliver 0.1-0.8 px wide, 600-1050 rows tall, leaning 3-40 px
            const double x = uni(10, W - 50), y = uni(0, 40), h = uni(600, 1050), lean = uni(3, 40), w = uni(0.1, 0.8);
            s.geo.tri(Vec3f(float(x), float(y), z), Vec3f(float(x + w), float(y), z),
                      Vec3f(float(x + lean), float(y + h), z + 0.02f));
        }
    }
    const uint32_t n = uint32_t(s.geo.triangles.size());
    s.list.clear(1.0);
    for (uint32_t first : {0u, n / 2}) {
        const uint32_t count = first == 0 ? n / 2 : n - n / 2;
        s.list.depthFunc(DepthFunc::Less);
        s.list.draw(first, count);
        s.list.depthMask(false);
        s.list.depthFunc(DepthFunc::GEqual);
        s.list.beginQuery(QueryKind::SamplesPassed);
        s.list.draw(first, count);
        s.list.endQuery();
        s.list.depthMask(true);
    }
    for (const DepthFormat& format : {DepthFormat::unorm(24), DepthFormat::float32()}) {
        const OrthoView view = windowView(W, H, format);
        CpuBackendOptions ref;
        ref.scalarReference = true;
        const Outcome expected = run(s, view, ref);
        EXPECT_GT(expected.stats.fragments, 50000u);  // armed: the large triangles drew
        for (int tile : {64, 1024})
            for (int threads : {1, 2}) {
                CpuBackendOptions fast;
                fast.tileSize = tile;
                fast.threads = threads;
                expectSame(expected, run(s, view, fast),
                           format.name() + " tile " + std::to_string(tile) + " threads " + std::to_string(threads));
            }
    }
}

// Trap: setup writes each chunk of 1024 triangles into a slot of one record per triangle; a chunk
// of triangles clipped into several sub-triangles outgrows its slot, spills, and every slot moves
// (records.cpp). A wrong shift of the record ranges, a spilled chunk's records lost, or a spill
// left over into the next list would change counts or depth against the scalar path. Three
// chunks, the middle one all triangles crossing both depth planes (3 sub-triangles each); draws
// within and across chunks; then a list without clipping on the same backend.
TEST(Differential, ClippedChunksSpillTheirSlots) {
    const int W = 96, H = 80, kChunk = 1024;
    std::mt19937_64 rng(4242);
    auto uni = [&](double lo, double hi) { return lo + (hi - lo) * double(rng() >> 11) * 0x1p-53; };
    Geo geo;
    for (int t = 0; t < 3 * kChunk; ++t) {
        const bool crossing = t >= kChunk && t < 2 * kChunk;
        const double cx = uni(5, W - 5), cy = uni(5, H - 5), r = crossing ? uni(4, 12) : uni(0.5, 4);
        const double z = uni(0.2, 0.8);
        geo.tri(Vec3f(float(cx - r), float(cy - r), float(crossing ? -0.5 : z)),
                Vec3f(float(cx + r), float(cy - r * 0.3), float(crossing ? 0.5 : z + 0.1)),
                Vec3f(float(cx), float(cy + r), float(crossing ? 1.5 : z - 0.1)));
    }
    CommandList clipped;
    clipped.clear(1.0);
    for (const auto& [first, count] : std::vector<std::pair<uint32_t, uint32_t>>{
             {0, 3 * kChunk}, {kChunk + 100, 50}, {kChunk - 10, 30}, {2 * kChunk - 5, 400}, {0, 3 * kChunk}}) {
        clipped.depthFunc(count == 50 ? DepthFunc::Always : DepthFunc::Less);
        clipped.beginQuery();
        clipped.draw(first, count);
        clipped.endQuery();
    }
    CommandList plain;
    plain.clear(1.0);
    plain.depthFunc(DepthFunc::LEqual);
    plain.beginQuery();
    plain.draw(0, kChunk);
    plain.endQuery();
    plain.beginQuery();
    plain.draw(2 * kChunk, kChunk);
    plain.endQuery();
    const OrthoView view = windowView(W, H, DepthFormat::unorm(24));
    auto runBoth = [&](const CpuBackendOptions& o) {
        auto b = backendFor(geo, view, o);
        Outcome first, second;
        first.results = b->execute(clipped);
        first.stats = b->lastStats();
        first.depth = b->readDepth();
        second.results = b->execute(plain);
        second.stats = b->lastStats();
        second.depth = b->readDepth();
        return std::pair{first, second};
    };
    CpuBackendOptions ref;
    ref.scalarReference = true;
    const auto expected = runBoth(ref);
    // The middle chunk is clipped (every triangle of it, in each of its draws) and draws something.
    EXPECT_GE(expected.first.stats.clipped, uint64_t(2 * kChunk));
    EXPECT_EQ(expected.second.stats.clipped, 0u);
    EXPECT_GT(expected.first.results[1], 0u);
    for (int tile : {16, 64}) {
        CpuBackendOptions fast;
        fast.tileSize = tile;
        fast.threads = 2;
        const auto got = runBoth(fast);
        expectSame(expected.first, got.first, "clipped list, tile " + std::to_string(tile));
        expectSame(expected.second, got.second, "plain list after it, tile " + std::to_string(tile));
    }
}

// ---------------------------------------------------------------------------------------------
// Tiles (OrthoView::tile): Cullide draws a viewport larger than a backend's limit in tiles.

// Trap: a tile whose window coordinates are not exactly the whole view's shifted by its origin
// (a box recomputed per tile, the scale taken from the tile's size instead of the grid's) samples
// another grid: fragments, depths, query or conflict counts differ at the tile's pixels. (The
// conservative depth error bound is taken over the grid's pixels too, conservative.cpp; it moves
// an interval by ~1e-14 of a stored step, and no case here is sensitive to it.) A view whose
// pixels have no dyadic size (so toWindow rounds), tiles that do not divide it, each on a fresh
// backend: its depth image is the whole view's sub-rectangle, and its counts add up
// (ANY_SAMPLES_PASSED: their maximum) to the whole view's, for the depth-test and the conservative
// commands. Vertices beyond the guard band are left out: it lies at a fixed distance from the
// tile's own origin, the one rule not invariant under the shift (no fitted view reaches it).
TEST(Tiles, TilesHoldTheWholeViewsFragments) {
    for (uint64_t seed = 201; seed <= 204; ++seed) {
        const int W = 150, H = 110;
        RandomScene s = randomScene(seed, W, H, 400, 150);
        for (Vec3f& p : s.geo.positions) p.x() = std::clamp(p.x(), -1000.0f, 1000.0f);
        OrthoView view = windowView(W, H, seed % 2 ? DepthFormat::unorm(24) : DepthFormat::float32());
        view.xmin = -0.37, view.xmax = 151.3, view.ymin = 0.71, view.ymax = 109.9;
        CommandList conservative;
        conservative.clearIntervals();
        for (uint32_t i = 0; i < uint32_t(s.geo.triangles.size()); ++i) {
            conservative.beginQuery();
            conservative.drawConservative(i, 1, true, true);
            conservative.endQuery();
        }
        std::vector<uint8_t> any;
        for (const Command& c : s.list.commands())
            if (c.op == Command::Op::BeginQuery) any.push_back(c.queryKind == QueryKind::AnySamplesPassed);

        CpuBackendOptions o;
        o.threads = 2;
        auto whole = backendFor(s.geo, view, o);
        const std::vector<uint64_t> want = whole->execute(s.list);
        const DepthImage wantDepth = whole->readDepth();
        const std::vector<uint64_t> wantConflicts = whole->execute(conservative);
        std::vector<uint64_t> got(want.size(), 0), gotConflicts(wantConflicts.size(), 0);
        size_t depthDiffers = 0;
        const int side = seed % 2 ? 64 : 37;
        for (int y = 0; y < H; y += side)
            for (int x = 0; x < W; x += side) {
                const OrthoView tile = view.tile(x, y, std::min(side, W - x), std::min(side, H - y));
                auto b = backendFor(s.geo, tile, o);
                const std::vector<uint64_t> r = b->execute(s.list);
                ASSERT_EQ(r.size(), got.size());
                for (size_t q = 0; q < r.size(); ++q) got[q] = any[q] ? std::max(got[q], r[q]) : got[q] + r[q];
                const DepthImage d = b->readDepth();
                for (int j = 0; j < tile.height; ++j)
                    for (int i = 0; i < tile.width; ++i) depthDiffers += d.at(i, j) != wantDepth.at(x + i, y + j);
                const std::vector<uint64_t> c = b->execute(conservative);
                for (size_t q = 0; q < c.size(); ++q) gotConflicts[q] += c[q];
            }
        EXPECT_EQ(got, want) << "seed " << seed;
        EXPECT_EQ(depthDiffers, 0u) << "seed " << seed;
        EXPECT_EQ(gotConflicts, wantConflicts) << "seed " << seed;
        uint64_t fragments = 0;
        for (uint64_t c : wantConflicts) fragments += c;
        EXPECT_GT(fragments, 0u) << "sanity: the conservative draws conflict somewhere";
    }
}

// Trap: the window transform done only for the vertices a list draws (a list that draws few
// triangles of a large geometry, as the deep reducePCS calls do): a vertex left untransformed, one
// still holding the previous view's coordinates (a stale stamp), a shared vertex, or a later list
// under the same view that draws other triangles, or all of them. A grid mesh (shared vertices)
// under two views; on one backend, lists of a few ranges after the view changes; on another, the
// same lists after a list that draws everything under the same view (every vertex transformed):
// same counts and depth images.
TEST(CpuBackend, WindowOfTheDrawnVerticesOnly) {
    Geo g;
    const int nx = 60, ny = 40;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i)
            g.add(float(i) * 1.7f + 0.3f * float(j % 3), float(j) * 1.9f, float((i * 7 + j * 3) % 11) / 11.0f);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const uint32_t a = uint32_t(j * (nx + 1) + i), b = a + 1, c = a + uint32_t(nx + 1), d = c + 1;
            g.tri(a, b, d);
            g.tri(a, d, c);
        }
    const uint32_t n = uint32_t(g.triangles.size());
    OrthoView first = windowView(120, 90), second = windowView(160, 100);
    first.xmax = 100, first.ymax = 75;
    second.xmin = 5, second.xmax = 105.5, second.ymin = -3, second.ymax = 80;
    auto ranges = [](std::initializer_list<std::array<uint32_t, 2>> rs) {
        CommandList l;
        l.clear(1.0);
        for (const auto& r : rs) {
            l.beginQuery();
            l.draw(r[0], r[1]);
            l.endQuery();
        }
        return l;
    };
    const CommandList all = ranges({{0, n}});
    const CommandList few = ranges({{10, 30}, {900, 40}, {4000, 25}});
    const CommandList others = ranges({{11, 30}, {2500, 60}, {4700, 10}});  // overlapping and new vertices
    CpuBackendOptions o;
    o.threads = 2;
    auto sparse = backendFor(g, first, o), dense = backendFor(g, second, o);
    sparse->execute(all);  // every vertex transformed under the first view
    sparse->setView(second);
    dense->execute(all);
    for (const CommandList* l : {&few, &others, &all, &few}) {
        const std::vector<uint64_t> got = sparse->execute(*l), want = dense->execute(*l);
        EXPECT_EQ(got, want);
        EXPECT_EQ(sparse->readDepth().values, dense->readDepth().values);
        uint64_t covered = 0;
        for (uint64_t c : want) covered += c;
        EXPECT_GT(covered, 0u) << "sanity: the ranges cover pixels";
    }
}

// Trap: releaseScratch() (trace recording frees the records between frames) leaving the backend
// without per-tile state or with stale records: lists after it, with and without a new view,
// must give what a backend that never released gives, for the plain and the conservative path.
TEST(CpuBackend, ReleaseScratchKeepsResults) {
    const RandomScene s = randomScene(77, 90, 70, 500, 200);
    const OrthoView view = windowView(90, 70, DepthFormat::unorm(24));
    CpuBackendOptions o;
    o.threads = 2;
    o.tileSize = 16;
    auto kept = backendFor(s.geo, view, o), released = backendFor(s.geo, view, o);
    CommandList cons;
    cons.clearIntervals();
    cons.beginQuery();
    cons.drawConservative(0, 200, true, true);
    cons.endQuery();
    for (int round = 0; round < 3; ++round) {
        if (round == 2) {  // a new view after a release: the tile state is made again
            const OrthoView other = windowView(70, 90, DepthFormat::float32());
            kept->setView(other);
            released->setView(other);
        }
        EXPECT_EQ(kept->execute(s.list), released->execute(s.list)) << "round " << round;
        EXPECT_EQ(kept->execute(cons), released->execute(cons)) << "round " << round;
        EXPECT_EQ(kept->readDepth().values, released->readDepth().values) << "round " << round;
        released->releaseScratch();
    }
}

// Trap: borrowGeometry (trace recording lends the pipeline's arrays) answering differently from
// setGeometry, or still reading the lender's arrays after releaseScratch, when they may be gone:
// a draw then finds no geometry and is refused.
TEST(CpuBackend, BorrowedGeometryIsForgottenOnRelease) {
    const RandomScene s = randomScene(78, 80, 60, 400, 150);
    const OrthoView view = windowView(80, 60, DepthFormat::unorm(24));
    auto copied = backendFor(s.geo, view, {});
    auto lender = raster::makeCpuBackend();
    lender->borrowGeometry(s.geo.positions, s.geo.triangles);
    lender->setView(view);
    EXPECT_EQ(copied->execute(s.list), lender->execute(s.list));
    EXPECT_EQ(copied->readDepth().values, lender->readDepth().values);
    lender->releaseScratch();
    CommandList draw;
    draw.draw(0, 1);
    EXPECT_THROW(lender->execute(draw), InputError);
}

// ---------------------------------------------------------------------------------------------
// Resolutions and formats

// Number of centres strictly below the hypotenuse of the triangle (0,0), (W,0), (0,H); centres
// on the hypotenuse belong to the other side (it is a right edge: exclusive in both rules).
uint64_t lowerLeftCount(int64_t W, int64_t H) {
    uint64_t n = 0;
    for (int64_t j = 0; j < H; ++j)
        for (int64_t i = 0; i < W; ++i) n += (2 * i + 1) * H + (2 * j + 1) * W < 2 * W * H;
    return n;
}

// Trap: off-by-one at the viewport border, tiles at the right/top edge partly outside, 1-pixel
// and very elongated viewports, and the largest sizes.
TEST(Resolution, FromOneByOneToHuge) {
    std::vector<std::pair<int, int>> sizes = {{1, 1},     {1, 7},      {7, 1},    {3, 5},    {64, 64},  {65, 63},
                                              {500, 500}, {1024, 768}, {4096, 1}, {1, 4096}, {1000, 37}};
    if (!CULLIDE_SANITIZED) sizes.push_back({4096, 4096});
    for (auto [W, H] : sizes) {
        Geo g;
        g.quad(0, 0, float(W), float(H), 0.75f);
        g.tri(Vec3f(0, 0, 0.25f), Vec3f(float(W), 0, 0.25f), Vec3f(0, float(H), 0.25f));
        auto b = backendFor(g, windowView(W, H));
        CommandList l;
        l.clear();
        l.beginQuery();
        l.draw(0, 2);
        l.endQuery();
        l.beginQuery();
        l.draw(2, 1);
        l.endQuery();
        l.depthFunc(DepthFunc::Equal);
        l.beginQuery();
        l.draw(0, 2);
        l.endQuery();
        const auto r = b->execute(l);
        const uint64_t lower = lowerLeftCount(W, H);
        EXPECT_EQ(r[0], uint64_t(W) * uint64_t(H)) << W << "x" << H;
        EXPECT_EQ(r[1], lower) << W << "x" << H;
        EXPECT_EQ(r[2], uint64_t(W) * uint64_t(H) - lower) << W << "x" << H;
    }
}

// Trap: a format whose stored values are not the rounded plane depth, or that loses monotonicity.
// A ramp from z = 0 to 1 along x at every unorm width 8..32 and float; fast and reference agree.
TEST(Resolution, DepthBitsEightToThirtyTwoAndFloat) {
    Geo g;
    const int W = 64, H = 3;
    const uint32_t a = g.add(0, 0, 0), b = g.add(W, 0, 1), c = g.add(W, H, 1), d = g.add(0, H, 0);
    g.tri(a, b, c);
    g.tri(a, c, d);
    std::vector<DepthFormat> formats;
    for (int n = 8; n <= 32; ++n) formats.push_back(DepthFormat::unorm(n));
    formats.push_back(DepthFormat::float32());
    for (const DepthFormat& f : formats) {
        RandomScene s;
        s.geo = g;
        s.list.clear();
        s.list.draw(0, 2);
        CpuBackendOptions ref;
        ref.scalarReference = true;
        const Outcome expected = run(s, windowView(W, H, f), ref);
        expectSame(expected, run(s, windowView(W, H, f), {}), f.name());
        const double lsb = f.kind == DepthFormat::Kind::Float32 ? 1e-7 : 0.5 / (std::ldexp(1.0, f.bits) - 1);
        for (int i = 0; i < W; ++i) {
            const double z = (i + 0.5) / W;
            EXPECT_NEAR(expected.depth.depth(i, 1), z, lsb * 1.000001) << f.name() << " i=" << i;
            if (i > 0) {
                EXPECT_GT(expected.depth.at(i, 1), expected.depth.at(i - 1, 1)) << f.name();
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Debug pictures

// Trap: PNG output upside down or failing silently.
TEST(Png, WritesDepthAndMaskPictures) {
    Geo g;
    g.tri(Vec3f(0, 0, 0.2f), Vec3f(16, 0, 0.2f), Vec3f(0, 8, 0.8f));
    auto b = backendFor(g, windowView(16, 8));
    CommandList l;
    l.clear();
    l.draw(0, 1);
    b->execute(l);
    const std::string depthPath = ::testing::TempDir() + "cullide_png_test_depth.png";
    const std::string maskPath = ::testing::TempDir() + "cullide_png_test_mask.png";
    writeDepthPng(b->readDepth(), depthPath, {true, encodeDepth(1.0, DepthFormat{})});
    std::vector<uint8_t> mask(16 * 8);
    for (size_t i = 0; i < mask.size(); ++i) mask[i] = uint8_t(i % 7);
    writeMaskPng(16, 8, mask, maskPath);
    for (const std::string& p : {depthPath, maskPath}) {
        std::FILE* f = std::fopen(p.c_str(), "rb");
        ASSERT_NE(f, nullptr) << p;
        unsigned char head[24] = {};
        ASSERT_EQ(std::fread(head, 1, 24, f), 24u);
        std::fclose(f);
        EXPECT_EQ(head[1], 'P');
        EXPECT_EQ(head[2], 'N');
        EXPECT_EQ(head[3], 'G');
        EXPECT_EQ(head[19], 16);  // IHDR width (big endian, low byte)
        EXPECT_EQ(head[23], 8);  // IHDR height
        std::remove(p.c_str());
    }
    EXPECT_THROW(writeMaskPng(16, 8, mask, "/nonexistent-folder/x.png"), InputError);
    EXPECT_THROW(writeMaskPng(15, 8, mask, maskPath), InputError);
}

}  // namespace
}  // namespace cullide::raster
