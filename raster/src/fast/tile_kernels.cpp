// The per-tile work of the fast path of the CPU backend (tile_kernels.h).
#include "fast/tile_kernels.h"

#include "setup/depth_simd.h"

#include <algorithm>
#include <bit>
#include <utility>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cullide::raster::detail {

namespace {

constexpr size_t kPrefetch = 8;  // records fetched ahead in a tile's list

// The hot loop: one record clipped to a pixel rectangle (inclusive bounds).
// Record: also append the fragments to `rec` as groups (the caller guarantees room for one group
// per pixel of the clipped rectangle).
template <DepthFunc F, bool Float, bool Record>
void rasterizeInTile(const EdgeTri& t, int bx0, int by0, int bx1, int by1, uint32_t* depth, size_t stride, bool mask,
                     int bits, uint64_t& fragments, uint64_t& passed, FragGroup*& rec) {
    const int x0 = std::max<int>(t.x0, bx0), x1 = std::min<int>(t.x1, bx1);
    const int y0 = std::max<int>(t.y0, by0), y1 = std::min<int>(t.y1, by1);
    if (x0 > x1 || y0 > y1) return;
    const int64_t a0 = t.a[0], a1 = t.a[1], a2 = t.a[2], b0 = t.b[0], b1 = t.b[1], b2 = t.b[2];
    uint64_t frag = 0, pass = 0;
    for (int j = y0; j <= y1; ++j) {
        int64_t e0 = a0 * x0 + b0 * j + t.c[0];
        int64_t e1 = a1 * x0 + b1 * j + t.c[1];
        int64_t e2 = a2 * x0 + b2 * j + t.c[2];
        const double row = t.plane.row(j);
        uint32_t* d = depth + size_t(j) * stride;
        [[maybe_unused]] FragGroup* group = nullptr;  // the row's open group
        for (int i = x0; i <= x1; ++i, e0 += a0, e1 += a1, e2 += a2) {
            if ((e0 | e1 | e2) < 0) continue;
            ++frag;
            const double z = clampDepth(t.plane.at(row, i));
            const uint32_t incoming = Float ? std::bit_cast<uint32_t>(float(z)) : encodeUnorm(z, bits);
            if constexpr (Record) {
                const uint32_t pixel = uint32_t(size_t(j) * stride + size_t(i));
                if (group == nullptr || pixel - group->pixel >= 4) {
                    group = rec++;
                    group->pixel = pixel;
                    group->lanes = 0;
                }
                group->lanes |= 1u << (pixel - group->pixel);
                group->z[pixel - group->pixel] = incoming;
            }
            const uint32_t stored = d[i];
            const bool ok = depthTest(F, incoming, stored);  // branch-free below: outcomes are noisy
            pass += ok;
            d[i] = ok && mask ? incoming : stored;
        }
    }
    fragments += frag;
    passed += pass;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CULLIDE_RASTER_AVX2 1
// The same loop four pixels at a time with AVX2 (selected at run time where the CPU has it):
// the same integer edge functions, the same double operations in the same order (no FMA: the
// target does not enable it), so the same fragments, depths and results bit for bit. The lanes
// past the record's right end or outside it are masked off; masked loads and stores touch no
// other pixel (the neighbouring tile belongs to another thread).
alignas(16) constexpr int32_t kLaneMasks[16][4] = {{0, 0, 0, 0},   {-1, 0, 0, 0},   {0, -1, 0, 0},   {-1, -1, 0, 0},
                                                   {0, 0, -1, 0},  {-1, 0, -1, 0},  {0, -1, -1, 0},  {-1, -1, -1, 0},
                                                   {0, 0, 0, -1},  {-1, 0, 0, -1},  {0, -1, 0, -1},  {-1, -1, 0, -1},
                                                   {0, 0, -1, -1}, {-1, 0, -1, -1}, {0, -1, -1, -1}, {-1, -1, -1, -1}};

// The depth test of four lanes at once (unsigned comparisons through the signed ones, sign bits
// flipped), for the lanes in `lanes`.
template <DepthFunc F>
__attribute__((target("avx2"))) inline __m128i depthTest4(__m128i incoming, __m128i stored, __m128i lanes) {
    const __m128i signBit = _mm_set1_epi32(INT32_MIN);
    const __m128i si = _mm_xor_si128(incoming, signBit), ss = _mm_xor_si128(stored, signBit);
    const __m128i all = _mm_set1_epi32(-1);
    __m128i ok;
    if constexpr (F == DepthFunc::Never) ok = _mm_setzero_si128();
    else if constexpr (F == DepthFunc::Less) ok = _mm_cmpgt_epi32(ss, si);
    else if constexpr (F == DepthFunc::Equal) ok = _mm_cmpeq_epi32(incoming, stored);
    else if constexpr (F == DepthFunc::LEqual) ok = _mm_xor_si128(_mm_cmpgt_epi32(si, ss), all);
    else if constexpr (F == DepthFunc::Greater) ok = _mm_cmpgt_epi32(si, ss);
    else if constexpr (F == DepthFunc::NotEqual) ok = _mm_xor_si128(_mm_cmpeq_epi32(incoming, stored), all);
    else if constexpr (F == DepthFunc::GEqual) ok = _mm_xor_si128(_mm_cmpgt_epi32(ss, si), all);
    else ok = all;
    return _mm_and_si128(ok, lanes);
}

// A record whose rectangle, clipped to the tile, is one or two pixels wide (most, on meshes finer
// than the image): two rows at a time in one vector, lanes (x0, j), (x0 + 1, j), (x0, j + 1),
// (x0 + 1, j + 1), instead of the scalar loop's chain of double operations per pixel. The same
// edge functions (integers), the same depth operations per pixel in the same order
// (DepthPlane::row, then at), so the same fragments, depths and counts; recorded as one group per
// row (replays apply the same fragments in the same order).
template <DepthFunc F, bool Float, bool Record>
__attribute__((target("avx2"))) void rasterizeNarrowAvx2(const EdgeTri& t, int x0, int y0, int x1, int y1, int bx1,
                                                         uint32_t* depth, size_t stride, bool mask, int bits,
                                                         uint64_t& fragments, uint64_t& passed, FragGroup*& rec) {
    const bool wide = x1 > x0;
    // The edge functions at the block's four pixels, and their step to the next pair of rows.
    __m256i e[3], down[3];
    for (int k = 0; k < 3; ++k) {
        const int64_t a = t.a[k], b = t.b[k], base = a * x0 + b * y0 + t.c[k];
        e[k] = _mm256_add_epi64(_mm256_set1_epi64x(base), _mm256_setr_epi64x(0, a, b, a + b));
        down[k] = _mm256_set1_epi64x(2 * b);
    }
    // Pixel centres double(i) + 0.5 and double(j) + 0.5: exact.
    const DepthPlane& p = t.plane;
    const __m256d cx = _mm256_setr_pd(x0 + 0.5, x0 + 1.5, x0 + 0.5, x0 + 1.5);
    const __m256d dx = _mm256_sub_pd(cx, _mm256_set1_pd(p.x0));
    const __m256d z0 = _mm256_set1_pd(p.z0), dzdx = _mm256_set1_pd(p.dzdx), dzdy = _mm256_set1_pd(p.dzdy);
    const __m256d py0 = _mm256_set1_pd(p.y0);
    const auto laneMask = [](int bits4) { return _mm_load_si128(reinterpret_cast<const __m128i*>(kLaneMasks[bits4])); };
    // A row's two pixels of the block, read and written whole (the test's verdict blended in) when
    // both lie in the tile (this thread's: bx1 is its last column), else only the first. Masked
    // stores are microcoded on AMD's Zen 1 (family 23). A group is flagged whole (its replay reads
    // and writes four pixels) when all four lie in the tile.
    const bool pair = x0 + 1 <= bx1;
    const uint32_t wholeFlag = x0 + 3 <= bx1 ? kWholeGroup : 0;
    const auto loadRow = [pair](const uint32_t* d) {
        return pair ? _mm_loadl_epi64(reinterpret_cast<const __m128i*>(d)) : _mm_cvtsi32_si128(int(*d));
    };
    const auto storeRow = [pair](uint32_t* d, __m128i v) {
        if (pair) _mm_storel_epi64(reinterpret_cast<__m128i*>(d), v);
        else *d = uint32_t(_mm_cvtsi128_si32(v));
    };
    uint64_t frag = 0, pass = 0;
    [[maybe_unused]] FragGroup* out = rec;  // a local cursor, as rasterizeInTileAvx2's
    for (int j = y0; j <= y1; j += 2, e[0] = _mm256_add_epi64(e[0], down[0]), e[1] = _mm256_add_epi64(e[1], down[1]),
             e[2] = _mm256_add_epi64(e[2], down[2])) {
        const bool tall = j < y1;
        const int valid = (wide ? 3 : 1) | (tall ? (wide ? 12 : 4) : 0);
        const int outside = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_or_si256(e[0], _mm256_or_si256(e[1], e[2]))));
        const int inside = ~outside & valid;
        if (inside == 0) continue;
        const __m256d cy = _mm256_setr_pd(j + 0.5, j + 0.5, j + 1.5, j + 1.5);
        const __m256d row = _mm256_add_pd(z0, _mm256_mul_pd(dzdy, _mm256_sub_pd(cy, py0)));
        const __m128i incoming = clampEncode4<Float>(_mm256_add_pd(row, _mm256_mul_pd(dzdx, dx)), bits);
        uint32_t* const d0 = depth + size_t(j) * stride + size_t(x0);
        uint32_t* const d1 = tall ? d0 + stride : d0;  // the second row's, read and written only when there is one
        const int top = inside & 3, bottom = inside >> 2;
        if constexpr (Record) {
            if (top) {
                FragGroup* g = out++;
                g->pixel = uint32_t(size_t(j) * stride + size_t(x0));
                g->lanes = uint32_t(top) | wholeFlag;
                _mm_storeu_si128(reinterpret_cast<__m128i*>(g->z), incoming);
            }
            if (bottom) {
                FragGroup* g = out++;
                g->pixel = uint32_t(size_t(j + 1) * stride + size_t(x0));
                g->lanes = uint32_t(bottom) | wholeFlag;
                _mm_storeu_si128(reinterpret_cast<__m128i*>(g->z), _mm_srli_si128(incoming, 8));
            }
        }
        const __m128i stored = _mm_unpacklo_epi64(loadRow(d0), loadRow(d1));
        const __m128i ok = depthTest4<F>(incoming, stored, laneMask(inside));
        const int okBits = _mm_movemask_ps(_mm_castsi128_ps(ok));
        frag += uint64_t(std::popcount(unsigned(inside)));
        pass += uint64_t(std::popcount(unsigned(okBits)));
        if (mask) {  // written back whatever the verdict (no branch on it: rasterizeInTileAvx2)
            // d1 first: when it is d0 (one row), its lanes failed (not valid) and d0's write wins.
            const __m128i written = _mm_blendv_epi8(stored, incoming, ok);
            storeRow(d1, _mm_srli_si128(written, 8));
            storeRow(d0, written);
        }
    }
    if constexpr (Record) rec = out;
    fragments += frag;
    passed += pass;
}

template <DepthFunc F, bool Float, bool Record>
__attribute__((target("avx2"))) void rasterizeInTileAvx2(const EdgeTri& t, int bx0, int by0, int bx1, int by1,
                                                         uint32_t* depth, size_t stride, bool mask, int bits,
                                                         uint64_t& fragments, uint64_t& passed, FragGroup*& rec) {
    const int x0 = std::max<int>(t.x0, bx0), x1 = std::min<int>(t.x1, bx1);
    const int y0 = std::max<int>(t.y0, by0), y1 = std::min<int>(t.y1, by1);
    if (x0 > x1 || y0 > y1) return;
    // Records one or two pixels wide: two rows at a time in one vector.
    if (x1 - x0 < 2)
        return rasterizeNarrowAvx2<F, Float, Record>(t, x0, y0, x1, y1, bx1, depth, stride, mask, bits, fragments,
                                                     passed, rec);
    const int64_t a0 = t.a[0], a1 = t.a[1], a2 = t.a[2], b0 = t.b[0], b1 = t.b[1], b2 = t.b[2];
    const __m256i off0 = _mm256_set_epi64x(3 * a0, 2 * a0, a0, 0), step0 = _mm256_set1_epi64x(4 * a0);
    const __m256i off1 = _mm256_set_epi64x(3 * a1, 2 * a1, a1, 0), step1 = _mm256_set1_epi64x(4 * a1);
    const __m256i off2 = _mm256_set_epi64x(3 * a2, 2 * a2, a2, 0), step2 = _mm256_set1_epi64x(4 * a2);
    const __m256d offsets = _mm256_set_pd(3.5, 2.5, 1.5, 0.5);
    const __m256d planeX0 = _mm256_set1_pd(t.plane.x0), dzdx = _mm256_set1_pd(t.plane.dzdx);
    uint64_t frag = 0, pass = 0;
    // The recording cursor as a local (written back at the end): through the reference, each
    // group loaded and stored it, the vector stores in between (which may alias anything) keeping
    // it in memory.
    [[maybe_unused]] FragGroup* out = rec;
    // Two passes over batches of rows. The first tests every group's edges and keeps the groups
    // with fragments, as (row, column, lanes) in 32 bits (pixel indices are below 2^14), without a
    // branch on whether a group has any: on small triangles that branch went either way (half of
    // the groups of their boxes are empty) and each miss flushed the depth work after it. The
    // second runs the kept groups in the same order: the same fragments, tests, writes and records
    // as one pass.
    constexpr int kBatch = 512;  // groups kept before the second pass; a row has at most 256 (1024 px tiles)
    uint32_t kept[kBatch];
    double rowZ[kBatch];  // DepthPlane::row of the batch's rows, from its first
    int batchY = y0;
    const int rowGroups = (x1 - x0) / 4 + 1;
    const auto runKept = [&](int n) __attribute__((target("avx2"), always_inline)) {
        for (int k = 0; k < n; ++k) {
            const uint32_t g = kept[k];
            const int j = int(g >> 18), i = int(g >> 4 & 0x3FFF), inside = int(g & 15);
            // Pixel centres i + l + 0.5 from double(i) + (l + 0.5): exact (small multiples of 1/2),
            // so the same values as DepthPlane::at's.
            const __m256d centres = _mm256_add_pd(_mm256_set1_pd(double(i)), offsets);
            const __m256d z =
                _mm256_add_pd(_mm256_set1_pd(rowZ[j - batchY]), _mm256_mul_pd(dzdx, _mm256_sub_pd(centres, planeX0)));
            const __m128i incoming = clampEncode4<Float>(z, bits);
            // Four pixels in the tile (this thread's: bx1 is its last column) read and written
            // whole, the verdict blended in (masked stores are microcoded on Zen 1); a group at
            // the tile's right edge masked.
            const bool whole = i + 3 <= bx1;
            if constexpr (Record) {
                FragGroup* r = out++;
                r->pixel = uint32_t(size_t(j) * stride + size_t(i));
                r->lanes = uint32_t(inside) | (whole ? kWholeGroup : 0);
                _mm_storeu_si128(reinterpret_cast<__m128i*>(r->z), incoming);
            }
            const __m128i lanes = _mm_load_si128(reinterpret_cast<const __m128i*>(kLaneMasks[inside]));
            int* const p = reinterpret_cast<int*>(depth + size_t(j) * stride + size_t(i));
            const __m128i stored =
                whole ? _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)) : _mm_maskload_epi32(p, lanes);
            const __m128i ok = depthTest4<F>(incoming, stored, lanes);
            const int okBits = _mm_movemask_ps(_mm_castsi128_ps(ok));
            frag += uint64_t(std::popcount(unsigned(inside)));
            pass += uint64_t(std::popcount(unsigned(okBits)));
            // A whole group is written back whatever the verdict (no branch on it either).
            if (mask) {
                if (whole) _mm_storeu_si128(reinterpret_cast<__m128i*>(p), _mm_blendv_epi8(stored, incoming, ok));
                else if (okBits != 0) _mm_maskstore_epi32(p, ok, incoming);
            }
        }
    };
    int n = 0;
    for (int j = y0; j <= y1; ++j) {
        if (n + rowGroups > kBatch || j - batchY == kBatch) {
            runKept(n);
            n = 0;
            batchY = j;
        }
        rowZ[j - batchY] = t.plane.row(j);
        __m256i e0 = _mm256_add_epi64(_mm256_set1_epi64x(a0 * x0 + b0 * j + t.c[0]), off0);
        __m256i e1 = _mm256_add_epi64(_mm256_set1_epi64x(a1 * x0 + b1 * j + t.c[1]), off1);
        __m256i e2 = _mm256_add_epi64(_mm256_set1_epi64x(a2 * x0 + b2 * j + t.c[2]), off2);
        for (int i = x0; i <= x1; i += 4, e0 = _mm256_add_epi64(e0, step0), e1 = _mm256_add_epi64(e1, step1),
                 e2 = _mm256_add_epi64(e2, step2)) {
            const int outside = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_or_si256(e0, _mm256_or_si256(e1, e2))));
            const int valid = x1 - i >= 3 ? 15 : (1 << (x1 - i + 1)) - 1;
            const int inside = ~outside & valid;
            kept[n] = uint32_t(j) << 18 | uint32_t(i) << 4 | uint32_t(inside);
            n += inside != 0;
        }
    }
    runKept(n);
    if constexpr (Record) rec = out;
    fragments += frag;
    passed += pass;
}

// The direct path's run of records (RunRecordsFn): a small record's tests and writes as
// rasterizeNarrowAvx2's, with no branch on its fragments or outcomes. Its two rows are read and
// written whole, two pixels each, the depth test's verdict blended in: the pixels it does not cover
// are written back unchanged. Only the direct path calls this, on one thread at a time over the
// whole buffer, so that no other thread can write them in between; a row's second pixel may be
// the first of the next row, and the buffer's last pixel takes the masked form (it has no
// neighbour). AMD's Zen 1 (family 23) runs a masked store as a microcoded sequence: the two per
// record were most of this loop (BM_Triangles leg 1, 500 px, one thread, three runs of an
// in-process switch: 23.6-26.8 -> 17.9-19.6 ms).
template <DepthFunc F>
__attribute__((target("avx2"))) void runRecordsAvx2(const EdgeTri* recs, const SmallFrags* small, uint32_t n,
                                                    RasterFn raster, int width, int height, uint32_t* depth,
                                                    size_t stride, bool mask, int bits, uint64_t& fragments,
                                                    uint64_t& passed) {
    const auto laneMask = [](uint32_t bits4) {
        return _mm_load_si128(reinterpret_cast<const __m128i*>(kLaneMasks[bits4]));
    };
    FragGroup* noRecording = nullptr;
    // The last pixel with a right-hand neighbour in the buffer.
    const uint32_t* const lastPair = depth + (size_t(height) - 1) * stride + size_t(width) - 2;
    uint64_t frag = 0, pass = 0;
    for (uint32_t k = 0; k < n; ++k) {
        const SmallFrags& f = small[k];
        const uint32_t lanes = f.lanes;
        if (lanes == kNotSmall) {
            raster(recs[k], 0, 0, width - 1, height - 1, depth, stride, mask, bits, frag, pass, noRecording);
            continue;
        }
        uint32_t* const d0 = depth + f.pixel;
        uint32_t* const d1 = d0 + (lanes > 3 ? stride : 0);  // the second row's, only when there is one
        const __m128i incoming = _mm_loadu_si128(reinterpret_cast<const __m128i*>(f.z));
        const bool plain = d1 <= lastPair;  // both rows' pixel pairs lie in the buffer
        const __m128i stored = plain
            ? _mm_unpacklo_epi64(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(d0)),
                                 _mm_loadl_epi64(reinterpret_cast<const __m128i*>(d1)))
            : _mm_unpacklo_epi64(_mm_maskload_epi32(reinterpret_cast<const int*>(d0), laneMask(lanes & 3)),
                                 _mm_maskload_epi32(reinterpret_cast<const int*>(d1), laneMask(lanes >> 2)));
        const __m128i ok = depthTest4<F>(incoming, stored, laneMask(lanes));
        frag += uint64_t(std::popcount(lanes));
        pass += uint64_t(std::popcount(unsigned(_mm_movemask_ps(_mm_castsi128_ps(ok)))));
        if (!mask) continue;
        if (plain) [[likely]] {
            // d1 first: when it is d0 (one row), its lanes failed (not covered) and d0's write wins.
            const __m128i written = _mm_blendv_epi8(stored, incoming, ok);
            _mm_storel_epi64(reinterpret_cast<__m128i*>(d1), _mm_srli_si128(written, 8));
            _mm_storel_epi64(reinterpret_cast<__m128i*>(d0), written);
        } else {
            _mm_maskstore_epi32(reinterpret_cast<int*>(d0), _mm_and_si128(ok, laneMask(3)), incoming);
            _mm_maskstore_epi32(reinterpret_cast<int*>(d1), _mm_srli_si128(ok, 8), _mm_srli_si128(incoming, 8));
        }
    }
    fragments += frag;
    passed += pass;
}
#endif

// The direct path's run of records without small ones (the scalar loops): each record through
// the pixel loop.
void runRecordsScalar(const EdgeTri* recs, const SmallFrags*, uint32_t n, RasterFn raster, int width, int height,
                      uint32_t* depth, size_t stride, bool mask, int bits, uint64_t& fragments, uint64_t& passed) {
    FragGroup* noRecording = nullptr;
    for (uint32_t k = 0; k < n; ++k)
        raster(recs[k], 0, 0, width - 1, height - 1, depth, stride, mask, bits, fragments, passed, noRecording);
}

// A draw replayed from its recorded fragments: the same tests, counts and writes, in the same order.
template <DepthFunc F>
void replayFragments(const FragGroup* g, const FragGroup* end, uint32_t* depth, bool mask, uint64_t& fragments,
                     uint64_t& passed) {
    uint64_t frag = 0, pass = 0;
    for (; g != end; ++g)
        for (uint32_t l = 0; l < 4; ++l) {
            if (!(g->lanes >> l & 1)) continue;
            ++frag;
            const uint32_t incoming = g->z[l], stored = depth[g->pixel + l];
            const bool ok = depthTest(F, incoming, stored);
            pass += ok;
            depth[g->pixel + l] = ok && mask ? incoming : stored;
        }
    fragments += frag;
    passed += pass;
}

#ifdef CULLIDE_RASTER_AVX2
template <DepthFunc F>
__attribute__((target("avx2"))) void replayFragmentsAvx2(const FragGroup* g, const FragGroup* end, uint32_t* depth,
                                                         bool mask, uint64_t& fragments, uint64_t& passed) {
    uint64_t frag = 0, pass = 0;
    for (; g != end; ++g) {
        const uint32_t bits = g->lanes & kGroupLanes;
        const __m128i lanes = _mm_load_si128(reinterpret_cast<const __m128i*>(kLaneMasks[bits]));
        const __m128i incoming = _mm_loadu_si128(reinterpret_cast<const __m128i*>(g->z));
        int* d = reinterpret_cast<int*>(depth + g->pixel);
        // A whole group's four pixels are read and written whole (rasterizeInTileAvx2).
        const bool whole = (g->lanes & kWholeGroup) != 0;
        const __m128i stored =
            whole ? _mm_loadu_si128(reinterpret_cast<const __m128i*>(d)) : _mm_maskload_epi32(d, lanes);
        const __m128i ok = depthTest4<F>(incoming, stored, lanes);
        const int okBits = _mm_movemask_ps(_mm_castsi128_ps(ok));
        frag += uint64_t(std::popcount(bits));
        pass += uint64_t(std::popcount(unsigned(okBits)));
        // A whole group is written back whatever the verdict (rasterizeInTileAvx2).
        if (mask) {
            if (whole) _mm_storeu_si128(reinterpret_cast<__m128i*>(d), _mm_blendv_epi8(stored, incoming, ok));
            else if (okBits != 0) _mm_maskstore_epi32(d, ok, incoming);
        }
    }
    fragments += frag;
    passed += pass;
}
#endif

// One conservative record clipped to a pixel rectangle: test and/or merge intervals.
void rasterizeConservative(const ConsRec& r, int bx0, int by0, int bx1, int by1, uint32_t* ilo, uint32_t* ihi,
                           size_t stride, bool test, bool write, const DepthFormat& format, uint64_t& fragments,
                           uint64_t& passed) {
    const ConsTri& t = r.t;
    const int x0 = std::max<int>(t.x0, bx0), x1 = std::min<int>(t.x1, bx1);
    const int y0 = std::max<int>(t.y0, by0), y1 = std::min<int>(t.y1, by1);
    if (x0 > x1 || y0 > y1) return;
    const int64_t a0 = r.e.a[0], a1 = r.e.a[1], a2 = r.e.a[2];
    uint64_t frag = 0, pass = 0;
    for (int j = y0; j <= y1; ++j) {
        int64_t e0 = a0 * x0 + r.e.b[0] * j + r.e.c[0];
        int64_t e1 = a1 * x0 + r.e.b[1] * j + r.e.c[1];
        int64_t e2 = a2 * x0 + r.e.b[2] * j + r.e.c[2];
        const size_t row = size_t(j) * stride;
        for (int i = x0; i <= x1; ++i, e0 += a0, e1 += a1, e2 += a2) {
            if ((e0 | e1 | e2) < 0) continue;
            ++frag;
            uint32_t lo, hi;
            consInterval(t, i, j, format, lo, hi);
            uint32_t& slo = ilo[row + size_t(i)];
            uint32_t& shi = ihi[row + size_t(i)];
            if (test) pass += intervalConflicts(lo, hi, slo, shi) ? 1 : 0;
            if (write) {
                slo = std::min(slo, lo);
                shi = std::max(shi, hi);
            }
        }
    }
    fragments += frag;
    passed += pass;
}

template <template <DepthFunc, bool, bool> class K, bool Float, size_t... F>
constexpr RasterTable makeTable(std::index_sequence<F...>) {
    return {std::array<RasterFn, 8>{K<DepthFunc(F), Float, false>::run...},
            std::array<RasterFn, 8>{K<DepthFunc(F), Float, true>::run...},
            std::array<ReplayFn, 8>{K<DepthFunc(F), Float, false>::replay...},
            std::array<RunRecordsFn, 8>{K<DepthFunc(F), Float, false>::runRecords...}};
}

template <DepthFunc F, bool Float, bool Record>
struct ScalarKernel {
    static constexpr RasterFn run = &rasterizeInTile<F, Float, Record>;
    static constexpr ReplayFn replay = &replayFragments<F>;
    static constexpr RunRecordsFn runRecords = &runRecordsScalar;
};

#ifdef CULLIDE_RASTER_AVX2
template <DepthFunc F, bool Float, bool Record>
struct Avx2Kernel {
    static constexpr RasterFn run = &rasterizeInTileAvx2<F, Float, Record>;
    static constexpr ReplayFn replay = &replayFragmentsAvx2<F>;
    static constexpr RunRecordsFn runRecords = &runRecordsAvx2<F>;
};
#endif

}  // namespace

// The hot loops for this CPU: AVX2 when asked for and present, else the scalar loops.
RasterTable pickRasterTable(bool isFloat, bool simd) {
    constexpr auto funcs = std::make_index_sequence<8>();
#ifdef CULLIDE_RASTER_AVX2
    if (simd && __builtin_cpu_supports("avx2"))
        return isFloat ? makeTable<Avx2Kernel, true>(funcs) : makeTable<Avx2Kernel, false>(funcs);
#endif
    (void)simd;
    return isFloat ? makeTable<ScalarKernel, true>(funcs) : makeTable<ScalarKernel, false>(funcs);
}

// A draw's samples that passed, added to its query's count (the tile's list stays in query order).
void countQuery(TileOut& out, int32_t query, uint64_t n) {
    if (query < 0 || n == 0) return;
    if (!out.queries.empty() && out.queries.back().query == uint32_t(query)) out.queries.back().count += n;
    else out.queries.push_back({uint32_t(query), n});
}

void runTile(const TileJob& job, size_t tile, FragCache& cache, TileOut& out, TileCapture* capture) {
    out.queries.clear();
    out.fragments = out.passed = 0;
    const int ts = job.grid.tileSize, W = job.width, H = job.height, bits = job.format.bits;
    const int bx0 = int(tile % size_t(job.grid.tilesX)) * ts, by0 = int(tile / size_t(job.grid.tilesX)) * ts;
    const int bx1 = std::min(bx0 + ts, W) - 1, by1 = std::min(by0 + ts, H) - 1;
    const RasterTable& table = job.table;
    uint32_t* const depth = job.depth;
    const EdgeTri* const records = job.plain.records.data();
    const uint32_t* recs = job.plain.bins.begin(tile);
    const size_t nrecs = job.plain.bins.size(tile);
    const std::vector<Event>& events = job.events.events;
    const TileBins& eventBins = job.events.bins;
    size_t hint = 0, consHint = 0;
    cache.reset(eventBins.size(tile));
    for (uint32_t k = eventBins.start[tile]; k < eventBins.start[tile + 1]; ++k) {
        const Event& e = events[eventBins.items[k]];
        if (e.clear) {
            for (int j = by0; j <= by1; ++j)
                std::fill_n(depth + size_t(j) * size_t(W) + size_t(bx0), bx1 - bx0 + 1, e.clearValue);
            continue;
        }
        if (e.intervalClear) {
            for (int j = by0; j <= by1; ++j) {
                std::fill_n(job.ilo + size_t(j) * size_t(W) + size_t(bx0), bx1 - bx0 + 1, kEmptyIntervalLo);
                std::fill_n(job.ihi + size_t(j) * size_t(W) + size_t(bx0), bx1 - bx0 + 1, kEmptyIntervalHi);
            }
            continue;
        }
        const uint64_t before = out.passed;
        if (e.conservative) {
            const uint32_t* crecs = job.conservative.bins.begin(tile);
            const size_t ncrecs = job.conservative.bins.size(tile);
            size_t p = gallopLowerBound(crecs, ncrecs, consHint, e.recBegin);
            for (; p < ncrecs && crecs[p] < e.recEnd; ++p)
                rasterizeConservative(job.conservative.records[crecs[p]], bx0, by0, bx1, by1, job.ilo, job.ihi,
                                      size_t(W), e.test, e.write, job.format, out.fragments, out.passed);
            consHint = p;
            countQuery(out, e.query, out.passed - before);
            continue;
        }
        FragCache::Entry& seen = cache.find(e.recBegin, e.recEnd);
        if (seen.recBegin == e.recBegin && seen.recEnd == e.recEnd) {
            table.replay[size_t(e.func)](cache.groups.data() + seen.start, cache.groups.data() + seen.stop, depth,
                                         e.mask, out.fragments, out.passed);
        } else {
            // Rasterize, and record while the groups fit when a later draw will replay them.
            FragGroup* const groups = cache.groups.data();
            FragGroup* w = groups + cache.used;
            bool record = e.drawnAgain;
            size_t p = gallopLowerBound(recs, nrecs, hint, e.recBegin);
            for (; p < nrecs && recs[p] < e.recEnd; ++p) {
                // A tile's records are scattered through the records: fetch ahead (no effect on
                // results).
                if (p + kPrefetch < nrecs) {
                    const char* ahead = reinterpret_cast<const char*>(&records[recs[p + kPrefetch]]);
                    __builtin_prefetch(ahead);
                    __builtin_prefetch(ahead + 64);
                }
                const EdgeTri& tri = records[recs[p]];
                if (record) {  // room for one group per pixel of the clipped rectangle
                    const int64_t cw = std::min<int>(tri.x1, bx1) - std::max<int>(tri.x0, bx0) + 1;
                    const int64_t ch = std::min<int>(tri.y1, by1) - std::max<int>(tri.y0, by0) + 1;
                    record = cw <= 0 || ch <= 0 || int64_t(groups + kFragCap - w) >= cw * ch;
                }
                FragGroup* const from = w;
                (record ? table.record : table.raster)[size_t(e.func)](tri, bx0, by0, bx1, by1, depth, size_t(W),
                                                                       e.mask, bits, out.fragments, out.passed, w);
                if (capture) {  // records met before are kept as first recorded; a gap spoils it
                    const size_t next = capture->groupBegin.size();
                    if (p == next && record) {
                        capture->groupBegin.push_back(uint32_t(from - groups));
                        capture->groupEnd.push_back(uint32_t(w - groups));
                    } else if (p >= next) {
                        capture->ok = false;
                    }
                }
            }
            hint = p;
            if (record) {
                seen = {e.recBegin, e.recEnd, uint32_t(cache.used), uint32_t(w - groups)};
                cache.used = size_t(w - groups);
            }
        }
        countQuery(out, e.query, out.passed - before);
    }
}

}  // namespace cullide::raster::detail
