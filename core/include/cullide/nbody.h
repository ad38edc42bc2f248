// The field's "N-body" kind of scene, generated reproducibly (`cullide make-scene nbody`).
//
// K rigid bodies (source meshes at random scales and orientations) move ballistically in a box,
// bouncing off its walls and passing through each other (no response between bodies), so that
// every frame has many inter-object intersections and near-contacts. The motion is closed-form
// (no time stepping): same request, same bytes (docs/scenes.md).
//
// Conventions
//   - Objects "body_000", ...: each a source mesh resampled so that the bodies' triangles add up
//     to about request.triangles; frames give each body's rigid transform (moving objects).
//   - The motion does not depend on `frames`: frame i of F is the state at time i * T / (F - 1)
//     (T fixed); F = 1 gives time 0. Every vertex of every body stays inside the box in every
//     frame.
//   - The base scene (Animation::scene) is frame 0.
#pragma once

#include "cullide/scene.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace cullide {

struct NBodyRequest {
    size_t count = 100;          // bodies, >= 1
    size_t triangles = 146'000;  // all bodies together, about
    size_t frames = 76;          // >= 1
    uint64_t seed = 1;
};

inline constexpr size_t kMaxNBodyCount = 10'000, kMaxNBodyTriangles = 5'000'000, kMaxNBodyFrames = 1000;

// `meshes` (at least one) are the source meshes, chosen per body by the seed; `source` names them
// in errors. Throws InputError(source, ...) for a mesh with no triangles or a zero or non-finite
// extent, InputError("nbody", ...) for a request out of range.
Animation makeNBody(std::span<const Mesh> meshes, const NBodyRequest& request, const std::string& source = "mesh");

}  // namespace cullide
