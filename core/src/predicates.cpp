// Exact predicates and the rules for faces that share vertices (see cullide/predicates.h).
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
// This file and oracle/src/cgal_reference.cpp are the only ones that include CGAL. It is compiled
// with -frounding-math (CGAL's interval filters need it) and -ffp-contract=off (the error bounds
// assume every product and sum is rounded on its own, never fused).
#include "cullide/predicates.h"

#include "cullide/error.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace cullide {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

Point toPoint(const Vec3d& p) {
    return Point(p.x(), p.y(), p.z());
}

// Exact integer coordinates for n double values (n <= 12): all of them in integers of one power of
// two (integerUnit); false when one is not a float or they span over 62 bits.
bool toIntegers(const double* x, int n, int64_t* out) {
    float f[12];
    for (int i = 0; i < n; ++i) {
        f[i] = float(x[i]);
        if (double(f[i]) != x[i]) return false;
    }
    const int32_t unit = integerUnit(f, size_t(n));
    if (unit == kNoUnit) return false;
    const double scale = unitScale(unit);
    for (int i = 0; i < n; ++i) out[i] = toUnit(f[i], scale);  // |out| < 2^62
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

int sign(CGAL::Orientation o) {
    return o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0;
}

// A 2D orientation in the projection onto axes (i, j) certainly non-zero (float filter)?
bool orient2dCertainlyNonZero(const Vec3d& p, const Vec3d& q, const Vec3d& r, int i, int j) {
    const double l = (q[i] - p[i]) * (r[j] - p[j]);
    const double rr = (q[j] - p[j]) * (r[i] - p[i]);
    const double det = l - rr;
    return orient2dFilterNonZero(det, std::abs(l) + std::abs(rr));
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

}  // namespace

// The float filter, then integers (differences below 2^62), then CGAL.
int orient2d(const Vec3d& p, const Vec3d& q, const Vec3d& r, int i, int j) {
    const double l = (q[i] - p[i]) * (r[j] - p[j]);
    const double rr = (q[j] - p[j]) * (r[i] - p[i]);
    const double det = l - rr;
    const double bound = kOrient2dErrBound * (std::abs(l) + std::abs(rr));
    if (det > bound) return 1;
    if (-det > bound) return -1;
    const double x[6] = {p[i], p[j], q[i], q[j], r[i], r[j]};
    int64_t c[6];
    if (toIntegers(x, 6, c)) {
        const int64_t a = c[2] - c[0], b = c[3] - c[1], e = c[4] - c[0], f = c[5] - c[1];  // |.| < 2^63
        constexpr int64_t kLimit = int64_t(1) << 62;
        if (a < kLimit && a > -kLimit && b < kLimit && b > -kLimit && e < kLimit && e > -kLimit && f < kLimit &&
            f > -kLimit) {
            const __int128 d = __int128(a) * f - __int128(b) * e;  // |.| < 2^125
            return d > 0 ? 1 : d < 0 ? -1 : 0;
        }
    }
    using P2 = Kernel::Point_2;
    const CGAL::Orientation o = CGAL::orientation(P2(p[i], p[j]), P2(q[i], q[j]), P2(r[i], r[j]));
    return o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0;
}

// CGAL's coplanar_orientation: the first axis-plane projection (in its order) in which p q r do
// not degenerate.
int coplanarOrientation(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s) {
    static constexpr int kAxes[3][2] = {{0, 1}, {1, 2}, {0, 2}};
    for (const auto& ax : kAxes) {
        const int o = orient2d(p, q, r, ax[0], ax[1]);
        if (o != 0) return o * orient2d(p, q, s, ax[0], ax[1]);
    }
    return 0;  // p q r collinear: not called so
}

bool coplanarWedgesMeet(const Vec3d& v, const Vec3d& a1, const Vec3d& a2, const Vec3d& b1, const Vec3d& b2) {
    // A boundary ray of one wedge lies in the other (closed) wedge, decided in a projection in
    // which (v, a1, a2) (so (v, b1, b2) too, being coplanar) does not degenerate.
    int i = 0, j = 1;
    coplanarFrame(TrianglePoints{v, a1, a2}, &i, &j);
    const int oa = orient2d(v, a1, a2, i, j), ob = orient2d(v, b1, b2, i, j);
    auto inWedge = [&](const Vec3d& p1, const Vec3d& p2, int o, const Vec3d& p) {
        return o * orient2d(v, p1, p, i, j) >= 0 && o * orient2d(v, p, p2, i, j) >= 0;
    };
    return inWedge(a1, a2, oa, b1) || inWedge(a1, a2, oa, b2) || inWedge(b1, b2, ob, a1) || inWedge(b1, b2, ob, a2);
}

// Guigue-Devillers on the given signs: CGAL's do_intersect, with crossing told from touching.
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

int orient3d(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s) {
    const double ux = q.x() - p.x(), uy = q.y() - p.y(), uz = q.z() - p.z();
    const double vx = r.x() - p.x(), vy = r.y() - p.y(), vz = r.z() - p.z();
    const double wx = s.x() - p.x(), wy = s.y() - p.y(), wz = s.z() - p.z();
    const double m1 = vy * wz, m2 = vz * wy, m3 = vz * wx, m4 = vx * wz, m5 = vx * wy, m6 = vy * wx;
    const double det = ux * (m1 - m2) + uy * (m3 - m4) + uz * (m5 - m6);
    const double permanent = (std::abs(m1) + std::abs(m2)) * std::abs(ux) +
        (std::abs(m3) + std::abs(m4)) * std::abs(uy) + (std::abs(m5) + std::abs(m6)) * std::abs(uz);
    const double bound = kOrient3dErrBound * permanent;
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
    const int da[3] = {orient3d(b[0], b[1], b[2], a[0]), orient3d(b[0], b[1], b[2], a[1]),
                       orient3d(b[0], b[1], b[2], a[2])};
    if (da[0] == da[1] && da[1] == da[2] && da[0] != 0) return Contact::None;
    const int db[3] = {orient3d(a[0], a[1], a[2], b[0]), orient3d(a[0], a[1], a[2], b[1]),
                       orient3d(a[0], a[1], a[2], b[2])};
    return triangleContactFromSigns(a, b, da, db);
}

bool triangleSegmentIntersect(const TrianglePoints& t, const Vec3d& s0, const Vec3d& s1) {
    const int d0 = orient3d(t[0], t[1], t[2], s0);
    const int d1 = orient3d(t[0], t[1], t[2], s1);
    if (d0 == d1 && d0 != 0) return false;  // both strictly on one side
    if (d0 == 0 && d1 == 0)  // in the triangle's plane: CGAL's coplanar test
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

}  // namespace cullide
