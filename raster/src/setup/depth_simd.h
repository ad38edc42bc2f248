// The depth clamp and encoding of cullide/raster/rules.h on four lanes with AVX2, shared by the
// pixel loops (tile_kernels.cpp) and the direct path's four-wide setup (triangle_setup.cpp).
// Private to raster/.
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>

#include <cstdint>

namespace cullide::raster::detail {

// clampDepth and the encoding of rules.h on four lanes (`bits`: unorm bits; unused for Float).
// The clamp as max then min: max_pd(z, +0) gives +0 for NaN and -0 (its second operand when the
// first is not greater), min_pd(., 1) caps. Unorm as encodeUnorm: f + 1 when r - z >= 1/2 and
// f - 1 when r - z < -1/2, with one comparison: t = r - 1/2 when r >= 1/2 (up iff t >= z), else
// r + 1/2 (down iff t < z), so the code is f + [r >= 1/2] + [t >= z] - 1. Both forms of t are
// exact where they decide (encodeUnorm's comment; when a < 1, r + 1/2 > r >= z rounds to >= z,
// no change either way). 14 operations instead of 21: the encoding was a third of the pixel loop.
template <bool Float>
__attribute__((target("avx2"))) inline __m128i clampEncode4(__m256d z, int bits) {
    const __m256d one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    z = _mm256_min_pd(_mm256_max_pd(z, _mm256_setzero_pd()), one);
    if constexpr (Float) {
        return _mm_castps_si128(_mm256_cvtpd_ps(z));  // round to nearest, as float(z)
    } else {
        const __m256d a = _mm256_mul_pd(z, _mm256_set1_pd(double(uint64_t(1) << bits)));
        const __m256d f = _mm256_round_pd(a, _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC);
        const __m256d r = _mm256_sub_pd(a, f);
        const __m256d upper = _mm256_cmp_pd(r, half, _CMP_GE_OQ);
        const __m256d t = _mm256_add_pd(r, _mm256_blendv_pd(half, _mm256_set1_pd(-0.5), upper));
        const __m256d ge = _mm256_cmp_pd(t, z, _CMP_GE_OQ);
        // f + 2^52 holds f in its low 32 bits (an integer below 2^33); the masks are -1 where set.
        __m256i code = _mm256_castpd_si256(_mm256_add_pd(f, _mm256_set1_pd(0x1p52)));
        code = _mm256_sub_epi64(code, _mm256_castpd_si256(ge));
        code = _mm256_sub_epi64(code, _mm256_andnot_si256(_mm256_castpd_si256(upper), _mm256_set1_epi64x(1)));
        return _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(code, _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0)));
    }
}

}  // namespace cullide::raster::detail

#endif
