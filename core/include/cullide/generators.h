// The paper's scenes, generated reproducibly (`cullide make-scene`).
//
// Every generator is a pure function of its inputs and seed: same inputs, same bytes on one
// platform and build (no unordered containers, no threads; IEEE + - * / and sqrt in a fixed order,
// plus std::sin/std::cos, which glibc computes deterministically; random numbers from
// std::mt19937_64 with our own conversion to double, since std's distributions are
// implementation-defined).
//
// Conventions
//   - Generated scenes have identity object transforms; all geometry is in the positions.
//   - An animation's frames give full per-object positions (topology never changes). The base
//     scene (Animation::scene) is the fully deformed state, equal to the last frame for the bunny
//     and the twist, and to the middle frame (odd frame counts) for the cows; frame 0 of the
//     bunny and the twist is the undeformed mesh, bit for bit.
//   - Triangle counts are "about": resampling lands within ~1% of the request, cylinders within
//     a few percent (whole rings and sides).
//   - The generators made from a mesh place their deformation by fractions of its bounding box:
//     they throw InputError(source, ...) (`source` names the mesh) when the mesh has no triangles,
//     or a box whose extent is zero (all vertices one point; for the bunny, also no height, or no
//     width) or overflows float, where the fractions would divide by zero.
#pragma once

#include "cullide/scene.h"

#include <cstdint>
#include <string>

namespace cullide {

// 1-to-4 midpoint subdivision (each triangle -> 4; shared edges get one shared midpoint, so
// connectivity is kept). Triangle i becomes triangles 4i..4i+3: the corners at t[0], t[1], t[2],
// then the centre triangle, all with the parent's orientation. Vertices: the originals first,
// unchanged, then one midpoint per undirected edge, in order of first use (triangle order, edges
// t0-t1, t1-t2, t2-t0). The mesh's indices must be in range (checked).
Mesh subdivide(const Mesh& mesh);

// Simplifies to about `targetTriangles` (meshoptimizer's meshopt_simplify, quadric edge collapse
// with no error bound; where that stops more than 10% above the target, meshopt_simplifySloppy
// also runs and the closer result wins). Never increases the count: a target at or above the
// input's count returns the input unchanged. Unreferenced vertices are dropped, the rest keep
// their relative order. Triangle order is meshoptimizer's.
Mesh decimate(const Mesh& mesh, size_t targetTriangles);

// Subdivides and/or decimates `mesh` to about `targetTriangles` (> 0). Below the input's count it
// decimates; above it, it decimates to target / 4^k (the smallest k that makes this at most the
// input's count) and then subdivides k times: decimating a subdivided mesh folds its flat patches.
Mesh resample(const Mesh& mesh, size_t targetTriangles);

struct SceneRequest {
    size_t triangles = 5000;  // requested total triangle count (about)
    uint64_t seed = 1;
    size_t frames = 0;  // 0: a still scene; else an animation of this many frames
};

// A deformed Stanford bunny with a single self-intersection area (one object, "bunny"): the input
// resampled to request.triangles, then its back ear bent down about its root so that it plunges
// through the bunny's back. The bend is placed by fractions of the input's bounding box and
// expects the bundled bunny's frame (data/meshes/bunny.off: Y up, facing -x); on other meshes it
// is still a smooth deformation but need not make an intersection. Frames bend the ear from 0
// (frame 0: the resampled bunny unchanged) to the full bend (last frame).
Animation makeDeformedBunny(const Mesh& bunny, const SceneRequest& request, const std::string& source = "mesh");
// Two cows merged into one object ("two_cows") so that many self-intersections exist: each copy
// resampled to request.triangles / 2 (the first copy's vertices and triangles come first), the
// second turned 35 degrees about y and shifted so that bodies, heads and legs cross. Frames move
// the second copy along x from clear of the first on one side to clear on the other.
Animation makeTwoCows(const Mesh& cow, const SceneRequest& request, const std::string& source = "mesh");
// `count` (> 0) open cylinders ("cyl_000", ...; tubes without caps) with seeded random centres in
// [-1, 1]^3 and random directions, so that some but far from all pairs interpenetrate; about
// request.triangles in all. Frames bow each tube sideways (its own direction and amplitude) as
// sin(2 pi f / frames): frame 0 is the straight still scene.
Animation makeCylinders(size_t count, const SceneRequest& request);
// `count` (> 0) flat square sheets ("sheet_000", ...; unit squares, each a grid of about
// request.triangles / count triangles, two per cell), nearly parallel: sheet i's normal is +z
// tilted by tiltDegrees x a seeded factor in [0.5, 1.5] (below 90 degrees) towards a seeded
// azimuth, so the +-x and +-y views see every sheet nearly edge-on when tiltDegrees is small.
// Centres: x and y seeded in [-0.15, 0.15], z evenly spaced over [-0.08, 0.08] in a seeded order,
// each sheet turned about its normal by a seeded angle; neighbours at a few degrees to each other
// cross, far ones do not. A still scene (docs/cullide.md#chosen-directions: the scene on which
// axis views lose crossings edge-on).
Animation makeSheets(size_t count, double tiltDegrees, const SceneRequest& request);
// A twist of `base` about the longest axis of its bounding box, through the box centre: the angle
// varies linearly along that axis over +-45 degrees at full twist, and grows from 0 (frame 0: the
// mesh unchanged) to full (last frame). Coordinates along the axis do not change.
Animation makeTwistAnimation(const Mesh& base, const SceneRequest& request, const std::string& source = "mesh");

}  // namespace cullide
