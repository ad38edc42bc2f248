// Tests of the backend-neutral interface (core/include/cullide/depth_backend.h): depth formats,
// views, command-list validation, the immediate context, DepthImage. The CPU backend serves as
// the concrete backend where one is needed.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"

#include "window_geometry.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace cullide {
namespace {

// Trap: the parser accepting junk ("d2x", "", "33") or the name round trip losing the kind.
TEST(DepthFormat, ParseNameAndResolution) {
    EXPECT_EQ(DepthFormat::parse("24"), DepthFormat::unorm(24));
    EXPECT_EQ(DepthFormat::parse("D16"), DepthFormat::unorm(16));
    EXPECT_EQ(DepthFormat::parse("unorm32"), DepthFormat::unorm(32));
    EXPECT_EQ(DepthFormat::parse("float"), DepthFormat::float32());
    EXPECT_EQ(DepthFormat::parse("F32"), DepthFormat::float32());
    EXPECT_EQ(DepthFormat::parse("d32f"), DepthFormat::float32());
    for (const char* bad : {"", "d", "7", "33", "d2x", "unorm", "float64", "-8", "d024"})
        EXPECT_THROW(DepthFormat::parse(bad), InputError) << bad;
    EXPECT_THROW(DepthFormat::unorm(7), InputError);
    EXPECT_THROW(DepthFormat::unorm(33), InputError);
    EXPECT_EQ(DepthFormat::unorm(24).name(), "D24");
    EXPECT_EQ(DepthFormat::float32().name(), "D32F");
    for (int n = 8; n <= 32; ++n) EXPECT_EQ(DepthFormat::parse(DepthFormat::unorm(n).name()), DepthFormat::unorm(n));
    EXPECT_EQ(DepthFormat::unorm(8).resolution(), 1.0 / 255.0);
    EXPECT_EQ(DepthFormat::unorm(32).resolution(), 1.0 / 4294967295.0);
    EXPECT_EQ(DepthFormat::float32().resolution(), std::ldexp(1.0, -24));
}

// Trap: toWindow mapping the box to the wrong corner (y down) or depth reversed.
TEST(OrthoView, ToWindowMapsTheBoxToTheViewport) {
    OrthoView v;
    v.xmin = -2;
    v.xmax = 2;
    v.ymin = 0;
    v.ymax = 1;
    v.znear = 10;
    v.zfar = 20;
    v.width = 400;
    v.height = 100;
    v.validate();
    const Vec3d lo = v.toWindow(Vec3f(-2, 0, 10)), hi = v.toWindow(Vec3f(2, 1, 20)),
                mid = v.toWindow(Vec3f(0, 0.5f, 15));
    EXPECT_EQ(lo, Vec3d(0, 0, 0));
    EXPECT_EQ(hi, Vec3d(400, 100, 1));
    EXPECT_EQ(mid, Vec3d(200, 50, 0.5));
}

// Trap: a frame that is not right-handed or not orthonormal for directions near the axes.
TEST(OrthoView, LookingBuildsARightHandedOrthonormalFrame) {
    for (const Vec3d& d :
         {Vec3d(0, 0, 1), Vec3d(0, 0, -1), Vec3d(1, 0, 0), Vec3d(0, -3, 0), Vec3d(1, 2, 3), Vec3d(-1e-9, 1, 1e-9)}) {
        OrthoView v = OrthoView::looking(d);
        EXPECT_NO_THROW(v.validate());
        EXPECT_NEAR((v.dir - d.normalized()).norm(), 0.0, 1e-15);
        EXPECT_NEAR(v.right.cross(v.up).dot(v.dir), 1.0, 1e-12);
    }
    EXPECT_THROW(OrthoView::looking(Vec3d(0, 0, 0)), InputError);
    EXPECT_THROW(OrthoView::looking(Vec3d(NAN, 0, 1)), InputError);
}

// Trap: accepting views the rasterizer cannot handle (empty box, huge viewport, bad frame).
TEST(OrthoView, ValidateRejectsBadViews) {
    auto bad = [](auto mutate) {
        OrthoView v;
        mutate(v);
        EXPECT_THROW(v.validate(), InputError);
    };
    bad([](OrthoView& v) { v.xmax = v.xmin; });
    bad([](OrthoView& v) { v.zfar = v.znear - 1; });
    bad([](OrthoView& v) { v.width = 0; });
    bad([](OrthoView& v) { v.height = 16385; });
    bad([](OrthoView& v) { v.right = Vec3d(1, 1, 0); });
    bad([](OrthoView& v) { v.up = Vec3d(0, -1, 0); });  // left-handed
    bad([](OrthoView& v) { v.ymin = -INFINITY; });
    bad([](OrthoView& v) { v.depth.bits = 40; });
    OrthoView ok;
    ok.width = 16384;
    ok.height = 1;
    EXPECT_NO_THROW(ok.validate());
}

// Trap: a tile's window coordinates computed from a box of its own (rounded differently from the
// whole view's) or scaled by the tile's size: a tile must be the whole view shifted by an exact
// integer, for any box, or the tiles of one call sample a different grid. And a tile that does not
// lie inside its grid, or an origin without a grid, is refused rather than drawn somewhere.
TEST(OrthoView, TileIsAnExactShiftOfTheWholeView) {
    OrthoView v = OrthoView::looking(Vec3d(0.3, -0.5, 0.8));
    v.xmin = -1.37, v.xmax = 2.11, v.ymin = -0.93, v.ymax = 1.29, v.znear = -2, v.zfar = 2.7;
    v.width = 301, v.height = 177;
    const OrthoView t = v.tile(128, 64, 128, 113);
    EXPECT_NO_THROW(t.validate());
    EXPECT_EQ(t.fullWidth(), 301);
    EXPECT_EQ(t.fullHeight(), 177);
    const OrthoView tt = t.tile(5, 7, 10, 10);  // a tile of a tile: origins add, the grid stays
    EXPECT_EQ(tt.originX, 133);
    EXPECT_EQ(tt.originY, 71);
    EXPECT_EQ(tt.fullWidth(), 301);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    for (int k = 0; k < 1000; ++k) {
        const Vec3f p(u(rng), u(rng), u(rng));
        const Vec3d a = v.toWindow(p), b = t.toWindow(p);
        EXPECT_EQ(b.x(), a.x() - 128);  // exactly, not nearly
        EXPECT_EQ(b.y(), a.y() - 64);
        EXPECT_EQ(b.z(), a.z());
    }
    EXPECT_THROW(v.tile(200, 0, 128, 10).validate(), InputError);  // beyond the grid's right side
    EXPECT_THROW(v.tile(-1, 0, 10, 10).validate(), InputError);
    OrthoView noGrid = v;
    noGrid.originX = 3;
    EXPECT_THROW(noGrid.validate(), InputError);
    OrthoView hugeGrid = v.tile(0, 0, 10, 10);
    hugeGrid.gridWidth = kMaxViewportSide + 1;
    EXPECT_THROW(hugeGrid.validate(), InputError);
}

// Trap: nested queries or an end without a begin slipping through to a backend.
TEST(CommandList, RejectsNestedAndUnbalancedQueries) {
    CommandList l;
    EXPECT_THROW(l.endQuery(), InputError);
    EXPECT_EQ(l.beginQuery(), 0u);
    EXPECT_THROW(l.beginQuery(), InputError);
    l.draw(0, 1);
    l.endQuery();
    EXPECT_THROW(l.endQuery(), InputError);
    EXPECT_EQ(l.beginQuery(QueryKind::AnySamplesPassed), 1u);
    EXPECT_TRUE(l.queryOpen());
    EXPECT_EQ(l.queryCount(), 2u);
    EXPECT_EQ(l.drawCount(), 1u);
    EXPECT_THROW(l.clear(1.5), InputError);
    EXPECT_THROW(l.clear(NAN), InputError);
    EXPECT_THROW(l.draw(0xFFFFFFF0u, 100), InputError);
    l.reset();
    EXPECT_EQ(l.commands().size(), 0u);
    EXPECT_FALSE(l.queryOpen());
}

struct TwoQuads : test::Geo {
    // Quad 0 at depth z0 (triangles 0,1), quad 1 at depth z1 (triangles 2,3), both covering
    // the whole view box [0,4] x [0,4].
    TwoQuads(float z0, float z1) {
        for (float z : {z0, z1}) quad(0, 0, 4, 4, z);
    }
};

OrthoView box4() {
    return test::windowView(4, 4);
}

// Trap: execute() running part of a list before finding a bad draw range or an open query.
TEST(DepthBackend, ExecuteValidatesBeforeRunning) {
    TwoQuads q(0.25f, 0.75f);
    auto b = raster::makeCpuBackend();
    CommandList l;
    l.clear();
    EXPECT_THROW(b->execute(l), InputError);  // no view yet
    b->setGeometry(q.positions, q.triangles);
    b->setView(box4());
    l.draw(0, 2);
    l.draw(3, 2);  // out of range
    EXPECT_THROW(b->execute(l), InputError);
    EXPECT_EQ(b->readDepth().values, std::vector<uint32_t>(16, 0xFFFFFFu));  // nothing ran
    CommandList open;
    open.beginQuery();
    EXPECT_THROW(b->execute(open), InputError);
}

// Trap: ImmediateContext splitting a query over several lists, or buffering outside queries.
TEST(ImmediateContext, BuffersOnlyInsideQueries) {
    TwoQuads q(0.25f, 0.75f);
    auto b = raster::makeCpuBackend();
    b->setGeometry(q.positions, q.triangles);
    b->setView(box4());
    ImmediateContext ctx(*b);
    ctx.clear(1.0);
    ctx.draw(0, 2);  // executed at once: the buffer holds 0.25
    EXPECT_EQ(b->readDepth().depth(1, 1), double(raster::encodeDepth(0.25, DepthFormat{}) / 16777215.0));
    ctx.beginQuery();
    ctx.depthFunc(DepthFunc::Greater);
    ctx.depthMask(false);
    ctx.draw(2, 2);
    EXPECT_EQ(b->lastStats().draws, 1u);  // the query's commands are still buffered
    EXPECT_EQ(ctx.endQuery(), 16u);
    EXPECT_EQ(b->lastStats().draws, 1u);
    EXPECT_THROW(ctx.endQuery(), InputError);
    ctx.beginQuery(QueryKind::AnySamplesPassed);
    EXPECT_THROW(ctx.beginQuery(), InputError);
    ctx.draw(0, 2);  // 0.25 > 0.25 fails
    EXPECT_EQ(ctx.endQuery(), 0u);
    ctx.beginQuery(QueryKind::AnySamplesPassed);
    ctx.draw(0, 4);
    EXPECT_EQ(ctx.endQuery(), 1u);
}

// Trap: depth function and mask reset between lists (GL state persists).
TEST(DepthBackend, StatePersistsAcrossLists) {
    TwoQuads q(0.25f, 0.75f);
    auto b = raster::makeCpuBackend();
    b->setGeometry(q.positions, q.triangles);
    b->setView(box4());
    CommandList a;
    a.clear();
    a.depthFunc(DepthFunc::Greater);
    a.depthMask(false);
    b->execute(a);
    CommandList c;
    c.beginQuery();
    c.draw(0, 2);  // GREATER against 1.0: nothing passes, and nothing would be written
    c.endQuery();
    EXPECT_EQ(b->execute(c), std::vector<uint64_t>{0});
    CommandList d;
    d.depthFunc(DepthFunc::Less);
    d.draw(0, 2);  // mask still off
    b->execute(d);
    EXPECT_EQ(b->readDepth().at(0, 0), 0xFFFFFFu);
}

// Trap: a resized viewport keeping stale contents, or DepthImage::depth misreading formats.
TEST(DepthBackend, ResizeResetsToFarAndDepthImageDecodes) {
    TwoQuads q(0.25f, 0.75f);
    auto b = raster::makeCpuBackend();
    b->setGeometry(q.positions, q.triangles);
    OrthoView v = box4();
    b->setView(v);
    CommandList l;
    l.clear(0.0);
    b->execute(l);
    v.width = 3;
    v.depth = DepthFormat::float32();
    b->setView(v);
    DepthImage img = b->readDepth();
    ASSERT_EQ(img.values.size(), 12u);
    EXPECT_EQ(img.depth(2, 3), 1.0);
    CommandList m;
    m.clear(0.5);
    b->execute(m);
    EXPECT_EQ(b->readDepth().depth(0, 0), 0.5);
    EXPECT_EQ(b->readDepth().at(0, 0), 0x3F000000u);
    v.depth = DepthFormat::unorm(8);
    b->setView(v);
    b->execute(m);
    EXPECT_EQ(b->readDepth().at(0, 0), 128u);  // 127.5 -> 128
    EXPECT_EQ(b->readDepth().depth(0, 0), 128.0 / 255.0);
}

}  // namespace
}  // namespace cullide
