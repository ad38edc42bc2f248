// The field's "cloth on a ball" kind of scene, simulated reproducibly (`cullide make-scene cloth`).
//
// A square cloth (a regular grid, two triangles per cell) held flat above a sphere falls under
// gravity, drapes over it and folds. The simulator is small and deterministic: double precision,
// a fixed time step and iteration count, one thread, a fixed order of work, no fast-math; the
// same request gives the same bytes (docs/scenes.md says how it is made).
//
// Conventions
//   - Objects: "cloth" (its positions change every frame, identity transform) and "sphere" (a
//     still collider, drawn as a mesh whose vertices lie on the simulated sphere).
//   - The motion simulated does not depend on `frames`: frame i of F is the state at time
//     i * T / (F - 1) of the same simulation (the whole fall and drape, T fixed); F = 1 gives the
//     last state (the draped cloth). Fewer frames mean larger steps between them.
//   - The base scene (Animation::scene) is frame 0.
#pragma once

#include "cullide/scene.h"

#include <cstddef>
#include <cstdint>

namespace cullide {

enum class SelfCollision {
    Repulsion,  // cloth particles kept apart (a hash grid), as real simulator output is
    None,       // the cloth passes through itself
};

struct ClothRequest {
    size_t triangles = 92'000;  // the cloth's triangles, about (a square grid)
    size_t frames = 94;         // >= 1
    uint64_t seed = 1;          // perturbs the cloth's initial placement
    SelfCollision selfCollision = SelfCollision::Repulsion;
};

inline constexpr size_t kMinClothTriangles = 100, kMaxClothTriangles = 2'000'000, kMaxClothFrames = 1000;

// Throws InputError("cloth", ...) when the request is out of the ranges above.
Animation makeCloth(const ClothRequest& request);

}  // namespace cullide
