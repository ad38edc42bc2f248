// Differential tests of the CPU backend's view cache (raster/src/fast/view_cache.h: the fragments
// of lists that drew every triangle, replayed by later lists under the same view) against the
// scalar reference path. Every random test uses a fixed seed.
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
using test::RandomScene;
using test::randomScene;
using test::run;
using test::scalarReference;
using test::windowView;

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

// Trap: a call drawn in tiles of a few pixels (`prune --max-viewport 4`) sets a view per tile and
// captures each; the cache must find each tile's own fragments among hundreds (never a
// neighbour's, whose view differs only in its origin) and must not search them one by one (the
// time of every list grew with the tiles before it: 4 px tiles never finished). Every tile of a
// 60 x 44 view at 4 px, captured, then replayed: the results of the tiles against the scalar path
// on the whole view, and every replay a replay.
TEST(Differential, ViewCacheFindsEachOfManyTiles) {
    const int W = 60, H = 44, side = 4;
    const RandomScene s = randomScene(71, W, H, 120, 0);
    const uint32_t n = uint32_t(s.geo.triangles.size());
    CommandList whole;  // Cullide's pattern: every triangle drawn twice, with a query
    whole.clear(1.0);
    for (int pass = 0; pass < 2; ++pass) {
        whole.beginQuery();
        whole.draw(0, n);
        whole.endQuery();
    }
    const OrthoView view = windowView(W, H);
    CpuBackendOptions ref;
    ref.scalarReference = true;
    auto a = backendFor(s.geo, view, ref), b = backendFor(s.geo, view, {});
    const std::vector<uint64_t> expected = a->execute(whole);
    std::vector<OrthoView> tiles;
    for (int y = 0; y < H; y += side)
        for (int x = 0; x < W; x += side) tiles.push_back(view.tile(x, y, side, side));
    for (bool replay : {false, true}) {
        std::vector<uint64_t> sum(expected.size(), 0);
        for (const OrthoView& tile : tiles) {
            b->setView(tile);
            const std::vector<uint64_t> r = b->execute(whole);
            ASSERT_EQ(r.size(), sum.size());
            for (size_t q = 0; q < r.size(); ++q) sum[q] += r[q];
            EXPECT_EQ(b->lastReplayedView(), replay) << tile.originX << "," << tile.originY;
        }
        EXPECT_EQ(sum, expected) << (replay ? "replayed" : "captured");
    }
}

}  // namespace
}  // namespace cullide::raster
