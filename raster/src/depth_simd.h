// The depth clamp and encoding of cullide/raster/rules.h on four lanes with AVX2, shared by the
// pixel loops (tile_kernels.cpp) and the direct path's four-wide setup (triangle_setup.cpp).
// Private to raster/.
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>

#include <cstdint>

namespace cullide::raster::detail {

// clampDepth and the encoding of rules.h on four lanes (`bits`: unorm bits; unused for Float).
template <bool Float>
__attribute__((target("avx2"))) inline __m128i clampEncode4(__m256d z, int bits) {
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    z = _mm256_and_pd(z, _mm256_cmp_pd(z, zero, _CMP_GT_OQ));  // !(z > 0): +0 (NaN too)
    z = _mm256_blendv_pd(z, one, _mm256_cmp_pd(z, one, _CMP_GT_OQ));
    if constexpr (Float) {
        return _mm_castps_si128(_mm256_cvtpd_ps(z));  // round to nearest, as float(z)
    } else {
        const __m256d a = _mm256_mul_pd(z, _mm256_set1_pd(double(uint64_t(1) << bits)));
        const __m256d f = _mm256_round_pd(a, _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC);
        const __m256d r = _mm256_sub_pd(a, f);
        const __m256d up =
            _mm256_and_pd(_mm256_cmp_pd(r, half, _CMP_GE_OQ), _mm256_cmp_pd(_mm256_sub_pd(r, half), z, _CMP_GE_OQ));
        const __m256d down =
            _mm256_and_pd(_mm256_cmp_pd(r, half, _CMP_LT_OQ), _mm256_cmp_pd(_mm256_add_pd(r, half), z, _CMP_LT_OQ));
        const __m256d code = _mm256_sub_pd(_mm256_add_pd(f, _mm256_and_pd(up, one)), _mm256_and_pd(down, one));
        // An integer below 2^32 plus 2^52 holds it in its low 32 bits.
        return _mm256_castsi256_si128(
            _mm256_permutevar8x32_epi32(_mm256_castpd_si256(_mm256_add_pd(code, _mm256_set1_pd(0x1p52))),
                                        _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0)));
    }
}

}  // namespace cullide::raster::detail

#endif
