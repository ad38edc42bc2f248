// Scenes and runs the Cullide tests share (cullide_test.cpp, view_fit_test.cpp,
// view_groups_test.cpp, directions_test.cpp, cull_method_test.cpp).
#pragma once

#include "cullide/cullide.h"

#include <cstdint>
#include <set>

namespace cullide::test {

// A unit icosphere subdivided `levels` times (20 * 4^levels triangles), closed, no self-intersection.
Mesh icosphere(int levels);

// A ribbon swept along a planar curve that crosses itself (x = s^2 - 1, y = s^3 - s crosses at
// s = +-1), extruded along z: the two passes through the crossing cut each other along a line.
Mesh selfCrossingRibbon(int segments);

// Every (object, triangle) in a crossing pair (pairs sharing a vertex within an object excluded).
// Exact-enough (double, generic configurations only): some edge of one triangle passes through
// the interior of the other. For the hand-built scenes here, whose crossings are far from
// degenerate; the exact oracle is the real judge.
std::set<PcsTriangle> crossingTriangles(const Scene& scene);

// runCullide on the CPU reference backend with `threads` threads (0: all), a square viewport of
// `resolution` (or adaptive resolution with K = autoCoverage), branching 2.
CullideResult prune(const Scene& scene, CullMethod method, uint32_t leafSize,
                    HierarchyKind kind = HierarchyKind::Connectivity, int threads = 0, int resolution = 256,
                    double autoCoverage = 0);

// Whether the PCS of `r` holds every triangle of `want`.
bool contains(const CullideResult& r, const std::set<PcsTriangle>& want);

}  // namespace cullide::test
