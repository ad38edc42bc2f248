// Near contacts: triangle pairs that do not intersect but come within a distance of each other.
//
// They are what makes image-space culling hard: two layers of a folded cloth, a body resting on
// another, keep each other in the PCS at any resolution coarser than their gap, although no pair
// intersects. A study counts them beside the oracle's pairs (docs/studies.md).
//
// Conventions
//   - A near contact is an unordered pair of non-degenerate triangles whose distance (the
//     smallest distance between their points, in double, from the float world coordinates of
//     Scene::worldMesh) is at most `distance`, that the oracle does not report as intersecting,
//     and, within one object, that share no vertex index (neighbours of a mesh always touch).
//   - The distance is computed in double without exact arithmetic: a pair within a few ulps of
//     `distance` may fall on either side, always the same one for the same input.
//   - Threads: TBB; the count does not depend on the thread count.
#pragma once

#include "cullide/oracle/oracle.h"
#include "cullide/scene.h"

#include <cstddef>

namespace cullide::oracle {

struct NearContacts {
    size_t selfPairs = 0;     // both triangles in one object
    size_t objectPairs = 0;   // triangles of two objects
    size_t total() const { return selfPairs + objectPairs; }
};

// The near contacts of `scene` within `distance` (world units, finite, >= 0); `truth` is the
// oracle's answer for the same scene (findIntersections). Throws InputError("near contacts", ...)
// for a distance that is negative, not finite or over 2^59 (world coordinates are at most 2^60).
NearContacts countNearContacts(const Scene& scene, const Truth& truth, double distance);

// The distance between triangles (a0, a1, a2) and (b0, b1, b2) when they do not intersect (the
// smallest of the six corner-triangle and nine edge-edge distances); 0 or more otherwise, and
// not meaningful then.
double triangleDistance(const Vec3d& a0, const Vec3d& a1, const Vec3d& a2, const Vec3d& b0, const Vec3d& b1,
                        const Vec3d& b2);

}  // namespace cullide::oracle
