// The exact stage's cost model behind `--exact-switch auto` (ExactSwitch::exactCost,
// docs/cullide.md#switch-to-exact), calibrated on the scene being pruned.
#pragma once

#include "cullide/scene.h"

#include <cstddef>
#include <functional>

namespace cullide {

// n times the seconds per triangle of the exact stage (oracle::exactStage) on a calibration sample
// of `scene`: the 1/16 of its triangles (at least 2048, at most all) whose centroids lie nearest,
// in the max norm, to the coordinate-wise median centroid, a compact patch as dense as the PCS's
// leaves. The sample is timed once, at the model's first call, so that a run that switches pays
// for it inside its own time (and one that never predicts pays nothing). `scene` must outlive the
// model.
std::function<double(size_t)> exactStageCostModel(const Scene& scene);

}  // namespace cullide
