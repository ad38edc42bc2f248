// Tests of the CPU backend's interface (cullide/raster/cpu_backend.h): options, buffers and their
// reuse, views drawn in tiles, the window transform of the drawn vertices only, scratch release and
// borrowed geometry, resolutions and depth formats from the smallest to the largest, and the debug
// pictures. Every random test uses a fixed seed.
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

using test::backendFor;
using test::expectSame;
using test::Geo;
using test::Outcome;
using test::RandomScene;
using test::randomScene;
using test::run;
using test::windowView;

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
