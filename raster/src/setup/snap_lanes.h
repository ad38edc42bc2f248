// Eight triangles' snapped vertices in the lanes of AVX2 registers, and what setup decides from
// them alone: shared by the count pass's eight-wide form (records.cpp, countHints8) and the
// direct path's groups of eight (triangle_setup.cpp, setupSmallGroup8), so that both give
// countHints's verdicts. Private to raster/.
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include "setup/triangle_setup.h"

#include "cullide/mesh.h"

#include <immintrin.h>

#include <cstddef>

namespace cullide::raster::detail {

// Lane l is triangle l; masks are -1 where true.
struct SnapLanes8 {
    __m256i x[3], y[3];  // vertex k's snapped coordinates
    __m256i inside;  // every vertex inside the clip volume (no clipping)
    __m256i rejected;  // the three vertices beyond one common side of the viewport
    __m256i flat, cw;  // zero snapped area; negative area (clockwise)
    __m256i minx, maxx, miny, maxy;  // the snapped bounding box
    __m256i lox, hix, loy, hiy;  // makeEdgeTri's pixel box, clipped to the viewport
    __m256i one;  // inside, non-zero area and a centre in the box: setupTriangle's one record
};

// A SnapVertex is three 32-bit words (x, y, then inside and beyond in the low bytes of the third),
// loaded vertex by vertex into the lanes: AVX2's gathers were slower here (an AMD EPYC; an A/B of
// BM_Prune, bunny 270k, one thread: 536, 532 -> 508, 504 ms without them, and gathering the
// setup's window vertices too made it 559 -> 756 ms). Integers only, as countHints's scalar form.
static_assert(sizeof(SnapVertex) == 12 && offsetof(SnapVertex, y) == 4 && offsetof(SnapVertex, inside) == 8 &&
              offsetof(SnapVertex, beyond) == 9);
__attribute__((target("avx2"))) inline SnapLanes8 snapLanes8(const Triangle* tris, const SnapVertex* snapped,
                                                             const SetupParams& params) {
    const __m256i ones = _mm256_set1_epi32(-1);
    SnapLanes8 s;
    __m256i f = ones;
    for (int k = 0; k < 3; ++k) {
        __m128i x4[2], y4[2], f4[2];
        for (int h = 0; h < 2; ++h) {
            // Lane l's (x, y) and (y, flags word) as two 8-byte loads, transposed by unpacking.
            __m128i xy[4], yf[4];
            for (int l = 0; l < 4; ++l) {
                const SnapVertex& v = snapped[tris[4 * h + l][k]];
                xy[l] = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&v.x));
                yf[l] = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&v.y));
            }
            const __m128i xy01 = _mm_unpacklo_epi32(xy[0], xy[1]), xy23 = _mm_unpacklo_epi32(xy[2], xy[3]);
            const __m128i yf01 = _mm_unpacklo_epi32(yf[0], yf[1]), yf23 = _mm_unpacklo_epi32(yf[2], yf[3]);
            x4[h] = _mm_unpacklo_epi64(xy01, xy23);
            y4[h] = _mm_unpackhi_epi64(xy01, xy23);
            f4[h] = _mm_unpackhi_epi64(yf01, yf23);
        }
        s.x[k] = _mm256_set_m128i(x4[1], x4[0]);
        s.y[k] = _mm256_set_m128i(y4[1], y4[0]);
        f = _mm256_and_si256(f, _mm256_set_m128i(f4[1], f4[0]));
    }
    const __m256i zero = _mm256_setzero_si256(), byte = _mm256_set1_epi32(0xFF);
    s.inside = _mm256_cmpeq_epi32(_mm256_and_si256(f, byte), _mm256_set1_epi32(1));
    s.rejected = _mm256_xor_si256(_mm256_cmpeq_epi32(_mm256_and_si256(_mm256_srli_epi32(f, 8), byte), zero), ones);
    // The orientation determinant in 64 bits: even lanes, then odd ones shifted down.
    const __m256i dx1 = _mm256_sub_epi32(s.x[1], s.x[0]), dy2 = _mm256_sub_epi32(s.y[2], s.y[0]);
    const __m256i dx2 = _mm256_sub_epi32(s.x[2], s.x[0]), dy1 = _mm256_sub_epi32(s.y[1], s.y[0]);
    const __m256i even = _mm256_sub_epi64(_mm256_mul_epi32(dx1, dy2), _mm256_mul_epi32(dx2, dy1));
    const __m256i odd = _mm256_sub_epi64(_mm256_mul_epi32(_mm256_srli_epi64(dx1, 32), _mm256_srli_epi64(dy2, 32)),
                                         _mm256_mul_epi32(_mm256_srli_epi64(dx2, 32), _mm256_srli_epi64(dy1, 32)));
    s.flat = _mm256_blend_epi32(_mm256_cmpeq_epi64(even, zero), _mm256_cmpeq_epi64(odd, zero), 0xAA);
    s.cw = _mm256_blend_epi32(_mm256_cmpgt_epi64(zero, even), _mm256_cmpgt_epi64(zero, odd), 0xAA);
    // boxHoldsCentre in 32 bits (|coordinate| <= 2^29 inside the clip volume): ceilShift(m - half)
    // is -((half - m) >> S).
    const __m128i sh = _mm_cvtsi32_si128(params.subpixelBits);
    const __m256i half = _mm256_set1_epi32(1 << (params.subpixelBits - 1));
    s.minx = _mm256_min_epi32(_mm256_min_epi32(s.x[0], s.x[1]), s.x[2]);
    s.maxx = _mm256_max_epi32(_mm256_max_epi32(s.x[0], s.x[1]), s.x[2]);
    s.miny = _mm256_min_epi32(_mm256_min_epi32(s.y[0], s.y[1]), s.y[2]);
    s.maxy = _mm256_max_epi32(_mm256_max_epi32(s.y[0], s.y[1]), s.y[2]);
    s.lox = _mm256_max_epi32(_mm256_sub_epi32(zero, _mm256_sra_epi32(_mm256_sub_epi32(half, s.minx), sh)), zero);
    s.hix = _mm256_min_epi32(_mm256_sra_epi32(_mm256_sub_epi32(s.maxx, half), sh), _mm256_set1_epi32(params.width - 1));
    s.loy = _mm256_max_epi32(_mm256_sub_epi32(zero, _mm256_sra_epi32(_mm256_sub_epi32(half, s.miny), sh)), zero);
    s.hiy =
        _mm256_min_epi32(_mm256_sra_epi32(_mm256_sub_epi32(s.maxy, half), sh), _mm256_set1_epi32(params.height - 1));
    const __m256i empty = _mm256_or_si256(_mm256_cmpgt_epi32(s.lox, s.hix), _mm256_cmpgt_epi32(s.loy, s.hiy));
    s.one = _mm256_andnot_si256(_mm256_or_si256(s.flat, empty), s.inside);
    return s;
}

}  // namespace cullide::raster::detail

#endif
