// The one way to prune a frame or a sequence of frames: Cullide's loop (runCullide) with every
// option around it wired once, for the command line (`cullide prune`, `trace record`, `validate`),
// the Python module, the study and the benchmarks.
//
// Conventions
//   - A Pruner runs frames in order on one backend. Over several frames it keeps each object's
//     hierarchy while the object's triangles are unchanged (HierarchyCache: the same PCS, bit for
//     bit, without the per-frame build) and, with coherent directions, what each direction pruned
//     (DirectionHistory). One frame has nothing to carry over, so nothing is kept.
//   - `--exact-switch auto` gets a cost model calibrated on each frame's own scene
//     (exactStageCostModel), fresh per frame, so every run pays for its calibration inside its
//     own time; a model the caller set in ExactSwitch::exactCost is used instead.
//   - With the exact stage, each frame's PCS goes to the oracle's exact stage (oracle::exactStage):
//     the pipeline's final intersecting pairs, and the time to them (prune + exact stage).
//   - Deterministic: the same scene, settings and backend results give the same PCS and pairs;
//     only the timings (and, with the auto switch, where it stops) depend on the machine.
#pragma once

#include "cullide/cullide.h"
#include "cullide/depth_backend.h"
#include "cullide/oracle/oracle.h"
#include "cullide/scene.h"

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <span>

namespace cullide {

// What a run asks for beyond Cullide's own options.
struct PruneSettings {
    CullideOptions cullide;  // validated by the Pruner; its per-frame hooks and caches are the Pruner's
    // Runs the exact stage on every frame's PCS (FramePrune::exact).
    bool exactStage = false;
    // Over several frames, keep each object's hierarchy while its triangles are unchanged; false
    // builds every frame's hierarchies, as the paper does (`prune --rebuild-hierarchy`).
    bool reuseHierarchies = true;
};

// One frame's outcome.
struct FramePrune {
    CullideResult cull;
    std::optional<oracle::Truth> exact;  // with PruneSettings::exactStage: the pairs among the PCS
    double exactSeconds() const { return exact ? exact->totalSeconds : 0; }
    // The pipeline's latency: image-space pruning, then the exact stage on its PCS.
    double timeToExactSeconds() const { return cull.totalSeconds + exactSeconds(); }
};

// Callbacks of one frame's reducePCS calls (CullideOptions::onPass and onPassStats).
struct FrameHooks {
    std::function<void(const PassStats&, std::span<const PcsTriangle>)> onPass;
    std::function<void(const PassStats&)> onPassStats;
};

// Prunes frames in order: one Pruner per frame sequence (a still scene is a sequence of one).
class Pruner {
public:
    // `frames`: how many frames this Pruner will run (more than one: state carries over between
    // them). Throws InputError on bad options (CullideOptions::validate).
    Pruner(PruneSettings settings, DepthBackend& backend, size_t frames = 1);

    // Prunes the next frame. The scene stays the caller's.
    FramePrune prune(const Scene& scene, const FrameHooks& hooks = {});
    // The same for a scene the caller gives up: emptied as soon as its geometry is uploaded, so
    // that it is not in memory beside the run's own copy (unless the exact stage or auto's cost
    // model reads it during the run).
    FramePrune prune(Scene&& scene, const FrameHooks& hooks = {});

private:
    CullideOptions frameOptions(const Scene& scene, const FrameHooks& hooks) const;
    bool readsScene() const;

    PruneSettings settings_;
    DepthBackend& backend_;
    std::shared_ptr<HierarchyCache> hierarchies_;
    std::shared_ptr<DirectionHistory> directionHistory_;
};

}  // namespace cullide
