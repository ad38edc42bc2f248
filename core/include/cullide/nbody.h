// The field's "N-body" kind of scene, generated reproducibly (`cullide make-scene nbody`).
//
// K rigid bodies (source meshes at random scales and orientations) move ballistically in a box,
// bouncing off its walls and passing through each other (no response between bodies), so that
// every frame has many inter-object intersections and near-contacts. The motion is closed-form
// (no time stepping): same request, same bytes (docs/scenes.md).
//
// Conventions
//   - Objects "body_000", ...: each one of the source meshes (chosen per body by the seed),
//     resampled so that the bodies' triangles add up to about request.triangles (round(N / K) per
//     body; bodies of one source share one resampled mesh), in model space: centred at its
//     bounding-box centre, bounding radius 1 about it. Only the frames' transforms move them.
//   - Sizes: body i's scale is r0 * f_i, f_i seeded in [0.6, 1.4], r0 such that the bodies'
//     bounding spheres fill 0.4 of the box (no body's radius over 3/4 of the box's half-size).
//   - Motion: each centre moves at a seeded constant velocity (1 to 2 box half-sizes per T) and
//     bounces off the walls (per axis a reflected triangle wave within the box shrunk by the
//     body's bounding radius); each orientation turns at a seeded constant angular velocity
//     (0.5 pi to 1.5 pi radians per T): R(t) = AngleAxis(|w| t, w / |w|) R0, R0 seeded.
//   - Frames give each body's Transform (rotation * scale, then the centre), computed in double
//     and rounded to float once. The motion does not depend on `frames`: frame i of F is the
//     state at time i * T / (F - 1) (T fixed); F = 1 gives time 0.
//   - The box is [-kNBodyHalfSize, kNBodyHalfSize]^3 whatever the request: every vertex of every
//     body stays inside it in every frame (world coordinates, as Scene::worldMesh computes them).
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
// request.triangles must be at least this many per body (a tetrahedron's worth: fewer cannot
// enclose a volume, and decimation cannot reach 1).
inline constexpr size_t kMinNBodyTrianglesPerBody = 4;
// The box the bodies move in: [-kNBodyHalfSize, kNBodyHalfSize] on every axis.
inline constexpr float kNBodyHalfSize = 1.0f;

// `meshes` (at least one) are the source meshes, chosen per body by the seed; `source` names them
// in errors. Throws InputError("nbody", ...) for a request out of range (naming the field), and
// InputError(source, ...) for no meshes, a mesh validateMesh refuses (no triangles, non-finite
// coordinates, indices out of range), one whose vertices are all one point, or one that cannot be
// resampled to within 4x of the per-body count.
Animation makeNBody(std::span<const Mesh> meshes, const NBodyRequest& request, const std::string& source = "mesh");

}  // namespace cullide
