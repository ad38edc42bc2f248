// The oracle's narrow phase on packed primitive records (internal to oracle/).
//
// A record holds a triangle's float corners, its vertex ids for the sharing rules and the unit
// of its corners' integer form (64 bytes, one cache line: 64 MB on a 1M-triangle mesh, where the
// 128-byte record with the plane stored took 128). The narrow phase computes each triangle's
// plane as Shewchuk's orient3d does (the cross product of the two edges from corner 0 and, per
// component, the sum of the absolute products: the permanent's factors) when a pair needs it.
// The sign of a point against that plane is then one dot product, trusted when it exceeds
// Shewchuk's static bound (the same arithmetic as orient3d's float filter); only unsure signs
// take the exact path.
#pragma once

#include "cullide/mesh.h"
#include "cullide/predicates.h"

#include <cstddef>
#include <cstdint>

namespace cullide::oracle::detail {

struct alignas(64) Prim {
    float p[3][3];  // world corners (float; exact in double)
    Triangle v;  // vertex ids for the sharing rules (welded when asked)
    uint32_t triangle;  // index in the object's mesh
    int32_t unit;  // the corners' coordinates are integers times 2^unit below 2^62 (the lowest
                   // set bit among them), the edges below 2^30 of it; kNoUnit otherwise
};
static_assert(sizeof(Prim) == 64);

// A triangle's plane as orient3d's filter evaluates it: n = (p1 - p0) x (p2 - p0) and, per
// component, the sum of the absolute products (the permanent's factors). Compiled with the narrow
// phase (-ffp-contract=off: no fused multiply-adds).
struct Plane {
    double n[3], perm[3];
};
Plane planeOf(const Prim& prim);

// Sets unit from p (p, v, triangle set by the caller).
void setUnit(Prim& prim);

// The narrow phase of one candidate pair (planeA = planeOf(a): the broad phase hands over runs
// of pairs with the same a, which then share it) (faceContact's answer, exactly): by the shared vertex
// ids, the exact signs of each triangle's corners against the other's plane (filter first, then
// integer arithmetic), which reject most pairs; a shared vertex then takes one more orientation,
// other pairs Guigue-Devillers on those signs; faceContact only for the rare rest.
Contact primContact(const Prim& a, const Plane& planeA, const Prim& b, bool sameMesh);

}  // namespace cullide::oracle::detail
