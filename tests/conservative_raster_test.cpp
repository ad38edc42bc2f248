// Tests of the CPU backend's conservative mode (rules 10-13 of cullide/raster/rules.h): coverage
// of closed pixel squares by hand-built cases, outward depth rounding, the interval test, the
// soundness contract on random triangles (every pixel a point of the triangle lies in is covered,
// with that point's depth inside the stored interval), and the differential tests fast path vs
// scalar reference and across thread counts and tile sizes. Fixed seeds throughout.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/rules.h"

#include "window_geometry.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>
#include <set>

namespace cullide::raster {
namespace {

using test::backendFor;
using test::Geo;
using test::windowView;

// The pixels triangle t covers conservatively (written into an emptied interval buffer).
std::set<std::pair<int, int>> coverage(CpuBackend& b, uint32_t t) {
    CommandList l;
    l.clearIntervals();
    l.drawConservative(t, 1, false, true);
    b.execute(l);
    const IntervalImage img = b.readIntervals();
    std::set<std::pair<int, int>> px;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if (img.covered(x, y)) px.insert({x, y});
    return px;
}

// The samples the GL-like (not conservative) draw of triangle t passes with ALWAYS.
uint64_t samplesDrawn(CpuBackend& b, uint32_t t) {
    ImmediateContext ctx(b);
    ctx.depthFunc(DepthFunc::Always);
    ctx.beginQuery();
    ctx.draw(t, 1);
    return ctx.endQuery();
}

double codeValue(uint32_t code, const DepthFormat& f) {
    if (f.kind == DepthFormat::Kind::Float32) return double(std::bit_cast<float>(code));
    return double(code) / (std::ldexp(1.0, f.bits) - 1.0);
}

// ---------------------------------------------------------------------------------------------
// Outward rounding

// Trap: round-to-nearest can land on either side of z; the interval needs the codes just below
// and just above, also at the ends (z = 1 with 32 bits would overflow a naive floor + 1).
TEST(ConservativeRules, DepthRoundsOutwardForEveryFormat) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<DepthFormat> formats{DepthFormat::float32()};
    for (int n = 8; n <= 32; ++n) formats.push_back(DepthFormat::unorm(n));
    for (const DepthFormat& f : formats) {
        std::vector<double> zs{0.0, 1.0, 0.5, 1.0 / 3.0, std::nextafter(1.0, 0.0), 1e-300};
        for (int k = 0; k < 2000; ++k) zs.push_back(u(rng));
        if (f.kind == DepthFormat::Kind::Unorm)
            for (uint32_t c : {0u, 1u, 2u, 77u}) zs.push_back(double(c) / (std::ldexp(1.0, f.bits) - 1.0));
        for (double z : zs) {
            const uint32_t lo = encodeDepthDown(z, f), hi = encodeDepthUp(z, f);
            ASSERT_LE(codeValue(lo, f), z) << f.name() << " z=" << z;
            ASSERT_GE(codeValue(hi, f), z) << f.name() << " z=" << z;
            ASSERT_LE(hi - lo, 1u) << f.name() << " z=" << z;  // tight: adjacent codes or equal
            ASSERT_LE(lo, encodeDepth(z, f));
            ASSERT_GE(hi, encodeDepth(z, f));
        }
    }
}

// Trap: a fragment that spans exactly the stored interval's end must conflict (touching counts);
// strictly in front or strictly behind must not.
TEST(ConservativeRules, ConflictIsOverlapOfClosedIntervals) {
    EXPECT_TRUE(intervalConflicts(5, 10, 10, 20));  // touches the stored lo
    EXPECT_TRUE(intervalConflicts(20, 30, 10, 20));  // touches the stored hi
    EXPECT_FALSE(intervalConflicts(5, 9, 10, 20));  // strictly in front
    EXPECT_FALSE(intervalConflicts(21, 30, 10, 20));  // strictly behind
    EXPECT_FALSE(intervalConflicts(0, 0xfffffffeu, kEmptyIntervalLo, kEmptyIntervalHi));  // empty pixel
}

// ---------------------------------------------------------------------------------------------
// Coverage by hand

// Trap: the four closed squares meeting at a corner all touch a triangle whose vertex is that
// corner; point sampling covers none of them.
TEST(ConservativeCoverage, VertexOnAPixelCornerTouchesFourPixels) {
    Geo g;
    g.tri({2, 2, 0.5f}, {0.25f, 2, 0.5f}, {2, 0.25f, 0.5f});  // lower-left of corner (2, 2)
    auto b = backendFor(g, windowView(8, 8));
    const auto px = coverage(*b, 0);
    for (auto p :
         {std::pair{1, 1}, std::pair{2, 2}, std::pair{1, 2}, std::pair{2, 1}, std::pair{0, 1}, std::pair{1, 0}})
        EXPECT_TRUE(px.count(p)) << p.first << "," << p.second;
    EXPECT_FALSE(px.count({3, 3}));  // one pixel beyond the dilation
    EXPECT_FALSE(px.count({2, 3}));
}

// Trap: a zero-area triangle (a segment) produces no fragment in GL; conservatively it covers the
// pixels its segment passes through, and nothing more than a subpixel away.
TEST(ConservativeCoverage, DegenerateSegmentCoversItsPixels) {
    Geo g;
    g.tri({0.5f, 0.5f, 0.2f}, {5.5f, 0.5f, 0.8f}, {3.0f, 0.5f, 0.5f});
    auto b = backendFor(g, windowView(8, 8));
    const auto px = coverage(*b, 0);
    std::set<std::pair<int, int>> want;
    for (int x = 0; x <= 5; ++x) want.insert({x, 0});
    EXPECT_EQ(px, want);
    // The GL-like draw gives nothing.
    EXPECT_EQ(samplesDrawn(*b, 0), 0u);
}

// Trap: a diagonal segment crossing a pixel corner exactly touches the two pixels diagonal to it
// at that corner only (a separating-axis test with the segment's normal, not its bounding box).
TEST(ConservativeCoverage, DiagonalSegmentDoesNotCoverItsWholeBoundingBox) {
    Geo g;
    g.tri({0.5f, 0.5f, 0.5f}, {3.5f, 3.5f, 0.5f}, {2.0f, 2.0f, 0.5f});
    auto b = backendFor(g, windowView(8, 8));
    const auto px = coverage(*b, 0);
    for (int k = 0; k <= 3; ++k) EXPECT_TRUE(px.count({k, k}));
    // The line y = x passes through the corners (k, k): the squares (k-1, k) and (k, k-1) touch it.
    EXPECT_TRUE(px.count({0, 1}));
    EXPECT_TRUE(px.count({1, 0}));
    EXPECT_FALSE(px.count({0, 3}));  // inside the bounding box, far from the segment
    EXPECT_FALSE(px.count({3, 0}));
    EXPECT_FALSE(px.count({0, 2}));
}

// Trap: three coincident vertices: a point covers its pixel (and, on a pixel edge, both sides).
TEST(ConservativeCoverage, PointCoversItsPixel) {
    Geo g;
    g.tri({3.25f, 4.75f, 0.5f}, {3.25f, 4.75f, 0.5f}, {3.25f, 4.75f, 0.5f});
    g.tri({5.0f, 1.5f, 0.5f}, {5.0f, 1.5f, 0.5f}, {5.0f, 1.5f, 0.5f});  // on the edge x = 5
    auto b = backendFor(g, windowView(8, 8));
    EXPECT_EQ(coverage(*b, 0), (std::set<std::pair<int, int>>{{3, 4}}));
    EXPECT_EQ(coverage(*b, 1), (std::set<std::pair<int, int>>{{4, 1}, {5, 1}}));
}

// Trap: a sliver between two rows of pixel centres has positive area but covers no centre, so
// GL draws nothing; conservatively it covers the whole row it lies in.
TEST(ConservativeCoverage, SliverBetweenCentresCoversItsRow) {
    Geo g;
    g.tri({0.1f, 2.01f, 0.3f}, {9.9f, 2.02f, 0.3f}, {5.0f, 2.03f, 0.3f});
    auto b = backendFor(g, windowView(16, 16));
    const auto px = coverage(*b, 0);
    for (int x = 0; x <= 9; ++x) EXPECT_TRUE(px.count({x, 2})) << x;
    EXPECT_FALSE(px.count({10, 2}));
    EXPECT_FALSE(px.count({5, 3}));
    EXPECT_EQ(samplesDrawn(*b, 0), 0u);
}

// Trap: vertices far beyond the guard band cannot be snapped; the triangle must still cover every
// pixel it overlaps (here the whole viewport), with its vertex depth range.
TEST(ConservativeCoverage, HugeCoordinatesBeyondTheGuardBand) {
    Geo g;
    g.tri({-1e9f, -1e9f, 0.25f}, {3e9f, -1e9f, 0.25f}, {-1e9f, 3e9f, 0.75f});
    auto b = backendFor(g, windowView(16, 16));
    EXPECT_EQ(coverage(*b, 0).size(), 256u);
    const IntervalImage img = b->readIntervals();
    EXPECT_LE(codeValue(img.lo[0], img.format), 0.25);
    EXPECT_GE(codeValue(img.hi[0], img.format), 0.75);
}

// Trap: a scene far from the origin (world coordinates ~1e6, extent ~1) makes toWindow's rounding
// error large in pixels; coverage and depth must still contain the exact triangle.
TEST(ConservativeCoverage, FarFromTheOriginStillContainsTheTriangle) {
    Geo g;
    const float o = 1.0e6f;
    g.tri({o + 0.25f, o + 0.25f, o + 0.5f}, {o + 0.75f, o + 0.25f, o + 0.5f}, {o + 0.25f, o + 0.75f, o + 0.5f});
    OrthoView v;
    v.xmin = o, v.xmax = o + 1, v.ymin = o, v.ymax = o + 1, v.znear = o, v.zfar = o + 1;
    v.width = v.height = 16;
    auto b = backendFor(g, v);
    const auto px = coverage(*b, 0);
    // The exact triangle spans pixels 4..12 on each axis (x + y <= 12 in pixels).
    for (int x = 4; x <= 11; ++x) EXPECT_TRUE(px.count({x, 4})) << x;
    const IntervalImage img = b->readIntervals();
    const size_t k = 5 * 16 + 5;
    EXPECT_LE(codeValue(img.lo[k], img.format), 0.5);
    EXPECT_GE(codeValue(img.hi[k], img.format), 0.5);
}

// Trap: an edge-on triangle (zero area in view, but a depth range) must cover its segment with
// its whole depth range, so a triangle crossing it conflicts.
TEST(ConservativeCoverage, EdgeOnTriangleConflictsWithACrossingOne) {
    Geo g;
    g.tri({4, 1, 0.2f}, {4, 7, 0.2f}, {4, 4, 0.8f});  // edge-on: the plane x = 4
    g.tri({1, 3.5f, 0.5f}, {7, 3.5f, 0.5f}, {1, 4.5f, 0.5f});  // crosses it at depth 0.5
    g.tri({1, 3.5f, 0.9f}, {7, 3.5f, 0.9f}, {1, 4.5f, 0.9f});  // behind it everywhere
    auto b = backendFor(g, windowView(8, 8));
    CommandList l;
    l.clearIntervals();
    l.drawConservative(0, 1, false, true);
    l.beginQuery();
    l.drawConservative(1, 1, true, false);
    l.endQuery();
    l.beginQuery();
    l.drawConservative(2, 1, true, false);
    l.endQuery();
    const auto r = b->execute(l);
    EXPECT_GT(r[0], 0u);
    EXPECT_EQ(r[1], 0u);  // strictly behind: no conflict
    // The GL-like path sees nothing of the edge-on triangle.
    EXPECT_EQ(b->lastStats().rejected, 0u);
}

// Trap: two triangles sharing only a vertex always conflict at the pixel of that vertex, in any
// depth format: the reason adjacent triangles must be kept out of each other's tests.
TEST(ConservativeCoverage, TrianglesSharingAVertexAlwaysConflict) {
    for (const DepthFormat& f :
         {DepthFormat::unorm(8), DepthFormat::unorm(16), DepthFormat::unorm(32), DepthFormat::float32()}) {
        Geo g;
        g.tri({3.3f, 3.7f, 0.5f}, {0.2f, 3.7f, 0.1f}, {3.3f, 0.4f, 0.1f});
        g.tri({3.3f, 3.7f, 0.5f}, {7.2f, 3.7f, 0.9f}, {3.3f, 7.4f, 0.9f});
        auto b = backendFor(g, windowView(8, 8, f));
        CommandList l;
        l.clearIntervals();
        l.drawConservative(0, 1, false, true);
        l.beginQuery(QueryKind::AnySamplesPassed);
        l.drawConservative(1, 1, true, false);
        l.endQuery();
        EXPECT_EQ(b->execute(l)[0], 1u) << f.name();
    }
}

// ---------------------------------------------------------------------------------------------
// Soundness on random triangles: every sampled point of the triangle lies in a covered pixel
// whose interval contains its depth.

TEST(ConservativeContract, SampledPointsLieInCoveredPixelsAndIntervals) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int W = 32, H = 32;
    for (const DepthFormat& f :
         {DepthFormat::unorm(8), DepthFormat::unorm(24), DepthFormat::unorm(32), DepthFormat::float32()}) {
        // One backend per format, its geometry replaced per trial (a backend per trial: 42 s under
        // ThreadSanitizer and 12 s under ASan+UBSan; this way under 1 s in both).
        std::unique_ptr<CpuBackend> b;
        for (int trial = 0; trial < 300; ++trial) {
            Geo g;
            Vec3f p[3];
            const int kind = trial % 4;  // 0: general, 1: thin sliver, 2: edge-on (collinear xy), 3: tiny
            for (int k = 0; k < 3; ++k) p[k] = Vec3f(float(u(rng) * W), float(u(rng) * H), float(u(rng)));
            if (kind == 1) p[2] = p[0] + (p[1] - p[0]) * 0.5f + Vec3f(0, 0.01f, 0);
            if (kind == 2) {
                const float t = float(u(rng));
                p[2] = Vec3f(p[0].x() + t * (p[1].x() - p[0].x()), p[0].y() + t * (p[1].y() - p[0].y()), float(u(rng)));
            }
            if (kind == 3) p[1] = p[0] + Vec3f(0.01f, 0.003f, 0.1f), p[2] = p[0] + Vec3f(-0.002f, 0.01f, -0.1f);
            g.tri(p[0], p[1], p[2]);
            if (!b) b = backendFor(g, windowView(W, H, f));
            else b->setGeometry(g.positions, g.triangles);
            coverage(*b, 0);
            const IntervalImage img = b->readIntervals();
            for (int s = 0; s < 200; ++s) {
                double a = u(rng), c = u(rng);
                if (a + c > 1) a = 1 - a, c = 1 - c;
                if (s < 3) a = s == 1, c = s == 2;  // the vertices themselves
                // In long double: the exact point to ~1e-19, far below every bound.
                const long double x =
                    p[0].x() + a * ((long double)p[1].x() - p[0].x()) + c * ((long double)p[2].x() - p[0].x());
                const long double y =
                    p[0].y() + a * ((long double)p[1].y() - p[0].y()) + c * ((long double)p[2].y() - p[0].y());
                const long double z =
                    p[0].z() + a * ((long double)p[1].z() - p[0].z()) + c * ((long double)p[2].z() - p[0].z());
                const int i = std::min(int(std::floor(x)), W - 1), j = std::min(int(std::floor(y)), H - 1);
                if (i < 0 || j < 0) continue;
                ASSERT_TRUE(img.covered(i, j)) << f.name() << " trial " << trial << " pixel " << i << "," << j;
                const size_t k = size_t(j) * W + size_t(i);
                ASSERT_LE((long double)codeValue(img.lo[k], f),
                          std::max<long double>(0, std::min<long double>(1, z)) + 1e-18L)
                    << f.name() << " trial " << trial;
                ASSERT_GE((long double)codeValue(img.hi[k], f),
                          std::max<long double>(0, std::min<long double>(1, z)) - 1e-18L)
                    << f.name() << " trial " << trial;
            }
        }
    }
}

// Trap: the interval of a steep triangle over a pixel must be narrower than the triangle's whole
// range (the plane is used), yet contain the depth at the pixel's corners.
TEST(ConservativeContract, IntervalIsThePlaneOverThePixelNotTheWholeRange) {
    Geo g;
    g.tri({0, 0, 0.0f}, {16, 0, 1.0f}, {0, 16, 0.0f});  // z = x / 16
    auto b = backendFor(g, windowView(16, 16));
    coverage(*b, 0);
    const IntervalImage img = b->readIntervals();
    const size_t k = 2 * 16 + 5;  // pixel (5, 2): z in [5/16, 6/16]
    EXPECT_LE(codeValue(img.lo[k], img.format), 5.0 / 16);
    EXPECT_GE(codeValue(img.hi[k], img.format), 6.0 / 16);
    EXPECT_GT(codeValue(img.lo[k], img.format), 4.9 / 16);
    EXPECT_LT(codeValue(img.hi[k], img.format), 6.1 / 16);
}

// ---------------------------------------------------------------------------------------------
// Differential: fast path vs scalar reference, threads, tile sizes

struct Outcome {
    std::vector<uint64_t> results;
    RasterStats stats;
    IntervalImage img;
};

Outcome runRandom(uint64_t seed, const OrthoView& view, CpuBackendOptions o) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Geo g;
    const int n = 120;
    for (int t = 0; t < n; ++t) {
        const double cx = u(rng) * view.width, cy = u(rng) * view.height, s = t % 7 == 0 ? 40 : 4;
        Vec3f p[3];
        for (auto& q : p) q = Vec3f(float(cx + (u(rng) - 0.5) * s), float(cy + (u(rng) - 0.5) * s), float(u(rng)));
        if (t % 5 == 0) p[2] = p[0];  // a segment
        if (t % 11 == 0) p[1] = p[2] = p[0];  // a point
        g.tri(p[0], p[1], p[2]);
    }
    auto b = backendFor(g, view, o);
    Outcome out;
    CommandList l;
    l.clearIntervals();
    for (uint32_t k = 0; k < uint32_t(n); k += 3) {
        l.beginQuery(k % 2 ? QueryKind::SamplesPassed : QueryKind::AnySamplesPassed);
        l.drawConservative(k, std::min<uint32_t>(3, uint32_t(n) - k), true, k % 4 != 0);
        l.endQuery();
        if (k % 9 == 0) l.drawConservative(k, 1, false, true);
        if (k == 60) l.clearIntervals();
    }
    out.results = b->execute(l);
    out.stats = b->lastStats();
    out.img = b->readIntervals();
    return out;
}

void expectSame(const Outcome& a, const Outcome& b, const std::string& what) {
    EXPECT_EQ(a.results, b.results) << what;
    EXPECT_EQ(a.stats, b.stats) << what;
    EXPECT_EQ(a.img.lo, b.img.lo) << what;
    EXPECT_EQ(a.img.hi, b.img.hi) << what;
}

TEST(ConservativeDifferential, FastPathEqualsScalarReference) {
    for (uint64_t seed : {1, 2, 3})
        for (const DepthFormat& f : {DepthFormat::unorm(16), DepthFormat::unorm(32), DepthFormat::float32()}) {
            OrthoView v = windowView(64, 48, f);
            CpuBackendOptions fast, ref;
            fast.tileSize = 16;
            ref.scalarReference = true;
            expectSame(runRandom(seed, v, fast), runRandom(seed, v, ref),
                       "seed " + std::to_string(seed) + " " + f.name());
        }
}

TEST(ConservativeDifferential, ThreadCountAndTileSizeInvariance) {
    OrthoView v = windowView(128, 96);
    CpuBackendOptions base;
    base.threads = 1;
    const Outcome one = runRandom(5, v, base);
    for (int threads : {2, 4})
        for (int tile : {8, 64}) {
            CpuBackendOptions o;
            o.threads = threads;
            o.tileSize = tile;
            expectSame(one, runRandom(5, v, o), std::to_string(threads) + " threads, tile " + std::to_string(tile));
        }
}

// Trap: the conservative commands must leave the GL-like depth buffer alone, and a conservative
// draw needs a test or a write.
TEST(ConservativeCommands, DoNotTouchTheDepthBufferAndAreValidated) {
    Geo g;
    g.tri({1, 1, 0.5f}, {6, 1, 0.5f}, {1, 6, 0.5f});
    auto b = backendFor(g, windowView(8, 8));
    EXPECT_TRUE(b->supportsConservative());
    const DepthImage before = b->readDepth();
    coverage(*b, 0);
    EXPECT_EQ(b->readDepth().values, before.values);
    CommandList l;
    EXPECT_THROW(l.drawConservative(0, 1, false, false), InputError);
    l.drawConservative(0, 2, true, false);
    EXPECT_THROW(b->execute(l), InputError);  // beyond the geometry
}

}  // namespace
}  // namespace cullide::raster
