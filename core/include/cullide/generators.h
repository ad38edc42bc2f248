// The paper's scenes, generated reproducibly (`cullide make-scene`).
//
// Every generator is a pure function of its inputs and seed: same inputs, same bytes (no
// unordered containers, no threads, no platform maths beyond IEEE + - * / and sqrt; random
// numbers from std::mt19937_64 with our own distribution code, since std's distributions are
// implementation-defined).
#pragma once

#include "cullide/scene.h"

#include <cstdint>

namespace cullide {

// 1-to-4 midpoint subdivision (each triangle -> 4; shared edges get one shared midpoint, so
// connectivity is kept). Triangle i becomes triangles 4i..4i+3.
Mesh subdivide(const Mesh& mesh);

// Simplifies to about `targetTriangles` (meshoptimizer's meshopt_simplify; edge collapses that
// keep the surface's appearance). Never increases the count.
Mesh decimate(const Mesh& mesh, size_t targetTriangles);

// Subdivides and/or decimates `mesh` to the triangle count closest to `targetTriangles`.
Mesh resample(const Mesh& mesh, size_t targetTriangles);

struct SceneRequest {
    size_t triangles = 5000;   // requested total triangle count (about)
    uint64_t seed = 1;
    size_t frames = 0;         // 0: a still scene; else a deforming animation of this many frames
};

// A deformed Stanford bunny with a single self-intersection area (one object).
Animation makeDeformedBunny(const Mesh& bunny, const SceneRequest& request);
// Two cows merged into one object so that many self-intersections exist.
Animation makeTwoCows(const Mesh& cow, const SceneRequest& request);
// `count` open cylinders deforming (bending) over the frames, many of them interpenetrating,
// as in CULLIDE's many-object benchmark.
Animation makeCylinders(size_t count, const SceneRequest& request);
// A twist (or bend) of `base` over request.frames frames: per-frame positions.
Animation makeTwistAnimation(const Mesh& base, const SceneRequest& request);

}  // namespace cullide
