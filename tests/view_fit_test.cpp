// Fitting each reducePCS call's view: fitView's box, adaptive resolution (adaptiveViewport and its
// runs), the whole-geometry fit, and calls drawn in tiles. CPU reference backend.
#include "cullide/cullide.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/options.h"
#include "cullide/parallel.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene_io.h"

#include "cullide_test_util.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <map>
#include <memory>
#include <set>

#include <tbb/task_arena.h>

using namespace cullide;
using cullide::test::box;
using cullide::test::contains;
using cullide::test::crossingTriangles;
using cullide::test::icosphere;
using cullide::test::prune;
using cullide::test::rotation;
using cullide::test::sceneOf;
using cullide::test::selfCrossingRibbon;


// Trap: adaptive resolution that depends on the thread count (a median or a sum gathered in
// whatever order the threads finish) would give a different view, hence a different PCS, per
// thread count. Same scene with --resolution auto: the same PCS, per-call viewports and counts.
TEST(Cullide, AdaptiveResolutionDeterministicAcrossThreads) {
    const Scene s = sceneOf({{icosphere(3), rotation(0.2, 0.3, 0.1)},
                             {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                             {selfCrossingRibbon(81), rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
    const CullideResult one = prune(s, CullMethod::Modified, 8, HierarchyKind::Connectivity, 1, 64, 4);
    for (int threads : {2, 4}) {
        const CullideResult r = prune(s, CullMethod::Modified, 8, HierarchyKind::Connectivity, threads, 64, 4);
        EXPECT_EQ(r.pcs, one.pcs) << threads << " threads";
        ASSERT_EQ(r.passes.size(), one.passes.size());
        for (size_t i = 0; i < r.passes.size(); ++i) {
            EXPECT_EQ(r.passes[i].width, one.passes[i].width) << i;
            EXPECT_EQ(r.passes[i].height, one.passes[i].height) << i;
            EXPECT_EQ(r.passes[i].nodesOut, one.passes[i].nodesOut) << i;
        }
    }
}

// Trap: a per-call viewport that is not recorded (or recorded as the option's) makes the
// statistics lie and the study's false-prune attribution refit the wrong view. A fixed run
// records its viewport in every call; an adaptive run never goes below its base and refines the
// calls on the small deep PCS (the 64x64 base is coarse for 2560 triangles). (Its crossings are
// checked on the boxes of InterpenetratingBoxesKeepCrossingTriangles.)
TEST(Cullide, AdaptiveResolutionRecordedPerCall) {
    const Scene s = sceneOf(
        {{icosphere(3), rotation(0.2, 0.3, 0.1)}, {icosphere(3), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))}});
    const CullideResult fixed = prune(s, CullMethod::Modified, 4, HierarchyKind::Connectivity, 0, 64);
    for (const PassStats& p : fixed.passes) {
        EXPECT_EQ(p.width, 64);
        EXPECT_EQ(p.height, 64);
        EXPECT_EQ(p.round, 0u);
    }
    const CullideResult adaptive = prune(s, CullMethod::Modified, 4, HierarchyKind::Connectivity, 0, 64, 4);
    int finer = 0;
    for (const PassStats& p : adaptive.passes) {
        EXPECT_TRUE(std::max(p.width, p.height) >= 64 || (p.width == 64 && p.height == 64))
            << p.width << "x" << p.height;
        EXPECT_LE(int64_t(p.width) * p.height, kDefaultAutoBudget);
        finer += std::max(p.width, p.height) > 64;
    }
    EXPECT_GT(finer, 0) << "no call was refined";
}

// The size rule itself (cullide.h): no PCS or large triangles give the base viewport exactly
// (so an adaptive run that never refines is the fixed run); small triangles a finer one in the
// PCS's aspect; the pixel budget and the backend's side limit shrink it, never past 1.
TEST(Cullide, AdaptiveViewportFollowsTheRule) {
    const Mesh big = box(Vec3f(0, 0, 0), Vec3f(2, 1, 1));
    const TriangleRange all{0, uint32_t(big.triangles.size())};
    const Vec3d z(0, 0, 1);
    EXPECT_EQ(adaptiveViewport(big.positions, big.triangles, {}, z, 4, 100, 80, kDefaultAutoBudget, kMaxViewportSide),
              std::make_pair(100, 80));
    // Seen along z the box covers 2 x 1 twice (front and back): 4 / 0.02^2 = 10000 pixels at the
    // base pixel (2/100), fewer than 4 base viewports (4 * 8000): the call wants finer pixels.
    const auto [w, h] =
        adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 4, 100, 80, kDefaultAutoBudget, kMaxViewportSide);
    // (The frame's right and up may be either of x and y.)
    EXPECT_GT(std::max(w, h), 100);
    EXPECT_NEAR(double(std::max(w, h)) / std::min(w, h), 2.0, 0.05) << "the PCS's aspect";
    EXPECT_EQ(adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 0.5, 100, 80, kDefaultAutoBudget,
                               kMaxViewportSide),
              std::make_pair(100, 80))
        << "coverage already above 0.5 base viewports";
    const auto [bw, bh] = adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 1000, 100, 80, 20000, 16384);
    EXPECT_LE(int64_t(bw) * bh, 20000);
    EXPECT_GE(std::max(bw, bh), 100) << "a budget of the base's size or more never goes coarser than the base";
    const auto [sw, sh] =
        adaptiveViewport(big.positions, big.triangles, {&all, 1}, z, 1000, 100, 80, kDefaultAutoBudget, 150);
    EXPECT_LE(std::max(sw, sh), 150);
}

// The view is fitted tightly: the PCS's projected bounds touch the viewport (square pixels), and
// its depth extent maps inside (0, 1) with margins, never onto the cleared far value. In each of
// the six axis directions (whose bounds come from the points' box, permuted and negated: a wrong
// axis or sign misses this) and one oblique direction (the dot products), on a box off the origin
// in every axis.
TEST(Cullide, FitViewIsTight) {
    const Mesh m = box(Vec3f(-1, -2, 3), Vec3f(5, 2, 4));
    const TriangleRange all{0, uint32_t(m.triangles.size())};
    for (const Vec3d& dir : {Vec3d(0, 0, 1), Vec3d(0, 0, -1), Vec3d(1, 0, 0), Vec3d(-1, 0, 0), Vec3d(0, 1, 0),
                             Vec3d(0, -1, 0), Vec3d(0.3, -1, 0.2)}) {
        SCOPED_TRACE(testing::Message() << "direction " << dir.transpose());
        const OrthoView v = fitView(m.positions, m.triangles, {&all, 1}, dir, 300, 100, DepthFormat::unorm(16));
        double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9, zmin = 1e9, zmax = -1e9;
        for (const Vec3f& p : m.positions) {
            const Vec3d w = v.toWindow(p);
            xmin = std::min(xmin, w.x()), xmax = std::max(xmax, w.x());
            ymin = std::min(ymin, w.y()), ymax = std::max(ymax, w.y());
            zmin = std::min(zmin, w.z()), zmax = std::max(zmax, w.z());
        }
        // The frame's right/up may be either world axis; whichever extent limits the pixel size
        // fills its side of the viewport exactly and the other is centred.
        const bool xFills = std::abs(xmin) < 1e-9 && std::abs(xmax - 300) < 1e-9;
        const bool yFills = std::abs(ymin) < 1e-9 && std::abs(ymax - 100) < 1e-9;
        EXPECT_TRUE(xFills || yFills) << xmin << " " << xmax << " " << ymin << " " << ymax;
        EXPECT_NEAR(xmin + xmax, 300, 1e-9);
        EXPECT_NEAR(ymin + ymax, 100, 1e-9);
        EXPECT_GT(zmin * 65535, 1.5);
        EXPECT_LT(zmax * 65535, 65535 - 1.5);
        EXPECT_NEAR((v.xmax - v.xmin) / 300, (v.ymax - v.ymin) / 100, 1e-12) << "square pixels";
    }
}

// Bad option values are refused with a message naming the option, before any work.
// Trap: a view fitted to every vertex of the geometry rather than to the triangles drawn (the
// first levels, which draw everything, fit their view from the vertices once each): a vertex no
// triangle uses, far away, would stretch the view and make every triangle sub-pixel. The same
// meshes with such a vertex give the same PCS and calls as without it.
TEST(Cullide, UnusedVerticesDoNotWidenTheView) {
    const Scene clean = sceneOf(
        {{icosphere(2), rotation(0.2, 0.3, 0.1)}, {icosphere(2), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))}});
    Mesh far = icosphere(2);
    far.positions.push_back(Vec3f(1000, -800, 600));  // used by no triangle
    const Scene withFar =
        sceneOf({{far, rotation(0.2, 0.3, 0.1)}, {icosphere(2), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))}});
    const CullideResult want = prune(clean, CullMethod::Modified, 8), got = prune(withFar, CullMethod::Modified, 8);
    EXPECT_FALSE(want.pcs.empty());
    EXPECT_EQ(got.pcs, want.pcs);
    ASSERT_EQ(got.passes.size(), want.passes.size());
    for (size_t i = 0; i < got.passes.size(); ++i) EXPECT_EQ(got.passes[i].nodesOut, want.passes[i].nodesOut) << i;
}

// --- Tiles: a call whose viewport exceeds the backend's largest side ---

// Trap: a backend whose largest viewport is smaller than a call's (a GPU's limits under
// `--resolution auto`, or a fixed size) must not change the PCS: clamping the viewport (coarser
// pixels), tiles that sample another grid, results of the tiles not added (or ANY_SAMPLES_PASSED
// added instead of or-ed), or a list that depends on the state the previous tile left would all
// change it. Every method, fixed and adaptive resolution, fit and clustered views: the PCS and
// every call's statistics equal the whole-view run's, and the calls really were tiled.
TEST(CullideTiles, TiledCallsKeepTheWholeViewsPcs) {
    {  // The limit itself: an absurd side is refused, and so is a view beyond it.
        auto cpu = raster::makeCpuBackend();
        EXPECT_THROW(raster::ViewportLimit(*cpu, 0), InputError);
        EXPECT_THROW(raster::ViewportLimit(*cpu, kMaxViewportSide + 1), InputError);
        raster::ViewportLimit limit(*cpu, 64);
        OrthoView v;
        v.width = 65, v.height = 10;
        EXPECT_THROW(limit.setView(v), InputError);
    }
    const Scene s = sceneOf({{icosphere(2), rotation(0.2, 0.3, 0.1)},
                             {icosphere(2), rotation(0.5, 0.1, 0.3, Vec3f(1.2f, 0.3f, 0.2f))},
                             {selfCrossingRibbon(41), rotation(0.31, 0.47, 0.23, Vec3f(0.5f, 0, 0))}});
    for (CullMethod method : {CullMethod::Original, CullMethod::Modified, CullMethod::Reliable})
        for (double autoCoverage : {0.0, 4.0})
            for (ViewMode views : {ViewMode::Fit, ViewMode::Clustered}) {
                CullideOptions o;
                o.method = method;
                o.views = views;
                o.width = o.height = autoCoverage > 0 ? 48 : 150;
                o.autoCoverage = autoCoverage;
                o.hierarchy.leafSize = 8;
                auto cpu = raster::makeCpuBackend();
                const CullideResult want = runCullide(s, *cpu, o);
                raster::ViewportLimit small(*cpu, 64);  // refuses larger views: Cullide must tile
                const CullideResult got = runCullide(s, small, o);
                const std::string what =
                    std::string(toString(method)) + (autoCoverage > 0 ? " auto " : " 150 ") + toString(views);
                EXPECT_EQ(got.pcs, want.pcs) << what;
                EXPECT_GT(small.tilesSet(), 0u) << what << ": nothing was tiled";
                ASSERT_EQ(got.passes.size(), want.passes.size()) << what;
                size_t tiledCalls = 0;
                for (size_t i = 0; i < got.passes.size(); ++i) {
                    EXPECT_EQ(got.passes[i].nodesOut, want.passes[i].nodesOut) << what << " call " << i;
                    EXPECT_EQ(got.passes[i].width, want.passes[i].width) << what << " call " << i;
                    EXPECT_EQ(got.passes[i].views, want.passes[i].views) << what << " call " << i;
                    EXPECT_EQ(want.passes[i].tiles, want.passes[i].views) << what << " call " << i;
                    tiledCalls += got.passes[i].tiles > got.passes[i].views;
                }
                EXPECT_GT(tiledCalls, 0u) << what << ": no call counts its tiles";
            }
}
