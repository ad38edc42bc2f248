// Chosen directions (docs/cullide.md#chosen-directions): pcaFrame, pcaDirections and the coherent
// history, end to end on the CPU reference backend.
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

namespace {

// The triangles of `s` as one geometry and one range over all of them (pcaFrame's input).
struct Flat {
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    std::vector<TriangleRange> all() const { return {{0, uint32_t(triangles.size())}}; }
};
Flat flatOf(const Scene& s) {
    Flat f;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const Mesh m = s.worldMesh(i);
        const uint32_t base = uint32_t(f.positions.size());
        f.positions.insert(f.positions.end(), m.positions.begin(), m.positions.end());
        for (const Triangle& t : m.triangles) f.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    return f;
}

// |a . b| for unit vectors: 1 when they are the same line.
double sameLine(const Vec3d& a, const Vec3d& b) {
    return std::abs(a.normalized().dot(b.normalized()));
}

// Two boxes apart along x and a bar along x through both: every object crosses another.
Scene piercedBoxes() {
    return sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.05, 0.1, 0.02)},
                    {box(Vec3f(2, 0, 0), Vec3f(3, 1, 1)), rotation(0.03, -0.08, 0.04)},
                    {box(Vec3f(-0.5f, 0.4f, 0.45f), Vec3f(3.5f, 0.6f, 0.55f)), Transform::Identity()}});
}

CullideOptions coherentOptions(std::shared_ptr<DirectionHistory> history) {
    CullideOptions o;
    o.directionMode = DirectionMode::Coherent;
    o.directionHistory = std::move(history);
    o.hierarchy.leafSize = 1;
    o.width = o.height = 128;
    return o;
}

}  // namespace

// Trap: principal axes taken from the vertices (a box's vertex cloud is spread along its long
// side) or in Eigen's increasing order, or an eigenvector with an arbitrary sign. A 4 x 2 x 1 box
// turned by a known rotation: its face areas make the orientation tensor's axes the box's short
// side (faces of area 8), middle (4) and long side (2), in that order, each with its largest
// component positive.
TEST(CullideDirections, PcaFrameIsTheBoxsPrincipalAxes) {
    const Transform t = rotation(0.4, -0.7, 1.1, Vec3f(0.3f, -0.2f, 0.5f));
    const Scene s = sceneOf({{box(Vec3f(-2, -1, -0.5f), Vec3f(2, 1, 0.5f)), t}});
    const Flat f = flatOf(s);
    const std::vector<Vec3d> frame = pcaFrame(f.positions, f.triangles, f.all());
    ASSERT_EQ(frame.size(), 3u);
    const Eigen::Matrix3d r = t.linear().cast<double>();
    const Vec3d expected[3] = {r.col(2), r.col(1), r.col(0)};  // short, middle, long side
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(sameLine(frame[size_t(k)], expected[k]), 1.0, 1e-6) << k;
        EXPECT_NEAR(frame[size_t(k)].norm(), 1.0, 1e-12);
        int big = 0;
        for (int i = 1; i < 3; ++i)
            if (std::abs(frame[size_t(k)][i]) > std::abs(frame[size_t(k)][big])) big = i;
        EXPECT_GT(frame[size_t(k)][big], 0) << "sign fixed: largest component positive";
    }
    // The six directions: an orthonormal frame, both signs of each axis.
    const std::vector<Vec3d> dirs = pcaDirections(f.positions, f.triangles, f.all());
    ASSERT_EQ(dirs.size(), 6u);
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(dirs[size_t(2 * k + 1)], Vec3d(-dirs[size_t(2 * k)]));
        for (int j = 0; j < k; ++j) EXPECT_NEAR(dirs[size_t(2 * k)].dot(dirs[size_t(2 * j)]), 0.0, 1e-9);
    }
    // No area: the axes.
    const std::vector<Vec3f> flatPoints{Vec3f(0, 0, 0), Vec3f(1, 1, 1), Vec3f(2, 2, 2)};
    const std::vector<Triangle> degenerate{{0, 1, 2}};
    const std::vector<TriangleRange> one{{0, 1}};
    EXPECT_TRUE(pcaFrame(flatPoints, degenerate, one).empty());
    EXPECT_EQ(pcaDirections(flatPoints, degenerate, one), axisDirections());
}

// Trap: taking the principal axes themselves as views. For axis-aligned boxes (the frame is the
// axes) that is exactly the axis set, which sees every face edge-on from four directions and
// loses every crossing (Cullide.AxisAlignedBoxesLoseCrossingEdgeOn). pca turns the frame so
// that every face is seen at a slant from every view, and keeps them all.
TEST(CullideDirections, PcaKeepsTheCrossingsAxesLoseEdgeOn) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(2, 2, 2)), Transform::Identity()},
                             {box(Vec3f(1.1f, 1.3f, 0.7f), Vec3f(3, 3, 3)), Transform::Identity()}});
    const std::set<PcsTriangle> truth = crossingTriangles(s);
    ASSERT_GE(truth.size(), 4u);
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.hierarchy.leafSize = 1;
    EXPECT_TRUE(runCullide(s, *backend, o).pcs.empty()) << "axes lose them";
    o.directionMode = DirectionMode::Pca;
    const CullideResult r = runCullide(s, *backend, o);
    EXPECT_TRUE(contains(r, truth)) << "PCS " << r.pcs.size() << ", crossing " << truth.size();
    for (const PassStats& p : r.passes) {
        EXPECT_LT(p.direction, 6u);
        EXPECT_NEAR(p.dirVector.norm(), 1.0, 1e-12);
        double worst = 1;  // how near edge-on the boxes' faces are seen, over the axes
        for (int a = 0; a < 3; ++a) worst = std::min(worst, std::abs(p.dirVector[a]));
        EXPECT_GT(worst, 0.2) << "a view nearly in a face's plane";
    }
}

// Trap: the same loss on tilted flat geometry: two 4 x 4-cell sheets tilted +-3 degrees about x
// from the xy plane, crossing along the x axis. Both contain x, so from +-x both are segments:
// no fragments, "fully visible", pruned, whatever the resolution. Their normals are near z, and
// pca's views all face them at a slant.
TEST(CullideDirections, PcaKeepsTiltedSheetsAxesLoseEdgeOn) {
    auto sheet = [](double degrees) {
        const double a = degrees * std::numbers::pi / 180;
        Mesh m;
        for (int j = 0; j <= 4; ++j)
            for (int k = 0; k <= 4; ++k) {
                const double x = k / 4.0 - 0.5, t = j / 4.0 - 0.5;
                m.positions.push_back(Vec3f(float(x), float(t * std::cos(a)), float(t * std::sin(a))));
            }
        for (uint32_t j = 0; j < 4; ++j)
            for (uint32_t k = 0; k < 4; ++k) {
                const uint32_t c = j * 5 + k;
                m.triangles.push_back({c, c + 1, c + 6});
                m.triangles.push_back({c, c + 6, c + 5});
            }
        return m;
    };
    // B moved by (0.03, 0.02, 0.01): the crossing line (still along x) between A's grid rows and
    // B's edges off A's, so that the pairs cross generically.
    const Scene s =
        sceneOf({{sheet(3), Transform::Identity()}, {sheet(-3), rotation(0, 0, 0, Vec3f(0.03f, 0.02f, 0.01f))}});
    const std::set<PcsTriangle> truth = crossingTriangles(s);
    ASSERT_GE(truth.size(), 4u) << "the sheets must cross";
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.hierarchy.leafSize = 1;
    const CullideResult axes = runCullide(s, *backend, o);
    EXPECT_FALSE(contains(axes, truth)) << "axes keep every crossing: the trap is gone";
    o.directionMode = DirectionMode::Pca;
    const CullideResult pca = runCullide(s, *backend, o);
    EXPECT_TRUE(contains(pca, truth)) << "PCS " << pca.pcs.size() << ", crossing " << truth.size();
}

// Trap: pca's sums gathered in the order threads finish would turn the frame per thread count.
// The same PCS and the same directions, bit for bit, with 1 and with every thread.
TEST(CullideDirections, PcaDeterministicAcrossThreads) {
    SceneRequest q;
    q.triangles = 20000;
    const Scene s = makeSheets(6, 3.0, q).scene;
    auto run = [&](int threads) {
        raster::CpuBackendOptions bo;
        bo.threads = threads;
        auto backend = raster::makeCpuBackend(bo);
        CullideOptions o;
        o.directionMode = DirectionMode::Pca;
        CullideResult r;
        tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
        arena.execute([&] { r = runCullide(s, *backend, o); });
        return r;
    };
    const CullideResult one = run(1), all = run(0);
    EXPECT_EQ(one.pcs, all.pcs);
    ASSERT_EQ(one.passes.size(), all.passes.size());
    for (size_t i = 0; i < one.passes.size(); ++i) EXPECT_EQ(one.passes[i].dirVector, all.passes[i].dirVector) << i;
}

// Trap: a history that starts empty and prunes with no directions (or an arbitrary subset).
// The first frame, and a run without a history, use the whole list in the given order.
TEST(CullideDirections, CoherentFirstFrameIsTheFullList) {
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.2, 0.3, 0.1)},
                             {box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), rotation(0.5, 0.1, 0.3, Vec3f(0.6f, 0.2f, 0))}});
    auto backend = raster::makeCpuBackend();
    for (bool withHistory : {false, true}) {
        auto history = withHistory ? std::make_shared<DirectionHistory>() : nullptr;
        const CullideResult r = runCullide(s, *backend, coherentOptions(history));
        std::vector<uint32_t> level0;
        for (const PassStats& p : r.passes)
            if (p.level == 0) level0.push_back(p.direction);
        EXPECT_EQ(level0, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
        CullideOptions fixed = coherentOptions(nullptr);
        fixed.directionMode = DirectionMode::Fixed;
        EXPECT_EQ(r.pcs, runCullide(s, *backend, fixed).pcs);
        if (history) {
            EXPECT_EQ(history->frames, 1u);
        }
    }
}

// Trap: a direction that pruned nothing kept next frame (no saving), or one that pruned dropped.
// Two boxes pierced by a bar: at the object level nothing can be pruned from any direction (the
// bar crosses both), so the next frame makes no object-level call; at every level below, the
// next frame makes exactly the calls that pruned something, in the given order; the PCS stays.
TEST(CullideDirections, CoherentDropsADirectionThatPrunedNothing) {
    const Scene s = piercedBoxes();
    auto backend = raster::makeCpuBackend();
    auto history = std::make_shared<DirectionHistory>();
    const CullideResult first = runCullide(s, *backend, coherentOptions(history));
    std::map<uint32_t, std::vector<uint32_t>> pruning;  // level -> directions that pruned
    for (const PassStats& p : first.passes) {
        if (p.level == 0) {
            EXPECT_EQ(p.trianglesOut, p.trianglesIn) << "the object level prunes nothing";
        }
        if (p.trianglesOut < p.trianglesIn) pruning[p.level].push_back(p.direction);
    }
    ASSERT_FALSE(pruning.empty());
    ASSERT_EQ(history->pruned.size(), first.levels);
    const CullideResult second = runCullide(s, *backend, coherentOptions(history));
    std::map<uint32_t, std::vector<uint32_t>> made;
    for (const PassStats& p : second.passes) made[p.level].push_back(p.direction);
    EXPECT_EQ(made.count(0), 0u) << "no object-level call";
    for (const auto& [level, dirs] : made) EXPECT_EQ(dirs, pruning[level]) << "level " << level;
    EXPECT_LT(second.passes.size(), first.passes.size());
    EXPECT_EQ(second.pcs, first.pcs);
}

// Trap: a direction once dropped never coming back. Every period-th frame (here 3) is a full
// check: frames 0 and 3 make the six object-level calls, frames 1, 2 and 4 none.
TEST(CullideDirections, CoherentFullCheckEveryPeriodFrames) {
    const Scene s = piercedBoxes();
    auto backend = raster::makeCpuBackend();
    auto history = std::make_shared<DirectionHistory>();
    history->period = 3;
    std::vector<size_t> calls;
    for (int f = 0; f < 5; ++f) {
        const CullideResult r = runCullide(s, *backend, coherentOptions(history));
        calls.push_back(
            size_t(std::count_if(r.passes.begin(), r.passes.end(), [](const PassStats& p) { return p.level == 0; })));
    }
    EXPECT_EQ(calls, (std::vector<size_t>{6, 0, 0, 6, 0}));
    // The plan itself: a level the last run did not reach, or another list length, is a full check.
    DirectionHistory h;
    h.frames = 1, h.count = 3, h.pruned = {{0, 5, 2}};
    EXPECT_EQ(h.plan(0, 3), (std::vector<uint32_t>{1, 2})) << "the given order, not most first";
    EXPECT_EQ(h.plan(1, 3), (std::vector<uint32_t>{0, 1, 2}));
    EXPECT_EQ(h.plan(0, 4), (std::vector<uint32_t>{0, 1, 2, 3}));
    h.pruned = {{0, 0, 0}};
    EXPECT_TRUE(h.plan(0, 3).empty()) << "nothing pruned at that level: no call";
}

// Trap: coherent that only reorders or drops calls but, where last frame's prediction holds,
// changes the PCS: dropping calls that would prune nothing must leave the PCS of the full list.
// Over a cylinders animation, with 1 and with every thread: the same PCS as axes on each frame
// where it made fewer calls and no call it skipped would have pruned (checked by the full run).
TEST(CullideDirections, CoherentSkipsOnlyCallsAndKeepsTheirPcs) {
    SceneRequest q;
    q.triangles = 3000;
    q.frames = 6;
    const Animation a = makeCylinders(12, q);
    auto backend = raster::makeCpuBackend();
    auto history = std::make_shared<DirectionHistory>();
    size_t coherentCalls = 0, fixedCalls = 0;
    for (size_t f = 0; f < a.frameCount(); ++f) {
        const Scene s = a.sceneAt(f);
        CullideOptions o = coherentOptions(history);
        o.hierarchy.leafSize = 16;
        const CullideResult c = runCullide(s, *backend, o);
        o.directionMode = DirectionMode::Fixed;
        const CullideResult full = runCullide(s, *backend, o);
        coherentCalls += c.passes.size(), fixedCalls += full.passes.size();
        // The skipped calls of the full run pruned nothing here: then the PCS must be the same.
        std::set<std::pair<uint32_t, uint32_t>> made;
        for (const PassStats& p : c.passes) made.insert({p.level, p.direction});
        bool predicted = true;
        for (const PassStats& p : full.passes)
            if (!made.count({p.level, p.direction}) && p.trianglesOut != p.trianglesIn) predicted = false;
        if (predicted) {
            EXPECT_EQ(c.pcs, full.pcs) << "frame " << f;
        }
    }
    EXPECT_LT(coherentCalls, fixedCalls);
}
