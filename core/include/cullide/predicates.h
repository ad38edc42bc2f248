// Exact geometric predicates on double coordinates, and the rules for faces that share vertices:
// the one implementation that the oracle's narrow phase (for the cases its fast path cannot
// decide), the reliable method's exact pair check and the mesh statistics all call.
//
// References
//   - J. R. Shewchuk: Adaptive precision floating-point arithmetic and fast robust geometric
//     predicates. Discrete & Computational Geometry 18, 1997 (the static error bound of the
//     float filter in orient3d).
//   - P. Guigue, O. Devillers: Fast and robust triangle-triangle overlap test using orientation
//     predicates. JGT 8(1), 2003; as CGAL 5.5 writes it
//     (Intersections_3/internal/Triangle_3_Triangle_3_do_intersect.h), with our filtered orient3d.
//   - CGAL 5.5 Polygon_mesh_processing::self_intersections: the rules for faces that share
//     vertices (faceContact).
//
// Conventions
//   - Every answer is exact for finite inputs whose products neither overflow nor underflow;
//     floats converted to double (what the oracle feeds in) always qualify below 2^60. The float
//     filter decides when |det| exceeds Shewchuk's bound; then exact integer arithmetic when the
//     coordinates are floats close enough in magnitude; otherwise CGAL's Epick decides.
//   - Triangles passed to triangleContact/faceContact must be non-degenerate (not collinear).
//   - Classes: `Crossing` iff the triangles are not coplanar and their relative interiors meet
//     (so each has points strictly on both sides of the other's plane, and the two chords on the
//     planes' common line overlap in a segment of positive length); `Touching` iff they meet
//     otherwise (on a boundary of one of them, or coplanar); `None` iff they do not meet.
#pragma once

#include "cullide/mesh.h"

#include <array>
#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace cullide {

// Shewchuk's static error bound of orient3d's float filter, (7 + 56 eps) eps with eps = 2^-53:
// a determinant evaluated as orient3d does (three differences, then the cofactor expansion)
// whose magnitude exceeds this times the permanent has the exact determinant's sign.
inline constexpr double kOrient3dErrBound = (7.0 + 56.0 * 0x1p-53) * 0x1p-53;
// The same for orient2d, (3 + 16 eps) eps: (q_i - p_i)(r_j - p_j) - (q_j - p_j)(r_i - p_i)
// evaluated in that order, against the sum of the two products' magnitudes.
inline constexpr double kOrient2dErrBound = (3.0 + 16.0 * 0x1p-53) * 0x1p-53;
// orient2d's filter: a determinant so evaluated, whose magnitude exceeds kOrient2dErrBound times
// its permanent (the two products' magnitudes summed), is certainly not zero.
inline bool orient2dFilterNonZero(double det, double permanent) {
    return std::abs(det) > kOrient2dErrBound * permanent;
}

// Sign (+1, 0, -1) of det[q - p, r - p, s - p]: +1 when s is on the positive side of the plane
// through p, q, r oriented counterclockwise (CGAL::orientation's convention).
int orient3d(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s);

// Sign (+1, 0, -1) of the orientation of p, q, r projected on axes (i, j):
// (q_i - p_i)(r_j - p_j) - (q_j - p_j)(r_i - p_i), exactly.
int orient2d(const Vec3d& p, const Vec3d& q, const Vec3d& r, int i, int j);

// True when p, q, r are collinear (coincident points included), exactly.
bool collinear(const Vec3d& p, const Vec3d& q, const Vec3d& r);

// CGAL's coplanar_orientation(p, q, r, s) (coplanar points, p q r not collinear): +1 when s is on
// r's side of the line pq, -1 on the other side, 0 on the line.
int coplanarOrientation(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s);

// Two coplanar non-degenerate triangles (v, a1, a2) and (v, b1, b2) that share the corner v:
// whether their closed wedges at v share more than v (then the triangles meet besides v).
bool coplanarWedgesMeet(const Vec3d& v, const Vec3d& a1, const Vec3d& a2, const Vec3d& b1, const Vec3d& b2);

enum class Contact : uint8_t { None, Touching, Crossing };

using TrianglePoints = std::array<Vec3d, 3>;

// Whether two non-degenerate triangles meet, and how (the plain test: no sharing rules).
Contact triangleContact(const TrianglePoints& a, const TrianglePoints& b);

// triangleContact given the exact signs of a's corners against b's plane (da[k] =
// orient3d(b's corners, a[k])) and of b's against a's (db): Guigue-Devillers on them.
Contact triangleContactFromSigns(const TrianglePoints& a, const TrianglePoints& b, const int da[3], const int db[3]);

// Whether the closed segment [s0, s1] meets the closed non-degenerate triangle t.
bool triangleSegmentIntersect(const TrianglePoints& t, const Vec3d& s0, const Vec3d& s1);

// Two faces of one mesh, with their vertex indices: the sharing rules (docs/oracle.md) then the
// plain test. Pass sameMesh = false for faces of different objects (indices ignored).
Contact faceContact(const TrianglePoints& a, const Triangle& ia, const TrianglePoints& b, const Triangle& ib,
                    bool sameMesh);

// Floats as exact integers of one power of two, the building block of the exact integer paths.
inline constexpr int32_t kNoUnit = INT32_MIN;

// The power of two 2^unit in which all of `coordinates` are integers below 2^62 (unit: their
// lowest set bit; 0 when all are zero), or kNoUnit when they span more than 62 bits. Inline: the
// oracle's setup calls it once per triangle (nine coordinates).
inline int32_t integerUnit(const float* coordinates, size_t count) {
    int emin = 1 << 20, emax = -(1 << 20);
    for (size_t i = 0; i < count; ++i) {
        const uint32_t b = std::bit_cast<uint32_t>(coordinates[i]);
        int e = int((b >> 23) & 0xff);
        uint32_t mant = b & 0x7fffff;
        if (e != 0) mant |= 0x800000;
        else e = 1;  // subnormal
        if (mant == 0) continue;
        // |x| = mant * 2^(e - 150): its lowest set bit, and 2^emax above |x|.
        emin = std::min(emin, e - 150 + std::countr_zero(mant));
        emax = std::max(emax, e - 150 + 32 - std::countl_zero(mant));
    }
    if (emax < emin) return 0;  // all zero
    return emax - emin > 62 ? kNoUnit : emin;
}

// 2^-unit, the scale that takes coordinates to integers of 2^unit (unit from integerUnit).
inline double unitScale(int32_t unit) {
    return std::bit_cast<double>(uint64_t(1023 - unit) << 52);
}

// x (a float) in integers of 2^unit, given scale = unitScale(unit): exact (a power-of-two
// scaling to an integer below 2^62).
inline int64_t toUnit(float x, double scale) {
    return int64_t(double(x) * scale);
}

}  // namespace cullide
