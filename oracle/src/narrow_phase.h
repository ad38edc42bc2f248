// The oracle's narrow phase on packed primitive records (internal to oracle/).
//
// A record holds a triangle's float corners and its vertex ids for the sharing rules (64 bytes,
// one cache line: 64 MB on a 1M-triangle mesh, where the 128-byte record with the plane stored
// took 128). Each triangle's plane is computed as Shewchuk's orient3d does (the cross product of
// the two edges from corner 0 and, per component, the sum of the absolute products: the
// permanent's factors): on small scenes once per triangle in the setup (oracle.cpp, beside the
// records), on large ones when a pair needs it.
// The sign of a point against that plane is then one dot product, trusted when it exceeds
// Shewchuk's static bound (the same arithmetic as orient3d's float filter); only unsure signs
// take the exact path.
#pragma once

#include "broad_phase.h"
#include "cullide/mesh.h"
#include "cullide/predicates.h"

#include <cstddef>
#include <cstdint>
#include <span>

namespace cullide::oracle::detail {

struct alignas(64) Prim {
    float p[3][3];  // world corners (float; exact in double)
    Triangle v;  // vertex ids for the sharing rules (welded when asked)
    uint32_t triangle;  // index in the object's mesh
    // Bit k: the triangle projected along axis k (onto axes k + 1 and k + 2, mod 3) is
    // counterclockwise, bit 3 + k: clockwise; neither: edge-on (exact; projectedTurns).
    uint8_t turns;
    // Bit c: corner c's fan is certified (certifyFans): every other triangle of the object that has
    // this corner's vertex meets this one only there, or only along their shared edge.
    uint8_t fans;
};
static_assert(sizeof(Prim) == 64);

// A triangle's plane as orient3d's filter evaluates it: n = (p1 - p0) x (p2 - p0) and, per
// component, the sum of the absolute products (the permanent's factors). Compiled with the narrow
// phase (-ffp-contract=off: no fused multiply-adds).
struct Plane {
    double n[3], perm[3];
};
Plane planeOf(const Prim& prim);
// The same from the corners (the setup's: not read back from a record just written, whose float
// stores an 8-byte load would wait for).
Plane planeOf(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2);
// Whether the corners of planeOf(p0, p1, p2) are certainly not collinear: its n[k] and perm[k] are
// orient2d's determinant and permanent on the axis pairs (1, 2), (2, 0) and (0, 1), evaluated as
// collinear() evaluates them, so this is collinear()'s own filter. False: ask collinear().
inline bool certainlyNotCollinear(const Plane& p) {
    return orient2dFilterNonZero(p.n[0], p.perm[0]) | orient2dFilterNonZero(p.n[1], p.perm[1]) |
        orient2dFilterNonZero(p.n[2], p.perm[2]);
}

// Prim::turns of the triangle p0 p1 p2 whose planeOf is `plane`: the signs of its components
// (orient2d's determinants on the axis pairs (1, 2), (2, 0), (0, 1)), by the filter, else exactly.
uint8_t projectedTurnsExact(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Plane& plane);
// Written out per axis: GCC 12 with -O2 -fsanitize=address,undefined compiled the loop over k,
// inlined into a test, to read n[0] for every axis (tests/oracle_test.cpp,
// CertifiedFansMeetOnlyAtTheirVertex, caught it).
inline uint8_t projectedTurns(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Plane& plane) {
    const double x = plane.n[0], y = plane.n[1], z = plane.n[2];
    const bool sure = orient2dFilterNonZero(x, plane.perm[0]) & orient2dFilterNonZero(y, plane.perm[1]) &
        orient2dFilterNonZero(z, plane.perm[2]);
    if (!sure) return projectedTurnsExact(p0, p1, p2, plane);
    return uint8_t(int(x > 0) | int(y > 0) << 1 | int(z > 0) << 2 | int(x < 0) << 3 | int(y < 0) << 4 | int(z < 0) << 5);
}

// Sets Prim::fans of one object's records (turns filled; vertex ids below vertexCount), with
// scratch from `arena` (null: malloc). A vertex's fan is certified when the records that have it
// (its fan) project along one axis to triangles of one turning sense whose outer edges form
// closed paths around the vertex that together wind around it exactly once. Their images then
// tile the plane around the vertex's image once: two triangles of the fan that share only the
// vertex have images that meet only at its image, two that share an edge only along that edge's
// image, and since each triangle projects one to one, the triangles meet only at the vertex, or
// only along the edge (no contact by faceContact's rules). Exact: each turn from the filter or
// orient2d, the winding from the records' corners compared as floats (docs/oracle.md, "Fans").
void certifyFans(std::span<Prim> prims, size_t vertexCount, PageArena* arena);

// Objects of more triangles than this have their primitive records in Morton order of their
// first corner (cache locality of the narrow phase's reads); smaller ones keep the mesh's own
// order (fits in cache; meshes come mostly in a coherent order). A variable so that the tests can
// run both orders on the same mesh; 2^16 (oracle.cpp).
extern size_t spatialOrderMin;

// Scenes of up to this many triangles have each triangle's plane computed once, in the setup (48
// bytes each; 6% of the oracle on a 6k mesh when computed per pair), and their candidates tested
// by primContacts; larger ones compute the planes where a pair needs them (the memory counts
// more) and test one pair at a time. A variable so that the tests can run both paths on the same
// scene; 2^18 (oracle.cpp).
extern size_t storedPlanesMax;

// Whether a call without a Workspace takes its arrays from a PageArena of its own
// (cullide/unwritten.h): where PageArena::available() (the default), never, or always (tests, so
// that both paths run on any machine). A variable so that the tests can run each (oracle.cpp).
enum class CallArena : uint8_t { WhereAvailable, Never, Always };
extern CallArena callArena;

// The narrow phase of one candidate pair (planeA = planeOf(a); storedB = &planeOf(b) where stored,
// null to compute it here when needed) (faceContact's answer, exactly): by the shared vertex
// ids, the exact signs of each triangle's corners against the other's plane (filter first, then
// integer arithmetic), which reject most pairs; a shared vertex then takes one more orientation,
// other pairs Guigue-Devillers on those signs; faceContact only for the rare rest.
Contact primContact(const Prim& a, const Plane& planeA, const Prim& b, const Plane* storedB, bool sameMesh);

// One object's records and stored planes (planes[i] = planeOf(prims[i])).
struct StoredPrims {
    const Prim* prims;
    const Plane* planes;
};

// Whether the broad phase reported the pair in the order the narrow phase tests: the lower object
// first, the lower primitive first within one object (it reports each unordered pair once; a pair
// in the other order, or a primitive with itself, is skipped and not counted).
inline bool inTestOrder(const Candidate& c) {
    return c.object0 < c.object1 || (c.object0 == c.object1 && c.prim0 < c.prim1);
}

// A candidate pair whose triangles meet: its index in the batch, and how.
struct Hit {
    uint32_t pair;
    Contact contact;
};

// primContact of each candidate pair (objects[o]: object o's records, planes stored): writes the
// pairs that meet to hits (room for count), returns how many, and adds to `tested` the number of
// pairs tested (those inTestOrder).
uint32_t primContacts(const StoredPrims* objects, const Candidate* pairs, uint32_t count, Hit* hits, size_t& tested);

}  // namespace cullide::oracle::detail
