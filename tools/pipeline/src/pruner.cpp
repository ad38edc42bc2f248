// The one way to prune a frame or a sequence (pruner.h).
#include "cullide/pipeline/pruner.h"

#include "cullide/pipeline/exact_cost.h"

#include <utility>

namespace cullide {

Pruner::Pruner(PruneSettings settings, DepthBackend& backend, size_t frames)
    : settings_(std::move(settings)), backend_(backend) {
    settings_.cullide.validate();
    if (frames > 1 && settings_.reuseHierarchies) hierarchies_ = std::make_shared<HierarchyCache>();
    if (frames > 1 && settings_.cullide.directionMode == DirectionMode::Coherent)
        directionHistory_ = std::make_shared<DirectionHistory>();
}

bool Pruner::readsScene() const {
    return settings_.exactStage || settings_.cullide.exactSwitch.kind == ExactSwitchKind::Auto;
}

CullideOptions Pruner::frameOptions(const Scene& scene, const FrameHooks& hooks) const {
    CullideOptions o = settings_.cullide;
    o.hierarchyCache = hierarchies_;
    o.directionHistory = directionHistory_;
    // Auto's exact-stage cost, calibrated on this frame (timed inside the run when it predicts),
    // unless the caller gave a model of its own.
    if (o.exactSwitch.kind == ExactSwitchKind::Auto && !o.exactSwitch.exactCost)
        o.exactSwitch.exactCost = exactStageCostModel(scene);
    if (hooks.onPass) o.onPass = hooks.onPass;
    if (hooks.onPassStats) o.onPassStats = hooks.onPassStats;
    return o;
}

FramePrune Pruner::prune(const Scene& scene, const FrameHooks& hooks) {
    FramePrune out;
    out.cull = runCullide(scene, backend_, frameOptions(scene, hooks));
    if (settings_.exactStage) out.exact = oracle::exactStage(scene, out.cull.pcs);
    return out;
}

FramePrune Pruner::prune(Scene&& scene, const FrameHooks& hooks) {
    if (readsScene()) return prune(static_cast<const Scene&>(scene), hooks);
    FramePrune out;
    const CullideOptions options = frameOptions(scene, hooks);
    out.cull = runCullide(std::move(scene), backend_, options);
    return out;
}

}  // namespace cullide
