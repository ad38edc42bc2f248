// The oracle's narrow phase on packed primitive records (internal to oracle/).
//
// A record holds a triangle's float corners, its vertex ids for the sharing rules and its plane
// as Shewchuk's orient3d computes it (the cross product of the two edges from corner 0 and, per
// component, the sum of the absolute products: the permanent's factors). The sign of a point
// against that plane is then one dot product, trusted when it exceeds Shewchuk's static bound
// (the same arithmetic as orient3d's float filter); only unsure pairs take the full exact path.
#pragma once

#include "cullide/mesh.h"
#include "cullide/predicates.h"

#include <cstddef>
#include <cstdint>

namespace cullide::oracle::detail {

struct alignas(64) Prim {
    double n[3];  // (p1 - p0) x (p2 - p0), evaluated as orient3d's filter does
    double perm[3];  // |products| of each component of n, summed (the permanent's factors)
    int64_t ni[3];  // the same cross product exactly, in integers of 2^unit (when unit is set)
    float p[3][3];  // world corners (float; exact in double)
    Triangle v;  // vertex ids for the sharing rules (welded when asked)
    uint32_t triangle;  // index in the object's mesh
    int32_t unit;  // the corners' coordinates are integers times 2^unit below 2^62 (the lowest
                   // set bit among them), the edges below 2^30 of it; kNoUnit otherwise
};
static_assert(sizeof(Prim) == 128);

// Fills n, perm, ni and unit from p (p, v, triangle set by the caller).
void setPlane(Prim& prim);

// The narrow phase of one candidate pair (faceContact's answer, exactly): by the shared vertex
// ids, the exact signs of each triangle's corners against the other's plane (filter first, then
// integer arithmetic), which reject most pairs; a shared vertex then takes one more orientation,
// other pairs Guigue-Devillers on those signs; faceContact only for the rare rest.
Contact primContact(const Prim& a, const Prim& b, bool sameMesh);

}  // namespace cullide::oracle::detail
