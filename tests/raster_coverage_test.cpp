// Tests of the CPU reference rasterizer's coverage: the fill rule on meshes sharing edges and
// vertices (every pixel centre covered once), clipping against the depth range and the guard band,
// and edge-on triangles. Every random test uses a fixed seed. On failure, debug PNGs go to the
// gtest temp folder.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/png.h"
#include "cullide/raster/rules.h"

#include "raster_test_util.h"
#include "test_util.h"
#include "window_geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

namespace cullide::raster {
namespace {

using test::alwaysQueries;
using test::backendFor;
using test::failPath;
using test::Geo;
using test::windowView;

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

}  // namespace
}  // namespace cullide::raster
