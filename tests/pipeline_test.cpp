// The pipeline (cullide/pipeline/pruner.h, exact_cost.h): the one way to prune a frame or a
// sequence must give what Cullide's loop gives when the same state is wired by hand, carry that
// state across frames, and run the exact stage on the PCS it found.
#include "cullide/pipeline/exact_cost.h"
#include "cullide/pipeline/pruner.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/cpu_backend.h"

#include "test_util.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace cullide {
namespace {

// Eight frames of twelve bowing cylinders: objects that deform (new hierarchies) and a sequence
// long enough for coherent directions to drop some.
const Animation& cylinders() {
    static const Animation a = [] {
        SceneRequest q;
        q.triangles = 3000;
        q.frames = 8;
        return makeCylinders(12, q);
    }();
    return a;
}

// Trap: the Pruner wires the hierarchy cache and the direction history differently from the
// loop run by hand (a cache not kept, a history reset per frame, the options' hooks dropped): over
// a sequence, every frame's PCS and call count must equal a hand-wired run's, for fixed and
// coherent directions.
TEST(Pipeline, SequenceMatchesHandWiredLoop) {
    const Animation& a = cylinders();
    auto backend = raster::makeCpuBackend();
    for (const DirectionMode mode : {DirectionMode::Fixed, DirectionMode::Coherent}) {
        PruneSettings settings;
        settings.cullide.directionMode = mode;
        Pruner pruner(settings, *backend, a.frameCount());
        CullideOptions byHand = settings.cullide;
        byHand.hierarchyCache = std::make_shared<HierarchyCache>();
        if (mode == DirectionMode::Coherent) byHand.directionHistory = std::make_shared<DirectionHistory>();
        size_t calls = 0;
        for (size_t f = 0; f < a.frameCount(); ++f) {
            const Scene scene = a.sceneAt(f);
            size_t hooked = 0;
            FrameHooks hooks;
            hooks.onPassStats = [&hooked](const PassStats&) { ++hooked; };
            const FramePrune ours = pruner.prune(scene, hooks);
            const CullideResult expected = runCullide(scene, *backend, byHand);
            EXPECT_EQ(ours.cull.pcs, expected.pcs) << "frame " << f;
            EXPECT_EQ(ours.cull.passes.size(), expected.passes.size()) << "frame " << f;
            EXPECT_EQ(hooked, ours.cull.passes.size()) << "frame " << f << ": the hook saw every call";
            EXPECT_FALSE(ours.exact) << "no exact stage unless asked";
            calls += ours.cull.passes.size();
        }
        EXPECT_GT(calls, 0u);
    }
}

// Trap: a hierarchy reused across frames where the settings ask for a rebuild (or none reused
// where they allow it): the cylinders' first frame builds all, later frames reuse what did not
// change only when reuseHierarchies is on; a single-frame Pruner keeps nothing.
TEST(Pipeline, HierarchiesCarryOverOnlyWhenAsked) {
    const Animation& a = cylinders();
    auto backend = raster::makeCpuBackend();
    const Scene first = a.sceneAt(0);
    for (const bool reuse : {true, false}) {
        PruneSettings settings;
        settings.reuseHierarchies = reuse;
        Pruner pruner(settings, *backend, 2);
        EXPECT_EQ(pruner.prune(first).cull.hierarchiesReused, 0u);
        const uint32_t reused = pruner.prune(first).cull.hierarchiesReused;
        if (reuse) EXPECT_EQ(reused, first.objects.size()) << "the same frame again: every hierarchy reused";
        else EXPECT_EQ(reused, 0u);
    }
    Pruner single(PruneSettings{}, *backend, 1);
    EXPECT_EQ(single.prune(first).cull.hierarchiesReused, 0u);
    EXPECT_EQ(single.prune(first).cull.hierarchiesReused, 0u) << "one frame: nothing kept";
}

// Trap: the exact stage run on another set than the PCS (the whole scene, or a PCS of an earlier
// frame), or its time left out of the time to exact pairs. The pairs must be the oracle's exact
// stage on this frame's PCS, and a scene given up to the run must stay readable for it.
TEST(Pipeline, ExactStageRunsOnThePcs) {
    const Scene scene = cylinders().sceneAt(7);
    auto backend = raster::makeCpuBackend();
    PruneSettings settings;
    settings.exactStage = true;
    Pruner pruner(settings, *backend);
    const FramePrune r = pruner.prune(scene);
    ASSERT_TRUE(r.exact);
    EXPECT_EQ(r.exact->pairs, oracle::exactStage(scene, r.cull.pcs).pairs);
    EXPECT_FALSE(r.exact->pairs.empty()) << "the bowing cylinders intersect in their last frame";
    EXPECT_DOUBLE_EQ(r.timeToExactSeconds(), r.cull.totalSeconds + r.exact->totalSeconds);
    Scene given = scene;
    Pruner again(settings, *backend);
    const FramePrune moved = again.prune(std::move(given));
    EXPECT_EQ(moved.cull.pcs, r.cull.pcs);
    ASSERT_TRUE(moved.exact);
    EXPECT_EQ(moved.exact->pairs, r.exact->pairs);
}

// Trap: a scene given up to the run (the memory-saving overload) pruned differently from one
// kept by the caller.
TEST(Pipeline, GivenUpSceneGivesTheSamePcs) {
    const Scene scene = cylinders().sceneAt(3);
    auto backend = raster::makeCpuBackend();
    Pruner kept(PruneSettings{}, *backend), given(PruneSettings{}, *backend);
    Scene copy = scene;
    EXPECT_EQ(given.prune(std::move(copy)).cull.pcs, kept.prune(scene).cull.pcs);
}

// Trap: absurd options accepted until the first frame (or never): the Pruner refuses them when it
// is made, naming the option.
TEST(Pipeline, RefusesBadOptionsUpFront) {
    auto backend = raster::makeCpuBackend();
    PruneSettings settings;
    settings.cullide.directions.clear();
    EXPECT_THROW((Pruner{settings, *backend}), InputError);
}

// Trap: a cost model the caller set replaced by the calibrated one. A model that prices the exact
// stage at nothing makes auto stop before the second level, predicting 0 s for it.
TEST(Pipeline, CallersCostModelIsKept) {
    const Scene scene = cylinders().sceneAt(7);
    auto backend = raster::makeCpuBackend();
    PruneSettings settings;
    settings.cullide.exactSwitch.kind = ExactSwitchKind::Auto;
    settings.cullide.exactSwitch.exactCost = [](size_t) { return 0.0; };
    const CullideResult r = Pruner(settings, *backend).prune(scene).cull;
    EXPECT_EQ(r.switchedAtLevel, 1);
    EXPECT_EQ(r.predictedExactSeconds, 0.0);
}

// Trap: the auto switch's cost model not linear in the PCS size, or calibrated on nothing: it
// must cost nothing for no triangles, scale linearly, and be zero on an empty scene (no sample).
TEST(Pipeline, ExactCostModelIsLinear) {
    const Scene scene = cylinders().sceneAt(0);
    const auto model = exactStageCostModel(scene);
    EXPECT_EQ(model(0), 0.0);
    const double one = model(1000);
    EXPECT_GT(one, 0.0);
    EXPECT_DOUBLE_EQ(model(4000), 4 * one) << "calibrated once, then linear";
    const Scene empty;
    EXPECT_EQ(exactStageCostModel(empty)(1000), 0.0);
}

}  // namespace
}  // namespace cullide
