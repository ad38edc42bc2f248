// The oracle's narrow phase on packed primitive records (see narrow_phase.h): the fast filtered
// path, which decides most pairs from a float filter on the planes and exact integer arithmetic;
// the exact predicates of cullide/predicates.h decide the rest.
//
// Compiled with -ffp-contract=off: the filter's error bound (Shewchuk's, as orient3d's) assumes
// every product and sum is rounded on its own, never fused.
#include "narrow_phase.h"

#include "cullide/parallel.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cullide::oracle {
namespace detail {
namespace {

Vec3d corner(const Prim& p, int k) {
    return Vec3d(p.p[k][0], p.p[k][1], p.p[k][2]);
}

// The edges from corner 0 in integers of 2^unit (unit from integerUnit), or false when one is
// 2^30 or more of them.
inline bool integerEdges(const Prim& prim, int32_t unit, int64_t u[3], int64_t v[3]) {
    const double scale = unitScale(unit);
    constexpr int64_t kLimit = int64_t(1) << 30;
    for (int k = 0; k < 3; ++k) {
        const int64_t c0 = toUnit(prim.p[0][k], scale);
        u[k] = toUnit(prim.p[1][k], scale) - c0;
        v[k] = toUnit(prim.p[2][k], scale) - c0;
        if (u[k] >= kLimit || u[k] <= -kLimit || v[k] >= kLimit || v[k] <= -kLimit) return false;
    }
    return true;
}

// Sign of orient3d(a's corners, (x, y, z)) when the float filter is sure of it, else 0. The same
// arithmetic as orient3d (w = s - p0; det = sum w_k n_k; permanent = sum |w_k| perm_k; the error
// bound (7 + 56 eps) eps * permanent), with the cofactor expansion along w instead of u, which
// Shewchuk's analysis covers alike (each term one difference times a 2x2 minor of differences).
inline int planeSide(const Prim& a, const Plane& pa, double x, double y, double z) {
    const double wx = x - double(a.p[0][0]), wy = y - double(a.p[0][1]), wz = z - double(a.p[0][2]);
    const double det = wx * pa.n[0] + wy * pa.n[1] + wz * pa.n[2];
    const double permanent = std::abs(wx) * pa.perm[0] + std::abs(wy) * pa.perm[1] + std::abs(wz) * pa.perm[2];
    const double bound = kOrient3dErrBound * permanent;
    // Without branches: the sign is unpredictable (a fifth of the oracle's time on mispredicted
    // jumps here).
    return int(det > bound) - int(-det > bound);
}

// Sign of orient3d(a's corners, b's corner k) when the filter cannot tell: when a's corners are
// integers of one unit 2^unit below 2^62 with edges below 2^30 units, a's integer normal
// (|N| < 2^61) when b's corner is an integer in that unit (|w| < 2^63: the dot product fits 126
// bits), then orient3d. The unit is found here, not stored per record: few pairs get here (none
// on most meshes), and finding it for every triangle was 5% of the oracle on a 6k mesh.
[[gnu::noinline]] int exactSideSlow(const Prim& a, const Prim& b, int k) {
    const int32_t unit = integerUnit(&a.p[0][0], 9);
    int64_t u[3], v[3];
    if (unit != kNoUnit && integerEdges(a, unit, u, v)) {
        const double scale = unitScale(unit);
        const int64_t ni[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
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
            det += __int128(ni[c]) * (q - toUnit(a.p[0][c], scale));  // |N| < 2^61, |w| < 2^63
        }
        if (exact) return det > 0 ? 1 : det < 0 ? -1 : 0;
    }
    return orient3d(corner(a, 0), corner(a, 1), corner(a, 2), corner(b, k));
}

// Sign of orient3d(a's corners, b's corner k), exactly (pa: a's plane): the filter, then
// exactSideSlow.
inline int exactSide(const Prim& a, const Plane& pa, const Prim& b, int k) {
    const int d = planeSide(a, pa, b.p[k][0], b.p[k][1], b.p[k][2]);
    return d != 0 ? d : exactSideSlow(a, b, k);
}

// exactSide of b's corners j and k: planeSide's filter on both at once in the two lanes of an
// SSE2 vector (x86-64's baseline), lane by lane the same operations in the same order, so the
// same signs; exactSideSlow for a lane the filter cannot tell. Most pairs are decided by two
// such signs (a neighbour's two other corners against a triangle's plane).
inline void exactSides2(const Prim& a, const Plane& pa, const Prim& b, int j, int k, int& sj, int& sk) {
#if defined(__SSE2__)
    const auto pair = [&](int c) { return _mm_set_pd(double(b.p[k][c]), double(b.p[j][c])); };
    const __m128d wx = _mm_sub_pd(pair(0), _mm_set1_pd(double(a.p[0][0])));
    const __m128d wy = _mm_sub_pd(pair(1), _mm_set1_pd(double(a.p[0][1])));
    const __m128d wz = _mm_sub_pd(pair(2), _mm_set1_pd(double(a.p[0][2])));
    const __m128d det =
        _mm_add_pd(_mm_add_pd(_mm_mul_pd(wx, _mm_set1_pd(pa.n[0])), _mm_mul_pd(wy, _mm_set1_pd(pa.n[1]))),
                   _mm_mul_pd(wz, _mm_set1_pd(pa.n[2])));
    const __m128d sign = _mm_set1_pd(-0.0);
    const __m128d permanent =
        _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_andnot_pd(sign, wx), _mm_set1_pd(pa.perm[0])),
                              _mm_mul_pd(_mm_andnot_pd(sign, wy), _mm_set1_pd(pa.perm[1]))),
                   _mm_mul_pd(_mm_andnot_pd(sign, wz), _mm_set1_pd(pa.perm[2])));
    const __m128d bound = _mm_mul_pd(_mm_set1_pd(kOrient3dErrBound), permanent);
    const int above = _mm_movemask_pd(_mm_cmpgt_pd(det, bound));
    const int below = _mm_movemask_pd(_mm_cmpgt_pd(_mm_xor_pd(det, sign), bound));
    sj = (above & 1) - (below & 1);
    sk = (above >> 1) - (below >> 1);
#else
    sj = planeSide(a, pa, b.p[j][0], b.p[j][1], b.p[j][2]);
    sk = planeSide(a, pa, b.p[k][0], b.p[k][1], b.p[k][2]);
#endif
    if (sj == 0) sj = exactSideSlow(a, b, j);
    if (sk == 0) sk = exactSideSlow(a, b, k);
}

}  // namespace

Plane planeOf(const Prim& prim) {
    return planeOf(Vec3f(prim.p[0][0], prim.p[0][1], prim.p[0][2]), Vec3f(prim.p[1][0], prim.p[1][1], prim.p[1][2]),
                   Vec3f(prim.p[2][0], prim.p[2][1], prim.p[2][2]));
}

Plane planeOf(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
    const double ux = double(p1.x()) - double(p0.x()), uy = double(p1.y()) - double(p0.y()),
                 uz = double(p1.z()) - double(p0.z());
    const double vx = double(p2.x()) - double(p0.x()), vy = double(p2.y()) - double(p0.y()),
                 vz = double(p2.z()) - double(p0.z());
    const double m1 = uy * vz, m2 = uz * vy, m3 = uz * vx, m4 = ux * vz, m5 = ux * vy, m6 = uy * vx;
    Plane pl;
    pl.n[0] = m1 - m2, pl.n[1] = m3 - m4, pl.n[2] = m5 - m6;
    pl.perm[0] = std::abs(m1) + std::abs(m2);
    pl.perm[1] = std::abs(m3) + std::abs(m4);
    pl.perm[2] = std::abs(m5) + std::abs(m6);
    return pl;
}

uint8_t projectedTurnsExact(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Plane& plane) {
    uint8_t turns = 0;
    for (int k = 0; k < 3; ++k) {
        int sign;
        if (orient2dFilterNonZero(plane.n[k], plane.perm[k])) sign = plane.n[k] > 0 ? 1 : -1;
        else sign = orient2d(p0.cast<double>(), p1.cast<double>(), p2.cast<double>(), (k + 1) % 3, (k + 2) % 3);
        turns |= uint8_t(sign > 0) << k | uint8_t(sign < 0) << (3 + k);
    }
    return turns;
}

// Bit i set when from[i] == id, for i below size (at most 32); from[] readable to a multiple of 4.
inline uint32_t matches(const uint32_t* from, uint32_t size, uint32_t id) {
    uint32_t bits = 0;
#if defined(__SSE2__)
    const __m128i key = _mm_set1_epi32(int(id));
    for (uint32_t i = 0; i < size; i += 4) {
        const __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(from + i)), key);
        bits |= uint32_t(_mm_movemask_ps(_mm_castsi128_ps(same))) << i;
    }
#else
    for (uint32_t i = 0; i < size; ++i) bits |= uint32_t(from[i] == id) << i;
#endif
    return size == 32 ? bits : bits & ((1u << size) - 1);
}

void certifyFans(std::span<Prim> prims, size_t vertexCount, PageArena* arena) {
    const size_t n = prims.size();
    // Per vertex, its fan's corners (record * 4 + corner: below 2^31, as records are below 2^29)
    // by a counting sort, and the turns every record of its fan has: 4 bytes per corner and 5 per
    // vertex, in one array so that a large mesh's goes back to the system when freed (the arena
    // keeps its chunks to the call's end: docs/oracle.md, "Fans").
    Buffer<uint32_t> scratch{ArenaAllocator<uint32_t>(arena)};
    scratch.resize(vertexCount + 1 + 3 * n + (vertexCount + 3) / 4);
    uint32_t* const end = scratch.data();  // vertex v's corners end at end[v] (from end[v - 1], or 0)
    uint32_t* const corners = end + vertexCount + 1;
    uint8_t* const turns = reinterpret_cast<uint8_t*>(corners + 3 * n);
    std::fill(end, end + vertexCount + 1, 0u);
    std::fill(turns, turns + vertexCount, uint8_t(0x3f));
    for (const Prim& prim : prims)
        for (int c = 0; c < 3; ++c) ++end[prim.v[c] + 1], turns[prim.v[c]] &= prim.turns;
    for (size_t v = 0; v < vertexCount; ++v) end[v + 1] += end[v];
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) corners[end[prims[i].v[c]]++] = uint32_t(4 * i + size_t(c));
    // Then per vertex whether its fan is certified: its records all turn one way along some axis
    // k, where its outer edges (from the corner after the vertex to the one before, in each
    // record's order) form closed paths that wind around its image exactly once. Fans of more
    // than kMaxFan records are not (the closed-paths check is quadratic).
    constexpr uint32_t kMaxFan = 32;
    parallelFor(0, vertexCount, 1024, [&](const tbb::blocked_range<size_t>& r) {
        uint32_t from[kMaxFan + 4], to[kMaxFan];  // ids; from[] readable to a multiple of 4
        const float* fromAt[kMaxFan];  // the outer edges' corners
        const float* toAt[kMaxFan];
        for (size_t v = r.begin(); v != r.end(); ++v) {
            const uint32_t first = v == 0 ? 0 : end[v - 1], size = end[v] - first;
            uint8_t& certified = turns[v];  // turns[v] is not read again once this is written
            const uint8_t same = turns[v];
            certified = 0;
            if (size < 3 || size > kMaxFan || same == 0) continue;
            for (uint32_t j = 0; j < size; ++j) {
                const uint32_t at = corners[first + j], c = at & 3;
                const Prim& prim = prims[at >> 2];
                const uint32_t next = c == 2 ? 0 : c + 1, prev = c == 0 ? 2 : c - 1;
                from[j] = prim.v[next], to[j] = prim.v[prev];
                fromAt[j] = prim.p[next], toAt[j] = prim.p[prev];
            }
            const float* const at = prims[corners[first] >> 2].p[corners[first] & 3];  // the vertex
            // Along axis k (X, Y: the axes k + 1 and k + 2) where every record turns one way: how
            // many of the fan's angles at the vertex's image hold the ray from it toward +X, each
            // angle [from, to) half open. Counterclockwise, each angle is below pi and holds the
            // ray iff from's Y <= the vertex's Y < to's Y; clockwise, mirrored. When the outer
            // edges form closed paths, that count is their winding number around the vertex's
            // image, at least one per path.
            bool once = false;
            for (int bit = 0; bit < 6 && !once; ++bit) {
                if (!(same >> bit & 1)) continue;
                const int y = bit % 3 == 0 ? 2 : bit % 3 - 1;
                const float vy = at[y];
                uint32_t winding = 0;
                if (bit < 3)
                    for (uint32_t j = 0; j < size; ++j) winding += (fromAt[j][y] <= vy) & (vy < toAt[j][y]);
                else
                    for (uint32_t j = 0; j < size; ++j) winding += (fromAt[j][y] >= vy) & (vy > toAt[j][y]);
                once = winding == 1;
            }
            if (!once) continue;
            // The outer edges form closed paths: each edge's end is exactly one edge's start (bit i
            // of match: to[j] = from[i]), and no two end at the same start (the bits of all j
            // together cover every edge). Then one path, winding once: the fan's images tile the
            // plane around the vertex's image once.
            for (uint32_t j = size; j < (size + 3) / 4 * 4; ++j) from[j] = ~0u;
            uint32_t all = 0;
            bool wrong = false;
            for (uint32_t j = 0; j < size; ++j) {
                const uint32_t match = matches(from, size, to[j]);
                wrong |= match == 0 || (match & (match - 1)) != 0;
                all |= match;
            }
            certified = !wrong && all == (size == 32 ? ~0u : (1u << size) - 1);
        }
    });
    const uint8_t* const certified = turns;
    parallelFor(0, n, 4096, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            Prim& prim = prims[i];
            prim.fans = uint8_t(certified[prim.v[0]] | certified[prim.v[1]] << 1 | certified[prim.v[2]] << 2);
        }
    });
}

namespace {

// Which corners two triangles share: the first two shared corners (sa on a, sb on b; unused
// beyond `count`) and how many there are.
struct Sharing {
    int count;
    int sa[2], sb[2];
};

// Shared vertex ids, without branches (which neighbour shares what is unpredictable): bit 3i + j
// when a's corner i is b's corner j. The corners of a kept triangle are distinct ids, so each bit
// is a different corner on both sides.
inline uint32_t sharedMask(const Prim& a, const Prim& b) {
    uint32_t mask = 0;
#if defined(__SSE2__)
    // b's ids and the record's triangle index after them in one vector (that lane masked off),
    // each of a's ids compared with all of them at once, instead of nine scalar comparisons: 4-5%
    // of the oracle's time on one and two cows, 2-3% on the subdivided meshes.
    static_assert(offsetof(Prim, triangle) == offsetof(Prim, v) + 3 * sizeof(uint32_t));
    const __m128i bv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b.v.data()));
    for (int i = 0; i < 3; ++i) {
        const __m128i same = _mm_cmpeq_epi32(bv, _mm_set1_epi32(int(a.v[i])));
        mask |= (uint32_t(_mm_movemask_ps(_mm_castsi128_ps(same))) & 7) << (3 * i);
    }
#else
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) mask |= uint32_t(a.v[i] == b.v[j]) << (3 * i + j);
#endif
    return mask;
}

// The number of shared corners (bits of the mask), without a loop.
inline int sharedCount(uint32_t mask) {
    const uint32_t rest = mask & (mask - 1);  // (std::popcount is a libgcc call on baseline x86-64)
    return int(mask != 0) + int(rest != 0) + int((rest & (rest - 1)) != 0);
}

// Whether a pair whose sharedMask is `mask` shares one or two corners, one of them a's corner whose
// fan is certified (certifyFans): then they meet only at it, or only along the shared edge.
inline bool fanDecides(const Prim& a, uint32_t mask, int count) {
    const uint32_t certified = (a.fans & 1u) * 7 | (a.fans & 2u) * 28 | (a.fans & 4u) * 112;  // bits 3c..3c+2
    return (mask & certified) != 0 && count < 3;
}

inline Sharing sharingOf(uint32_t mask) {
    // The first two shared corners, without a loop (its trip count mispredicted: a tenth of the
    // oracle's time); bit 9 stands in when there are fewer (its corners then unused).
    const uint32_t rest = mask & (mask - 1);
    const int bit0 = std::countr_zero(mask | 1u << 9), bit1 = std::countr_zero(rest | 1u << 9);
    return {sharedCount(mask), {bit0 / 3, bit1 / 3}, {bit0 % 3, bit1 % 3}};
}

// A pair sharing an edge (s.count == 2).
inline Contact edgeContact(const Prim& a, const Plane& planeA, const Prim& b, const Sharing& s) {
    // Not a fold-over unless b's opposite corner is on a's plane (faceContact's first test);
    // then the two opposite corners strictly on one side of the edge (its second).
    if (exactSide(a, planeA, b, 3 - s.sb[0] - s.sb[1]) != 0) return Contact::None;
    const Vec3d e0 = corner(a, s.sa[0]), e1 = corner(a, s.sa[1]);
    return coplanarOrientation(e0, e1, corner(a, 3 - s.sa[0] - s.sa[1]), corner(b, 3 - s.sb[0] - s.sb[1])) > 0
        ? Contact::Touching
        : Contact::None;
}

// vertexContact past its first rejection (s1, s2: the signs of b's corners after the shared one
// against a's plane, not both the same nonzero sign).
inline Contact vertexContactPast(const Prim& a, const Prim& b, const Plane* storedB, const Sharing& s, int s1, int s2) {
    const int b1 = (s.sb[0] + 1) % 3, b2 = (s.sb[0] + 2) % 3, a1 = (s.sa[0] + 1) % 3, a2 = (s.sa[0] + 2) % 3;
    int t1, t2;
    const Plane planeB = storedB ? *storedB : planeOf(b);
    exactSides2(b, planeB, a, a1, a2, t1, t2);
    if (t1 == t2 && t1 != 0) return Contact::None;
    // Coplanar (b's other corners exactly on a's plane, hence all six points): they meet
    // besides the shared vertex v iff their closed wedges at v share more than v, i.e. a
    // boundary ray of one lies in the other. The same answer as the opposite-edge rule (if
    // the wedges overlap in a cone C, either the opposite edges cross in C or the nearer one
    // lies in the other triangle), decided with a few exact 2D orientations.
    if (s1 == 0 && s2 == 0)
        return coplanarWedgesMeet(corner(a, s.sa[0]), corner(a, a1), corner(a, a2), corner(b, b1), corner(b, b2))
            ? Contact::Touching
            : Contact::None;
    // Not coplanar: b meets a's plane in a segment [v, p], p on b's opposite edge, and a
    // meets b's plane in [v, q], q on a's; both lie on the planes' common line, so the
    // triangles meet beyond v (CGAL's rule: the nearer of p and q is on the other triangle)
    // iff p is on q's side of v, i.e. in a's closed wedge at v. With a's corners v, a1, a2
    // in cyclic order and n their normal, the side of p against the line from v to a2 is
    // sign(orient3d(v, a2, b1, b2)) * sign(s2 - s1) (the segment b1 b2 crosses the plane
    // going the way of s2 - s1); a1's side is negative. When q = a2 (t2 = 0) that line is
    // the common line itself: use the line to a1 instead, on whose positive side a2 lies.
    const Vec3d v = corner(a, s.sa[0]), pb1 = corner(b, b1), pb2 = corner(b, b2);
    const int crossingWay = s2 > s1 ? 1 : -1;  // s1 != s2 here
    const bool meet = t2 != 0 ? orient3d(v, corner(a, a2), pb1, pb2) * crossingWay < 0
                              : orient3d(v, corner(a, a1), pb1, pb2) * crossingWay > 0;
    if (!meet) return Contact::None;
    // They meet along [v, min(p, q)]: a penetration when each straddles the other's plane.
    return s1 * s2 < 0 && t1 * t2 < 0 ? Contact::Crossing : Contact::Touching;
}

// A pair sharing one vertex (s.count == 1); b's plane from storedB, or computed here when needed.
inline Contact vertexContact(const Prim& a, const Plane& planeA, const Prim& b, const Plane* storedB,
                             const Sharing& s) {
    // b's opposite edge strictly on one side of a's plane: b meets a's plane only at the
    // shared vertex, which is on neither opposite edge: no contact elsewhere (and the same
    // with the roles swapped). Exact signs: nearly coplanar neighbours (subdivided flat
    // faces, rounded midpoints) are decided here too, not in faceContact.
    int s1, s2;
    exactSides2(a, planeA, b, (s.sb[0] + 1) % 3, (s.sb[0] + 2) % 3, s1, s2);
    if (s1 == s2 && s1 != 0) return Contact::None;
    return vertexContactPast(a, b, storedB, s, s1, s2);
}

// A pair sharing no vertex.
inline Contact apartContact(const Prim& a, const Plane& planeA, const Prim& b, const Plane* storedB) {
    // All of b's corners strictly on one side of a's plane, or all of a's of b's: apart.
    // Exact signs, then Guigue-Devillers on them (triangleContact without recomputing).
    int db[3], da[3];
    exactSides2(a, planeA, b, 0, 1, db[0], db[1]);
    db[2] = exactSide(a, planeA, b, 2);
    if (db[0] == db[1] && db[1] == db[2] && db[0] != 0) return Contact::None;
    const Plane planeB = storedB ? *storedB : planeOf(b);
    exactSides2(b, planeB, a, 0, 1, da[0], da[1]);
    da[2] = exactSide(b, planeB, a, 2);
    if (da[0] == da[1] && da[1] == da[2] && da[0] != 0) return Contact::None;
    const TrianglePoints pa{corner(a, 0), corner(a, 1), corner(a, 2)}, pb{corner(b, 0), corner(b, 1), corner(b, 2)};
    return triangleContactFromSigns(pa, pb, da, db);
}

// Three shared vertices (the same triangle twice): faceContact's rules.
Contact sameCornersContact(const Prim& a, const Prim& b, bool sameMesh) {
    const TrianglePoints pa{corner(a, 0), corner(a, 1), corner(a, 2)}, pb{corner(b, 0), corner(b, 1), corner(b, 2)};
    return faceContact(pa, a.v, pb, b.v, sameMesh);
}

}  // namespace

Contact primContact(const Prim& a, const Plane& planeA, const Prim& b, const Plane* storedB, bool sameMesh) {
    // b's plane is computed only past the first rejection.
    const uint32_t mask = sameMesh ? sharedMask(a, b) : 0;
    const Sharing s = sharingOf(mask);
    if (fanDecides(a, mask, s.count)) return Contact::None;
    if (s.count == 2) return edgeContact(a, planeA, b, s);
    if (s.count == 1) return vertexContact(a, planeA, b, storedB, s);
    if (s.count == 0) return apartContact(a, planeA, b, storedB);
    return sameCornersContact(a, b, sameMesh);
}

uint32_t primContacts(const StoredPrims* objects, const Candidate* pairs, uint32_t count, Hit* hits, size_t& tested) {
    // A chunk at a time, by sharing class: a pair's class is unpredictable (the grid hands over a
    // triangle's neighbours in a cell: on the cow, 69% share a vertex, 22% an edge, 9% none), and
    // so is the first rejection of a pair sharing a vertex (72% on the cow); one loop per class
    // and one for that rejection, each without a data-dependent branch, took 3-7% off the
    // oracle's time (A/B, meshes of 5.8k-46k triangles; the classes alone, within noise).
    constexpr uint32_t kChunk = 256, kAhead = 8;
    uint16_t index[6][kChunk];  // per class (4: not tested, 5: decided by a fan), the chunk's pairs
    uint16_t mask[kChunk];  // sharedMask per pair
    int8_t sign[kChunk][2];  // per vertex-class survivor, s1 and s2 of vertexContact
    uint32_t hitCount = 0;
    // Hits are rare: each is written, and kept when it is one.
    const auto record = [&](uint32_t k, Contact contact) {
        hits[hitCount] = {k, contact};
        hitCount += contact != Contact::None;
    };
    for (uint32_t first = 0; first < count; first += kChunk) {
        const uint32_t n = std::min(kChunk, count - first);
        const Candidate* const chunk = pairs + first;
        uint32_t size[6] = {0, 0, 0, 0, 0, 0};
        for (uint32_t k = 0; k < n; ++k) {
            // The second record of the pair kAhead on (and its plane) fetched ahead: random reads.
            if (k + kAhead < n) {
                const Candidate& f = chunk[k + kAhead];
                __builtin_prefetch(&objects[f.object1].prims[f.prim1]);
                __builtin_prefetch(&objects[f.object1].planes[f.prim1]);
            }
            const Candidate& c = chunk[k];
            const Prim& a = objects[c.object0].prims[c.prim0];
            const uint32_t m = c.object0 == c.object1 ? sharedMask(a, objects[c.object1].prims[c.prim1]) : 0;
            const int shared = sharedCount(m);
            const uint32_t cls = !inTestOrder(c) ? 4 : fanDecides(a, m, shared) ? 5 : uint32_t(shared);
            mask[k] = uint16_t(m);
            index[cls][size[cls]++] = uint16_t(k);
        }
        tested += n - size[4];
        // One shared vertex: the first rejection for all, then the rest for those it keeps.
        uint32_t kept = 0;
        for (uint32_t i = 0; i < size[1]; ++i) {
            const uint32_t k = index[1][i];
            const Candidate& c = chunk[k];
            const Sharing s = sharingOf(mask[k]);
            int s1, s2;
            exactSides2(objects[c.object0].prims[c.prim0], objects[c.object0].planes[c.prim0],
                        objects[c.object1].prims[c.prim1], (s.sb[0] + 1) % 3, (s.sb[0] + 2) % 3, s1, s2);
            index[1][kept] = uint16_t(k);
            sign[kept][0] = int8_t(s1), sign[kept][1] = int8_t(s2);
            kept += !(s1 == s2 && s1 != 0);
        }
        for (uint32_t i = 0; i < kept; ++i) {
            const uint32_t k = index[1][i];
            const Candidate& c = chunk[k];
            record(first + k,
                   vertexContactPast(objects[c.object0].prims[c.prim0], objects[c.object1].prims[c.prim1],
                                     &objects[c.object1].planes[c.prim1], sharingOf(mask[k]), sign[i][0], sign[i][1]));
        }
        for (uint32_t i = 0; i < size[2]; ++i) {
            const uint32_t k = index[2][i];
            const Candidate& c = chunk[k];
            record(first + k,
                   edgeContact(objects[c.object0].prims[c.prim0], objects[c.object0].planes[c.prim0],
                               objects[c.object1].prims[c.prim1], sharingOf(mask[k])));
        }
        for (uint32_t i = 0; i < size[0]; ++i) {
            const uint32_t k = index[0][i];
            const Candidate& c = chunk[k];
            record(first + k,
                   apartContact(objects[c.object0].prims[c.prim0], objects[c.object0].planes[c.prim0],
                                objects[c.object1].prims[c.prim1], &objects[c.object1].planes[c.prim1]));
        }
        for (uint32_t i = 0; i < size[3]; ++i) {
            const uint32_t k = index[3][i];
            const Candidate& c = chunk[k];
            record(first + k,
                   sameCornersContact(objects[c.object0].prims[c.prim0], objects[c.object1].prims[c.prim1], true));
        }
    }
    return hitCount;
}

}  // namespace detail
}  // namespace cullide::oracle
