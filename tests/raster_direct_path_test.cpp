// Differential tests of the CPU backend's direct path (raster/src/fast/direct_path.h: a list run
// straight through, without tiles) against the scalar reference path and the tiles. Every random
// test uses a fixed seed. On failure, debug PNGs go to the gtest temp folder.
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
using test::expectDirectOnThreads;
using test::expectSame;
using test::Geo;
using test::Outcome;
using test::RandomScene;
using test::randomScene;
using test::run;
using test::scalarReference;
using test::windowView;

// Trap: the direct path (one thread, each range drawn once: raster/src/fast/direct_path.h) sets up a
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

}  // namespace
}  // namespace cullide::raster
