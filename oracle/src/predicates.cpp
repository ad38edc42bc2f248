// Exact predicates and the triangle-triangle narrow phase (see predicates.h).
//
// References
//   - J. R. Shewchuk, DCG 18 (1997): orient3d's static filter. With u = q - p, v = r - p,
//     w = s - p computed in double, det = u . (v x w) evaluated in double is within
//     (7 + 56 eps) eps * permanent of the exact determinant of the (exact) input points, where
//     eps = 2^-53 and permanent is the same sum with absolute values; orient2d: (3 + 16 eps) eps.
//   - P. Guigue, O. Devillers, JGT 8(1) (2003), as written in CGAL 5.5
//     (Intersections_3/internal/Triangle_3_Triangle_3_do_intersect.h): the same case table and the
//     same two final orientations, so that our answers are CGAL's answers.
//
// This file and cgal_reference.cpp are the only ones that include CGAL. It is compiled with
// -frounding-math (CGAL's interval filters need it) and -ffp-contract=off (the error bounds
// assume every product and sum is rounded on its own, never fused).
#include "cullide/oracle/predicates.h"

#include "narrow_phase.h"

#include "cullide/error.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace cullide::oracle {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

Point toPoint(const Vec3d& p) { return Point(p.x(), p.y(), p.z()); }

constexpr double kEps = 0x1p-53;
constexpr double kO3dErrBound = (7.0 + 56.0 * kEps) * kEps;
constexpr double kO2dErrBound = (3.0 + 16.0 * kEps) * kEps;

// orient3d exactly in integers when the 12 coordinates are floats (as the oracle's always are)
// close enough in magnitude: each coordinate is an integer times 2^emin (emin: the lowest set
// bit among them), below 2^62 in that unit when the spread allows; the differences then need at
// most 41 bits each for the determinant to fit a 128-bit integer (3 * 41 + 3 bits). Returns false
// (undecided) otherwise. It decides exactly the cases the float filter cannot: nearly or exactly
// coplanar points, which CGAL would hand to multiprecision arithmetic.
// Exact integer coordinates for n float-valued doubles: each is an integer times 2^emin (emin:
// the lowest set bit among them); false when one is not a float or they span over 62 bits.
bool toIntegers(const double* x, int n, int64_t* out) {
    int emin = 1 << 20, emax = -(1 << 20);
    int64_t m[12];
    int unit[12];
    for (int i = 0; i < n; ++i) {
        const float f = float(x[i]);
        if (double(f) != x[i]) return false;
        const uint32_t b = std::bit_cast<uint32_t>(f);
        int e = int((b >> 23) & 0xff);
        uint32_t mant = b & 0x7fffff;
        if (e != 0) mant |= 0x800000;
        else e = 1;  // subnormal
        unit[i] = e - 150;  // |f| = mant * 2^unit
        m[i] = (b >> 31) ? -int64_t(mant) : int64_t(mant);
        if (mant == 0) continue;
        emin = std::min(emin, unit[i] + std::countr_zero(mant));
        emax = std::max(emax, unit[i] + 32 - std::countl_zero(mant));  // |f| < 2^emax
    }
    if (emax - emin > 62) return false;
    for (int i = 0; i < n; ++i) {
        if (m[i] == 0) {
            out[i] = 0;
            continue;
        }
        // m * 2^(unit - emin): unit >= emin - 23 (m's trailing zeros), |result| < 2^62.
        const int shift = unit[i] - emin;
        out[i] = shift >= 0 ? m[i] << shift : m[i] >> -shift;  // exact (C++20 shifts of negatives)
    }
    return true;
}

// orient3d exactly in integers when the 12 coordinates are floats (as the oracle's always are)
// close enough in magnitude: the differences then need at most 41 bits each for the determinant
// to fit a 128-bit integer (3 * 41 + 3 bits). Returns false (undecided) otherwise. It decides the
// cases the float filter cannot (nearly or exactly coplanar points) without CGAL's
// multiprecision arithmetic.
bool orient3dFromFloats(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s, int* result) {
    const double x[12] = {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), r.x(), r.y(), r.z(), s.x(), s.y(), s.z()};
    int64_t c[12];
    if (!toIntegers(x, 12, c)) return false;
    int64_t d[3][3];
    constexpr int64_t kLimit = int64_t(1) << 41;
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
            d[i][k] = c[3 * (i + 1) + k] - c[k];  // |.| < 2^63
            if (d[i][k] >= kLimit || d[i][k] <= -kLimit) return false;
        }
    using I = __int128;
    const I det = I(d[0][0]) * (I(d[1][1]) * d[2][2] - I(d[1][2]) * d[2][1]) +
                  I(d[0][1]) * (I(d[1][2]) * d[2][0] - I(d[1][0]) * d[2][2]) +
                  I(d[0][2]) * (I(d[1][0]) * d[2][1] - I(d[1][1]) * d[2][0]);
    *result = det > 0 ? 1 : det < 0 ? -1 : 0;
    return true;
}

// Sign of the 2D orientation of p, q, r projected on axes (i, j), exactly: float filter, then
// integers (differences below 2^62 bits... checked: below 2^61), then CGAL.
int orient2d(const Vec3d& p, const Vec3d& q, const Vec3d& r, int i, int j) {
    const double l = (q[i] - p[i]) * (r[j] - p[j]);
    const double rr = (q[j] - p[j]) * (r[i] - p[i]);
    const double det = l - rr;
    const double bound = kO2dErrBound * (std::abs(l) + std::abs(rr));
    if (det > bound) return 1;
    if (-det > bound) return -1;
    const double x[6] = {p[i], p[j], q[i], q[j], r[i], r[j]};
    int64_t c[6];
    if (toIntegers(x, 6, c)) {
        const int64_t a = c[2] - c[0], b = c[3] - c[1], e = c[4] - c[0], f = c[5] - c[1];  // |.| < 2^63
        constexpr int64_t kLimit = int64_t(1) << 62;
        if (a < kLimit && a > -kLimit && b < kLimit && b > -kLimit && e < kLimit && e > -kLimit && f < kLimit && f > -kLimit) {
            const __int128 d = __int128(a) * f - __int128(b) * e;  // |.| < 2^125
            return d > 0 ? 1 : d < 0 ? -1 : 0;
        }
    }
    using P2 = Kernel::Point_2;
    const CGAL::Orientation o = CGAL::orientation(P2(p[i], p[j]), P2(q[i], q[j]), P2(r[i], r[j]));
    return o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0;
}

// CGAL's coplanar_orientation(p, q, r, s) (coplanar points, p q r not collinear): +1 when s is on
// r's side of the line pq, -1 on the other side, 0 on the line; its projections, in its order.
int coplanarOrientation(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s) {
    static constexpr int kAxes[3][2] = {{0, 1}, {1, 2}, {0, 2}};
    for (const auto& ax : kAxes) {
        const int o = orient2d(p, q, r, ax[0], ax[1]);
        if (o != 0) return o * orient2d(p, q, s, ax[0], ax[1]);
    }
    return 0;  // p q r collinear: not called so
}

int sign(CGAL::Orientation o) { return o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0; }

// A 2D orientation in the projection onto axes (i, j) certainly non-zero (float filter)?
bool orient2dCertainlyNonZero(const Vec3d& p, const Vec3d& q, const Vec3d& r, int i, int j) {
    const double l = (q[i] - p[i]) * (r[j] - p[j]);
    const double rr = (q[j] - p[j]) * (r[i] - p[i]);
    const double det = l - rr;
    return std::abs(det) > kO2dErrBound * (std::abs(l) + std::abs(rr));
}

// Coplanar points, exactly: an axis pair (i, j) on which the non-degenerate triangle t projects
// non-degenerately, and its orientation there (CGAL's projection order: xy, yz, xz).
int coplanarFrame(const TrianglePoints& t, int* i, int* j) {
    static constexpr int kAxes[3][2] = {{0, 1}, {1, 2}, {0, 2}};
    for (const auto& ax : kAxes) {
        const int o = orient2d(t[0], t[1], t[2], ax[0], ax[1]);
        if (o != 0) {
            *i = ax[0], *j = ax[1];
            return o;
        }
    }
    return 0;
}

// p on the closed segment [a, b], given that the three are collinear (in projection i, j).
bool onCollinearSegment(const Vec3d& a, const Vec3d& b, const Vec3d& p, int i, int j) {
    return std::min(a[i], b[i]) <= p[i] && p[i] <= std::max(a[i], b[i]) && std::min(a[j], b[j]) <= p[j] &&
           p[j] <= std::max(a[j], b[j]);
}

// Closed segments [p1, p2] and [p3, p4] meet (2D, projection i, j).
bool segmentsMeet2d(const Vec3d& p1, const Vec3d& p2, const Vec3d& p3, const Vec3d& p4, int i, int j) {
    const int d1 = orient2d(p3, p4, p1, i, j), d2 = orient2d(p3, p4, p2, i, j);
    const int d3 = orient2d(p1, p2, p3, i, j), d4 = orient2d(p1, p2, p4, i, j);
    if (d1 * d2 < 0 && d3 * d4 < 0) return true;
    return (d1 == 0 && onCollinearSegment(p3, p4, p1, i, j)) || (d2 == 0 && onCollinearSegment(p3, p4, p2, i, j)) ||
           (d3 == 0 && onCollinearSegment(p1, p2, p3, i, j)) || (d4 == 0 && onCollinearSegment(p1, p2, p4, i, j));
}

// p in the closed triangle t (2D, projection i, j, t's orientation o there).
bool inTriangle2d(const TrianglePoints& t, const Vec3d& p, int i, int j, int o) {
    return orient2d(t[0], t[1], p, i, j) * o >= 0 && orient2d(t[1], t[2], p, i, j) * o >= 0 &&
           orient2d(t[2], t[0], p, i, j) * o >= 0;
}

// The closed segment [s0, s1] meets the closed triangle t, all coplanar: an end inside, or the
// segment meets an edge. Exact (orient2d); CGAL's answer.
bool coplanarTriangleSegment(const TrianglePoints& t, const Vec3d& s0, const Vec3d& s1) {
    int i = 0, j = 1;
    const int o = coplanarFrame(t, &i, &j);
    if (inTriangle2d(t, s0, i, j, o) || inTriangle2d(t, s1, i, j, o)) return true;
    for (int k = 0; k < 3; ++k)
        if (segmentsMeet2d(s0, s1, t[k], t[(k + 1) % 3], i, j)) return true;
    return false;
}

// Two coplanar closed triangles meet: an edge of a meets b, or b lies inside a.
bool coplanarTriangles(const TrianglePoints& a, const TrianglePoints& b) {
    for (int k = 0; k < 3; ++k)
        if (coplanarTriangleSegment(b, a[k], a[(k + 1) % 3])) return true;
    int i = 0, j = 1;
    const int o = coplanarFrame(a, &i, &j);
    return inTriangle2d(a, b[0], i, j, o);
}

// Guigue-Devillers' canonical order, CGAL's table: given the signs of a triangle's corners
// (0, 1, 2) with respect to the other's plane, the corners (sMin, tMin, sMax, tMax) of the two
// edges that bound its chord on the planes' common line. Returns false when all three signs are
// equal and non-zero (no contact) or all are zero (coplanar: *coplanar set).
bool canonicalOrder(int d0, int d1, int d2, int idx[4], bool* coplanar) {
    auto set = [&](int a, int b, int c, int d) { idx[0] = a, idx[1] = b, idx[2] = c, idx[3] = d; };
    *coplanar = false;
    if (d0 > 0) {
        if (d1 > 0) {
            if (d2 > 0) return false;
            set(1, 2, 2, 0);
        } else if (d2 > 0) {
            set(0, 1, 1, 2);
        } else {
            set(0, 1, 2, 0);
        }
    } else if (d0 < 0) {
        if (d1 < 0) {
            if (d2 < 0) return false;
            set(2, 0, 1, 2);
        } else if (d2 < 0) {
            set(1, 2, 0, 1);
        } else {
            set(2, 0, 0, 1);
        }
    } else if (d1 > 0) {
        if (d2 > 0) set(2, 0, 0, 1);
        else set(1, 2, 0, 1);
    } else if (d1 < 0) {
        if (d2 < 0) set(0, 1, 2, 0);
        else set(0, 1, 1, 2);
    } else if (d2 > 0) {
        set(2, 0, 1, 2);
    } else if (d2 < 0) {
        set(1, 2, 2, 0);
    } else {
        *coplanar = true;
        return false;
    }
    return true;
}

bool straddles(int d0, int d1, int d2) {
    return (d0 > 0 || d1 > 0 || d2 > 0) && (d0 < 0 || d1 < 0 || d2 < 0);
}

// Guigue-Devillers given the exact signs of a's corners against b's plane (da) and of b's
// against a's (db): CGAL's do_intersect, with crossing told from touching.
Contact triangleContactFromSigns(const TrianglePoints& a, const TrianglePoints& b, const int da[3], const int db[3]) {
    int ia[4], ib[4];
    bool coplanar = false;
    if (!canonicalOrder(da[0], da[1], da[2], ia, &coplanar)) {
        if (!coplanar) return Contact::None;
        // Coplanar: CGAL's 2D test on coplanar orientations (rare; it decides exactly too).
        return coplanarTriangles(a, b) ? Contact::Touching : Contact::None;
    }
    if (!canonicalOrder(db[0], db[1], db[2], ib, &coplanar)) {
        // b's corners all on a's plane while a's are not all on b's: impossible for
        // non-degenerate triangles, but answer as CGAL does.
        if (!coplanar) return Contact::None;
        return coplanarTriangles(a, b) ? Contact::Touching : Contact::None;
    }
    // The chords [i, j] of a and [k, l] of b on the common line overlap iff k <= j and i <= l;
    // each comparison is the sign of one orientation (zero: the two ends coincide).
    const int lo = orient3d(a[ia[0]], a[ia[1]], b[ib[0]], b[ib[1]]);
    const int hi = orient3d(a[ia[2]], a[ia[3]], b[ib[3]], b[ib[2]]);
    if (lo > 0 || hi > 0) return Contact::None;
    // Crossing: both straddle the other's plane and the overlap has positive length, i.e. both
    // comparisons are strict; then the overlap's inner points are interior to both triangles.
    if (lo < 0 && hi < 0 && straddles(da[0], da[1], da[2]) && straddles(db[0], db[1], db[2])) return Contact::Crossing;
    return Contact::Touching;
}

}  // namespace

int orient3d(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s) {
    const double ux = q.x() - p.x(), uy = q.y() - p.y(), uz = q.z() - p.z();
    const double vx = r.x() - p.x(), vy = r.y() - p.y(), vz = r.z() - p.z();
    const double wx = s.x() - p.x(), wy = s.y() - p.y(), wz = s.z() - p.z();
    const double m1 = vy * wz, m2 = vz * wy, m3 = vz * wx, m4 = vx * wz, m5 = vx * wy, m6 = vy * wx;
    const double det = ux * (m1 - m2) + uy * (m3 - m4) + uz * (m5 - m6);
    const double permanent = (std::abs(m1) + std::abs(m2)) * std::abs(ux) + (std::abs(m3) + std::abs(m4)) * std::abs(uy) +
                             (std::abs(m5) + std::abs(m6)) * std::abs(uz);
    const double bound = kO3dErrBound * permanent;
    if (det > bound) return 1;
    if (-det > bound) return -1;
    int exact = 0;
    if (orient3dFromFloats(p, q, r, s, &exact)) return exact;
    return sign(CGAL::orientation(toPoint(p), toPoint(q), toPoint(r), toPoint(s)));
}

bool collinear(const Vec3d& p, const Vec3d& q, const Vec3d& r) {
    // Collinear iff all three axis-plane projections have zero orientation.
    if (orient2dCertainlyNonZero(p, q, r, 0, 1) || orient2dCertainlyNonZero(p, q, r, 1, 2) ||
        orient2dCertainlyNonZero(p, q, r, 2, 0))
        return false;
    return CGAL::collinear(toPoint(p), toPoint(q), toPoint(r));
}

Contact triangleContact(const TrianglePoints& a, const TrianglePoints& b) {
    // Signs of a's corners with respect to b's plane, then of b's with respect to a's.
    const int da[3] = {orient3d(b[0], b[1], b[2], a[0]), orient3d(b[0], b[1], b[2], a[1]), orient3d(b[0], b[1], b[2], a[2])};
    if (da[0] == da[1] && da[1] == da[2] && da[0] != 0) return Contact::None;
    const int db[3] = {orient3d(a[0], a[1], a[2], b[0]), orient3d(a[0], a[1], a[2], b[1]), orient3d(a[0], a[1], a[2], b[2])};
    return triangleContactFromSigns(a, b, da, db);
}

bool triangleSegmentIntersect(const TrianglePoints& t, const Vec3d& s0, const Vec3d& s1) {
    const int d0 = orient3d(t[0], t[1], t[2], s0);
    const int d1 = orient3d(t[0], t[1], t[2], s1);
    if (d0 == d1 && d0 != 0) return false;  // both strictly on one side
    if (d0 == 0 && d1 == 0)                 // in the triangle's plane: CGAL's coplanar test
        return coplanarTriangleSegment(t, s0, s1);
    // The segment meets the plane in one point; it lies in the closed triangle iff the line
    // s0 s1 passes on the same (closed) side of the three edges.
    const int e0 = orient3d(s0, s1, t[0], t[1]);
    const int e1 = orient3d(s0, s1, t[1], t[2]);
    const int e2 = orient3d(s0, s1, t[2], t[0]);
    return (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
}

Contact faceContact(const TrianglePoints& a, const Triangle& ia, const TrianglePoints& b, const Triangle& ib,
                    bool sameMesh) {
    if (sameMesh) {
        int shared = 0, sa[3] = {0, 0, 0}, sb[3] = {0, 0, 0};  // positions of shared indices
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (ia[i] == ib[j]) {
                    sa[shared] = i;
                    sb[shared] = j;
                    ++shared;
                    break;
                }
        if (shared == 3) return Contact::Touching;  // a duplicated face lies on itself
        if (shared == 2) {
            // Shared edge (CGAL's rule): a fold-over iff the four corners are coplanar and the
            // two opposite corners are strictly on the same side of the edge.
            const Vec3d& e0 = a[sa[0]];
            const Vec3d& e1 = a[sa[1]];
            const Vec3d& ra = a[3 - sa[0] - sa[1]];
            const Vec3d& rb = b[3 - sb[0] - sb[1]];
            if (orient3d(a[0], a[1], a[2], rb) != 0) return Contact::None;
            return coplanarOrientation(e0, e1, ra, rb) > 0 ? Contact::Touching : Contact::None;
        }
        if (shared == 1) {
            // Shared vertex (CGAL's rule): they meet elsewhere iff one meets the other's
            // opposite edge.
            const int i = sa[0], j = sb[0];
            if (!triangleSegmentIntersect(a, b[(j + 1) % 3], b[(j + 2) % 3]) &&
                !triangleSegmentIntersect(b, a[(i + 1) % 3], a[(i + 2) % 3]))
                return Contact::None;
            const Contact c = triangleContact(a, b);
            CULLIDE_CHECK(c != Contact::None, "faceContact: triangles sharing a vertex must meet");
            return c;
        }
    }
    return triangleContact(a, b);
}

namespace detail {
namespace {

// 2^k as a double (-1022 <= k <= 1023).
double pow2(int k) { return std::bit_cast<double>(uint64_t(1023 + k) << 52); }

// x (a float) in integers of 2^unit: exact (a power-of-two scaling, an integer below 2^62).
int64_t toUnit(float x, double scale) { return int64_t(double(x) * scale); }

Vec3d corner(const Prim& p, int k) { return Vec3d(p.p[k][0], p.p[k][1], p.p[k][2]); }

// Sign of orient3d(a's corners, (x, y, z)) when the float filter is sure of it, else 0. The same
// arithmetic as orient3d (w = s - p0; det = sum w_k n_k; permanent = sum |w_k| perm_k; the error
// bound (7 + 56 eps) eps * permanent), with the cofactor expansion along w instead of u, which
// Shewchuk's analysis covers alike (each term one difference times a 2x2 minor of differences).
inline int planeSide(const Prim& a, double x, double y, double z) {
    const double wx = x - double(a.p[0][0]), wy = y - double(a.p[0][1]), wz = z - double(a.p[0][2]);
    const double det = wx * a.n[0] + wy * a.n[1] + wz * a.n[2];
    const double permanent = std::abs(wx) * a.perm[0] + std::abs(wy) * a.perm[1] + std::abs(wz) * a.perm[2];
    const double bound = kO3dErrBound * permanent;
    return det > bound ? 1 : -det > bound ? -1 : 0;
}
inline int planeSide(const Prim& a, const Prim& b, int k) { return planeSide(a, b.p[k][0], b.p[k][1], b.p[k][2]); }

// Sign of orient3d(a's corners, b's corner k) when the filter cannot tell: a's integer normal
// when b's corner is an integer in a's unit (|N| < 2^61, |w| < 2^63: the dot product fits 126
// bits), then orient3d.
[[gnu::noinline]] int exactSideSlow(const Prim& a, const Prim& b, int k) {
    if (a.unit != kNoUnit) {
        const double scale = pow2(-a.unit);
        __int128 det = 0;
        bool exact = true;
        for (int c = 0; c < 3; ++c) {
            // b's corner in a's unit: exact when it is an integer there, below 2^62.
            const double y = double(b.p[k][c]) * scale;
            if (!(std::abs(y) < 0x1p62)) {
                exact = false;
                break;
            }
            const int64_t q = int64_t(y);
            if (double(q) != y) {
                exact = false;
                break;
            }
            det += __int128(a.ni[c]) * (q - toUnit(a.p[0][c], scale));  // |N| < 2^61, |w| < 2^63
        }
        if (exact) return det > 0 ? 1 : det < 0 ? -1 : 0;
    }
    return orient3d(corner(a, 0), corner(a, 1), corner(a, 2), corner(b, k));
}

// Sign of orient3d(a's corners, b's corner k), exactly: the filter, then exactSideSlow.
inline int exactSide(const Prim& a, const Prim& b, int k) {
    const int d = planeSide(a, b, k);
    return d != 0 ? d : exactSideSlow(a, b, k);
}

}  // namespace

int32_t integerUnit(const float* x, size_t count) {
    int emin = 1 << 20, emax = -(1 << 20);
    for (size_t i = 0; i < count; ++i) {
        const uint32_t b = std::bit_cast<uint32_t>(x[i]);
        int e = int((b >> 23) & 0xff);
        uint32_t mant = b & 0x7fffff;
        if (e != 0) mant |= 0x800000;
        else e = 1;
        if (mant == 0) continue;
        emin = std::min(emin, e - 150 + std::countr_zero(mant));
        emax = std::max(emax, e - 150 + 32 - std::countl_zero(mant));
    }
    if (emax < emin) return 0;  // all zero
    return emax - emin > 62 ? kNoUnit : emin;
}

void setPlane(Prim& prim) {
    const double ux = double(prim.p[1][0]) - double(prim.p[0][0]), uy = double(prim.p[1][1]) - double(prim.p[0][1]),
                 uz = double(prim.p[1][2]) - double(prim.p[0][2]);
    const double vx = double(prim.p[2][0]) - double(prim.p[0][0]), vy = double(prim.p[2][1]) - double(prim.p[0][1]),
                 vz = double(prim.p[2][2]) - double(prim.p[0][2]);
    const double m1 = uy * vz, m2 = uz * vy, m3 = uz * vx, m4 = ux * vz, m5 = ux * vy, m6 = uy * vx;
    prim.n[0] = m1 - m2, prim.n[1] = m3 - m4, prim.n[2] = m5 - m6;
    prim.perm[0] = std::abs(m1) + std::abs(m2);
    prim.perm[1] = std::abs(m3) + std::abs(m4);
    prim.perm[2] = std::abs(m5) + std::abs(m6);
    prim.unit = kNoUnit;
    prim.ni[0] = prim.ni[1] = prim.ni[2] = 0;
    const int32_t unit = integerUnit(&prim.p[0][0], 9);
    if (unit == kNoUnit) return;
    const double scale = pow2(-unit);
    int64_t u[3], v[3];
    constexpr int64_t kLimit = int64_t(1) << 30;
    for (int k = 0; k < 3; ++k) {
        const int64_t c0 = toUnit(prim.p[0][k], scale);
        u[k] = toUnit(prim.p[1][k], scale) - c0;
        v[k] = toUnit(prim.p[2][k], scale) - c0;
        if (u[k] >= kLimit || u[k] <= -kLimit || v[k] >= kLimit || v[k] <= -kLimit) return;
    }
    // |components| < 2^61.
    prim.ni[0] = u[1] * v[2] - u[2] * v[1];
    prim.ni[1] = u[2] * v[0] - u[0] * v[2];
    prim.ni[2] = u[0] * v[1] - u[1] * v[0];
    prim.unit = unit;
}

Contact primContact(const Prim& a, const Prim& b, bool sameMesh) {
    // Shared vertex ids, without branches (which neighbour shares what is unpredictable): bit
    // 3i + j when a's corner i is b's corner j. The corners of a kept triangle are distinct ids,
    // so each bit is a different corner on both sides.
    int shared = 0, sa[3] = {0, 0, 0}, sb[3] = {0, 0, 0};
    if (sameMesh) {
        uint32_t mask = 0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) mask |= uint32_t(a.v[i] == b.v[j]) << (3 * i + j);
        for (; mask != 0 && shared < 3; mask &= mask - 1, ++shared) {
            const int bit = std::countr_zero(mask);
            sa[shared] = bit / 3, sb[shared] = bit % 3;
        }
    }
    if (shared == 2) {
        // Not a fold-over unless b's opposite corner is on a's plane (faceContact's first test);
        // then the two opposite corners strictly on one side of the edge (its second).
        if (exactSide(a, b, 3 - sb[0] - sb[1]) != 0) return Contact::None;
        const Vec3d e0 = corner(a, sa[0]), e1 = corner(a, sa[1]);
        return coplanarOrientation(e0, e1, corner(a, 3 - sa[0] - sa[1]), corner(b, 3 - sb[0] - sb[1])) > 0
                   ? Contact::Touching
                   : Contact::None;
    } else if (shared == 1) {
        // b's opposite edge strictly on one side of a's plane: b meets a's plane only at the
        // shared vertex, which is on neither opposite edge: no contact elsewhere (and the same
        // with the roles swapped). Exact signs: nearly coplanar neighbours (subdivided flat
        // faces, rounded midpoints) are decided here too, not in faceContact.
        const int b1 = (sb[0] + 1) % 3, b2 = (sb[0] + 2) % 3, a1 = (sa[0] + 1) % 3, a2 = (sa[0] + 2) % 3;
        const int s1 = exactSide(a, b, b1), s2 = exactSide(a, b, b2);
        if (s1 == s2 && s1 != 0) return Contact::None;
        const int t1 = exactSide(b, a, a1), t2 = exactSide(b, a, a2);
        if (t1 == t2 && t1 != 0) return Contact::None;
        // Coplanar (b's other corners exactly on a's plane, hence all six points): they meet
        // besides the shared vertex v iff their closed wedges at v share more than v, i.e. a
        // boundary ray of one lies in the other. The same answer as the opposite-edge rule (if
        // the wedges overlap in a cone C, either the opposite edges cross in C or the nearer one
        // lies in the other triangle), decided with a few exact 2D orientations.
        if (s1 == 0 && s2 == 0) {
            const TrianglePoints pa{corner(a, 0), corner(a, 1), corner(a, 2)};
            const Vec3d& v = pa[sa[0]];
            const Vec3d &pa1 = pa[a1], &pa2 = pa[a2];
            const Vec3d pb1 = corner(b, b1), pb2 = corner(b, b2);
            int i = 0, j = 1;
            coplanarFrame(pa, &i, &j);  // a (so b too, being coplanar) projects non-degenerately
            const int oa = orient2d(v, pa1, pa2, i, j), ob = orient2d(v, pb1, pb2, i, j);
            auto inWedge = [&](const Vec3d& p1, const Vec3d& p2, int o, const Vec3d& p) {
                return o * orient2d(v, p1, p, i, j) >= 0 && o * orient2d(v, p, p2, i, j) >= 0;
            };
            const bool meet = inWedge(pa1, pa2, oa, pb1) || inWedge(pa1, pa2, oa, pb2) || inWedge(pb1, pb2, ob, pa1) ||
                              inWedge(pb1, pb2, ob, pa2);
            return meet ? Contact::Touching : Contact::None;
        }
        // Not coplanar: b meets a's plane in a segment [v, p], p on b's opposite edge, and a
        // meets b's plane in [v, q], q on a's; both lie on the planes' common line, so the
        // triangles meet beyond v (CGAL's rule: the nearer of p and q is on the other triangle)
        // iff p is on q's side of v, i.e. in a's closed wedge at v. With a's corners v, a1, a2
        // in cyclic order and n their normal, the side of p against the line from v to a2 is
        // sign(orient3d(v, a2, b1, b2)) * sign(s2 - s1) (the segment b1 b2 crosses the plane
        // going the way of s2 - s1); a1's side is negative. When q = a2 (t2 = 0) that line is
        // the common line itself: use the line to a1 instead, on whose positive side a2 lies.
        const Vec3d v = corner(a, sa[0]), pb1 = corner(b, b1), pb2 = corner(b, b2);
        const int crossingWay = s2 > s1 ? 1 : -1;  // s1 != s2 here
        const bool meet = t2 != 0 ? orient3d(v, corner(a, a2), pb1, pb2) * crossingWay < 0
                                  : orient3d(v, corner(a, a1), pb1, pb2) * crossingWay > 0;
        if (!meet) return Contact::None;
        // They meet along [v, min(p, q)]: a penetration when each straddles the other's plane.
        return s1 * s2 < 0 && t1 * t2 < 0 ? Contact::Crossing : Contact::Touching;
    } else if (shared == 0) {
        // All of b's corners strictly on one side of a's plane, or all of a's of b's: apart.
        // Exact signs, then Guigue-Devillers on them (triangleContact without recomputing).
        int db[3], da[3];
        for (int k = 0; k < 3; ++k) db[k] = exactSide(a, b, k);
        if (db[0] == db[1] && db[1] == db[2] && db[0] != 0) return Contact::None;
        for (int k = 0; k < 3; ++k) da[k] = exactSide(b, a, k);
        if (da[0] == da[1] && da[1] == da[2] && da[0] != 0) return Contact::None;
        const TrianglePoints pa{corner(a, 0), corner(a, 1), corner(a, 2)}, pb{corner(b, 0), corner(b, 1), corner(b, 2)};
        return triangleContactFromSigns(pa, pb, da, db);
    }
    const TrianglePoints pa{corner(a, 0), corner(a, 1), corner(a, 2)}, pb{corner(b, 0), corner(b, 1), corner(b, 2)};
    return faceContact(pa, a.v, pb, b.v, sameMesh);
}

}  // namespace detail
}  // namespace cullide::oracle
