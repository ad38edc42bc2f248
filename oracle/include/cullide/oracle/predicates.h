// Exact geometric predicates of the oracle, on double coordinates.
//
// References
//   - J. R. Shewchuk: Adaptive precision floating-point arithmetic and fast robust geometric
//     predicates. Discrete & Computational Geometry 18, 1997 (the static error bound of the
//     float filter in orient3d).
//   - P. Guigue, O. Devillers: Fast and robust triangle-triangle overlap test using orientation
//     predicates. JGT 8(1), 2003; as CGAL 5.5 writes it
//     (Intersections_3/internal/Triangle_3_Triangle_3_do_intersect.h), with our filtered orient3d.
//
// Conventions
//   - Every answer is exact for finite inputs whose products neither overflow nor underflow;
//     floats converted to double (what the oracle feeds in) always qualify below 2^60. The float
//     filter decides when |det| exceeds Shewchuk's bound; otherwise CGAL's Epick decides.
//   - Triangles passed to triangleContact/faceContact must be non-degenerate (not collinear).
//   - Classes: `Crossing` iff the triangles are not coplanar and their relative interiors meet
//     (so each has points strictly on both sides of the other's plane, and the two chords on the
//     planes' common line overlap in a segment of positive length); `Touching` iff they meet
//     otherwise (on a boundary of one of them, or coplanar); `None` iff they do not meet.
#pragma once

#include "cullide/mesh.h"

#include <array>
#include <cstdint>

namespace cullide::oracle {

// Sign (+1, 0, -1) of det[q - p, r - p, s - p]: +1 when s is on the positive side of the plane
// through p, q, r oriented counterclockwise (CGAL::orientation's convention).
int orient3d(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s);

// True when p, q, r are collinear (coincident points included), exactly.
bool collinear(const Vec3d& p, const Vec3d& q, const Vec3d& r);

enum class Contact : uint8_t { None, Touching, Crossing };

using TrianglePoints = std::array<Vec3d, 3>;

// Whether two non-degenerate triangles meet, and how (the plain test: no sharing rules).
Contact triangleContact(const TrianglePoints& a, const TrianglePoints& b);

// Whether the closed segment [s0, s1] meets the closed non-degenerate triangle t.
bool triangleSegmentIntersect(const TrianglePoints& t, const Vec3d& s0, const Vec3d& s1);

// Two faces of one mesh, with their vertex indices: the sharing rules (oracle.h, docs/oracle.md)
// then the plain test. Pass sameMesh = false for faces of different objects (indices ignored).
Contact faceContact(const TrianglePoints& a, const Triangle& ia, const TrianglePoints& b, const Triangle& ib,
                    bool sameMesh);

}  // namespace cullide::oracle
