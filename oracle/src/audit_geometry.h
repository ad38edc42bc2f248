// The geometry behind the audit's causes (audit.h): how two triangles of a scene share vertices,
// whether they lie in one plane, and how deep a crossing pair interpenetrates.
#pragma once

#include "cullide/mesh.h"
#include "cullide/predicates.h"

namespace cullide::oracle::detail {

// How many vertex indices two triangles of one mesh have in common (0 to 3).
int sharedIndices(const Triangle& a, const Triangle& b);

// Whether the corners of both triangles lie in one plane, exactly (`a` non-degenerate).
bool coplanar(const TrianglePoints& a, const TrianglePoints& b);

// The penetration depth of two triangles: the length of the shortest translation that parts them
// (after which they at most touch). By the separating-axis theorem it is the smallest overlap of
// the two projections over the candidate axes, the two normals and the nine cross products of an
// edge of each (axes of zero length skipped): for convex polytopes these hold every facet normal
// of the Minkowski difference, whose nearest facet to the origin gives the depth. In double; 0
// for triangles that the axes separate. Meant for crossing pairs (not coplanar, both
// non-degenerate): for coplanar ones the in-plane edge normals would be needed too.
double penetrationDepth(const TrianglePoints& a, const TrianglePoints& b);

// Whether a part of `b` lies inside the prism over `a` (bounded by the planes through a's edges
// along its normal) and strictly behind a's plane (the side away from the normal of a's corners in
// their order). In double: an explanation, not a decision. `a` non-degenerate.
bool behindFace(const TrianglePoints& a, const TrianglePoints& b);

}  // namespace cullide::oracle::detail
