// Differential tests of the CPU backend's fast path (tiles, binning, records, the tile kernels
// and their replays) against the scalar reference path on random scenes, and across thread counts.
// Every random test uses a fixed seed. On failure, debug PNGs go to the gtest temp folder.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/png.h"
#include "cullide/raster/rules.h"

#include "raster_test_util.h"
#include "test_util.h"
#include "window_geometry.h"

#include <gtest/gtest.h>
#include <oneapi/tbb/global_control.h>

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
using test::scalarReference;
using test::windowView;

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

}  // namespace
}  // namespace cullide::raster
