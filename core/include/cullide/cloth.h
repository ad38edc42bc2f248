// The field's "cloth on a ball" kind of scene, simulated reproducibly (`cullide make-scene cloth`).
//
// A square cloth (a regular grid, two triangles per cell) held flat above a sphere falls under
// gravity, drapes over it and folds. The simulator is small and deterministic: position-based
// dynamics in double precision, a fixed time step and pass count, one thread, a fixed order of
// work, no fast-math; the same request gives the same bytes (docs/scenes.md says how it is made).
//
// Model (the private core/src/cloth_sim.h holds the constants)
//   - Sphere: centre at the origin, radius 1; y is up. Cloth: side 4.5 radii, so that its corners
//     hang well below the equator; it starts flat, a quarter radius above the sphere's top, placed
//     by the seed (turned about the vertical, tilted by up to 5 degrees, off the axis by up to a
//     tenth of a radius, each particle lifted by a jitter of 1e-3 edges).
//   - Particles of equal mass at the grid's vertices. Constraints: every triangle edge keeps its
//     rest length (rows, columns, each cell's diagonal); a little bending resistance (each particle
//     pulled towards the midpoint of its row and column neighbours). Gravity 9.81 radii/s^2,
//     velocity damping 5/s, the sphere's Coulomb friction (coefficient 0.5).
//   - Time: steps of 1/120 s over 3 s (the fall and the drape; the cloth is nearly still by the
//     end), each of about 10 substeps of two passes (more for a finer cloth, fewer for a coarser).
//   - Contact: every cloth vertex stays at least 0.5 % of the radius outside the sphere (more for a
//     coarse cloth, by its cells' sag, so that its triangles stay outside too). Edges stay within about 10 %
//     of their rest length (7 % for the default cloth).
//   - SelfCollision::Repulsion keeps apart the cloth particles of a sub-grid about 1/8 of a
//     radius apart (every k-th row and column, k from the cloth's resolution): particles of it that
//     are not grid neighbours are pushed to 0.6 sub-grid spacings, near pairs found by a spatial
//     hash every third step (1/40 s). Most layers of a fold lie in near-contact; a wrinkle finer
//     than the sub-grid, or a fold that closes between two searches, passes through (a few folds
//     per scene, as in real simulator output, whose collision proxies are coarser than its
//     mesh). SelfCollision::None lets the cloth pass through itself.
//
// Conventions
//   - Objects: "cloth" (its positions change every frame, identity transform) and "sphere" (a
//     still collider, drawn as an icosphere of 5120 triangles whose vertices lie on the simulated
//     sphere, so that its facets lie inside it). Frames give the cloth's positions and nothing for
//     the sphere.
//   - The cloth has about `triangles` triangles: n x n cells, 2 n^2 the nearest to `triangles`
//     (92,000 gives 214 x 214 cells: 91,592 triangles, 46,225 vertices).
//   - The motion simulated does not depend on `frames`: frame i of F is the state at the step
//     nearest time i * T / (F - 1) of the same simulation (the whole fall and drape, T fixed);
//     F = 1 gives the last state (the draped cloth). Fewer frames mean larger steps between them.
//   - The base scene (Animation::scene) is frame 0.
//   - Time: about proportional to the triangles (the default, 92k triangles, takes about 12 s on
//     one core); a finer cloth also takes more substeps per step (up to 16).
#pragma once

#include "cullide/scene.h"

#include <cstddef>
#include <cstdint>

namespace cullide {

enum class SelfCollision {
    Repulsion,  // cloth particles kept apart (a hash grid): mostly near-contact, a few folds through
    None,       // the cloth passes through itself
};

struct ClothRequest {
    size_t triangles = 92'000;  // the cloth's triangles, about (a square grid)
    size_t frames = 94;         // >= 1
    uint64_t seed = 1;          // perturbs the cloth's initial placement
    SelfCollision selfCollision = SelfCollision::Repulsion;
};

inline constexpr size_t kMinClothTriangles = 100, kMaxClothTriangles = 2'000'000, kMaxClothFrames = 1000;
// Every frame's positions are held until the scene is written (12 bytes a vertex, about half a
// vertex a triangle): triangles x frames is bounded too (the default is 8.6 million; this bound
// holds about 1.2 GB of frames, 2,000,000 triangles for 100 frames).
inline constexpr size_t kMaxClothTriangleFrames = 200'000'000;

// Throws InputError("cloth", ...) naming the field when the request is out of the ranges above.
// Every frame is held in memory: frames x vertices x 12 bytes (the default: 52 MB).
Animation makeCloth(const ClothRequest& request);

}  // namespace cullide
