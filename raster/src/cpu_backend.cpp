// The CPU reference backend: a GL depth buffer and occlusion queries, tiled and multithreaded
// with oneTBB, deterministic (bit-identical results for any thread count).
//
// References: Govindaraju, Redon, Lin, Manocha, CULLIDE (Graphics Hardware 2003) and the seed
// paper /work/shared/papers/000_7db8250a290ddd48.txt (Sections 3-5): what a backend must do.
// Mesa llvmpipe (lp_rast, lp_setup): 64x64 tiles, binning, per-tile in-order execution,
// per-thread occlusion counters summed at the end. Rules: cullide/raster/rules.h.
//
// One command list, fast path:
//   1. validate (draw ranges inside the geometry, no query left open);
//   2. window coordinates of all vertices (cached per geometry + view);
//   3. set up every triangle drawn by the list once (union of the draw ranges, in triangle order,
//      parallel over chunks): clip, snap, edge functions, depth plane, pixel bbox, tile rect.
//      Records are compacted in triangle order, so a draw [first, first+count) is the record
//      range [recBegin[first], recEnd[first+count-1]);
//   4. bin the records to tiles (CSR, each tile's list sorted by record index);
//   5. turn clears and draws into events carrying the GL state (function, mask, open query) and
//      bin each to the tiles its records touch (a clear touches all tiles);
//   6. one task per tile walks its events in order; for a draw it finds the draw's records in
//      the tile's list by galloping from the previous position (cheap for reducePCS's runs of
//      neighbouring and repeated ranges) and rasterizes them clipped to the tile, recording the
//      fragments; a later draw of the same records in the tile replays them (FragCache). Query
//      counts go to a per-tile sparse list of (query, count), in query order;
//   7. sum the per-tile lists into the results (integers: order-free).
// Every pixel is owned by exactly one tile and processed in command order, so the depth buffer
// and the counts do not depend on scheduling.
#include "cullide/raster/cpu_backend.h"

#include "cullide/parallel.h"

#include "conservative.h"
#include "cullide/error.h"
#include "reference_path.h"
#include "triangle_setup.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <bit>
#include <string>
#include <utility>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cullide::raster {

const char* toString(FillRule rule) { return rule == FillRule::BottomLeft ? "bottom-left" : "top-left"; }

namespace {

using detail::EdgeTri;
using detail::SetupParams;
using detail::SnappedTri;
using detail::WinVertex;

constexpr uint32_t kSetupChunk = 1024;  // triangles per setup task
constexpr uint32_t kBinChunk = 4096;    // records (or events) per binning task
constexpr uint32_t kMaxBinChunks = 64;
constexpr size_t kPrefetch = 8;  // records fetched ahead in a tile's list
constexpr uint32_t kExactTilesUpTo = 4096;  // draws up to this many records: binned to their exact tiles

// A vertex snapped once (rule 3); `inside` when it needs no clipping (then |x|, |y| <= 2^29).
struct SnapVertex {
    int32_t x, y;
    bool inside;
};

// Tile rectangle [tx0, tx1] x [ty0, ty1], inclusive; tx0 > tx1 when empty.
struct TileRect {
    uint16_t tx0, ty0, tx1, ty1;
};

struct Event {
    bool clear = false;
    bool intervalClear = false;                 // ClearIntervals
    bool conservative = false, test = false, write = false;  // DrawConservative
    DepthFunc func = DepthFunc::Less;
    bool mask = true;
    int32_t query = -1;
    uint32_t clearValue = 0;
    uint32_t recBegin = 0, recEnd = 0;  // draw: record range
    uint32_t first = 0, count = 0;      // draw: triangle range
    TileRect tiles{1, 1, 0, 0};
};

struct QueryCount {
    uint32_t query;
    uint64_t count;
};

// Per-tile results, padded against false sharing.
struct alignas(64) TileOut {
    std::vector<QueryCount> queries;
    uint64_t fragments = 0, passed = 0;
};

// Fragments recorded by a draw, for later draws of the same records in the same tile (reducePCS
// draws each object four times: to write and to test, in both passes). A draw's fragments and
// their incoming depths depend only on its records and the tile, not on the GL state, so a later
// draw replays them in the same order instead of rasterizing again: same counts, same buffer.
// A group is up to four consecutive pixels of one row.
struct FragGroup {
    uint32_t pixel;  // depth-buffer index of lane 0 (viewports have at most 16384^2 = 2^28 pixels)
    uint32_t lanes;  // bit l set: pixel + l is a fragment
    uint32_t z[4];   // incoming depth codes, per lane
};
constexpr size_t kFragCap = size_t(1) << 16;  // groups per thread and tile; draws beyond are not recorded

// Per thread: the groups recorded in the current tile and an open-addressing table from a draw's
// record range to its groups.
struct FragCache {
    struct Entry {
        uint32_t recBegin = UINT32_MAX, recEnd = 0;  // empty: begin > end, which no draw has
        uint32_t start = 0, stop = 0;       // groups[start, stop)
    };
    std::vector<FragGroup> groups;
    std::vector<Entry> table;
    size_t used = 0;

    void reset(size_t draws) {  // a new tile with up to `draws` draws
        if (groups.size() < kFragCap) groups.resize(kFragCap);
        const size_t cap = std::bit_ceil(std::max<size_t>(16, 2 * draws));
        table.assign(cap, Entry{});
        used = 0;
    }
    static size_t hash(uint32_t b, uint32_t e) { return size_t((uint64_t(b) << 32 | e) * 0x9E3779B97F4A7C15ull >> 40); }
    // The entry of [b, e), or the empty slot where it would go.
    Entry& find(uint32_t b, uint32_t e) {
        const size_t mask = table.size() - 1;
        for (size_t i = hash(b, e) & mask;; i = (i + 1) & mask) {
            Entry& x = table[i];
            if ((x.recBegin == b && x.recEnd == e) || x.recBegin > x.recEnd) return x;
        }
    }
};

// Every parallel loop of the backend is one phase whose tasks touch disjoint data; phases
// follow each other. cullide::parallelFor (cullide/parallel.h) annotates the joins for
// ThreadSanitizer.
using cullide::parallelFor;

// The hot loop: one record clipped to a pixel rectangle (inclusive bounds).
// Record: also append the fragments to `rec` as groups (the caller guarantees room for one group
// per pixel of the clipped rectangle).
template <DepthFunc F, bool Float, bool Record>
void rasterizeInTile(const EdgeTri& t, int bx0, int by0, int bx1, int by1, uint32_t* depth, size_t stride, bool mask,
                     int bits, uint64_t& fragments, uint64_t& passed, FragGroup*& rec) {
    const int x0 = std::max<int>(t.x0, bx0), x1 = std::min<int>(t.x1, bx1);
    const int y0 = std::max<int>(t.y0, by0), y1 = std::min<int>(t.y1, by1);
    if (x0 > x1 || y0 > y1) return;
    const int64_t a0 = t.a[0], a1 = t.a[1], a2 = t.a[2];
    uint64_t frag = 0, pass = 0;
    for (int j = y0; j <= y1; ++j) {
        int64_t e0 = a0 * x0 + t.b[0] * j + t.c[0];
        int64_t e1 = a1 * x0 + t.b[1] * j + t.c[1];
        int64_t e2 = a2 * x0 + t.b[2] * j + t.c[2];
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
alignas(16) constexpr int32_t kLaneMasks[16][4] = {
    {0, 0, 0, 0},   {-1, 0, 0, 0},   {0, -1, 0, 0},   {-1, -1, 0, 0},   {0, 0, -1, 0},   {-1, 0, -1, 0},
    {0, -1, -1, 0}, {-1, -1, -1, 0}, {0, 0, 0, -1},   {-1, 0, 0, -1},   {0, -1, 0, -1},  {-1, -1, 0, -1},
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

template <DepthFunc F, bool Float, bool Record>
__attribute__((target("avx2"))) void rasterizeInTileAvx2(const EdgeTri& t, int bx0, int by0, int bx1, int by1,
                                                        uint32_t* depth, size_t stride, bool mask, int bits,
                                                        uint64_t& fragments, uint64_t& passed, FragGroup*& rec) {
    const int x0 = std::max<int>(t.x0, bx0), x1 = std::min<int>(t.x1, bx1);
    const int y0 = std::max<int>(t.y0, by0), y1 = std::min<int>(t.y1, by1);
    if (x0 > x1 || y0 > y1) return;
    // Records one or two pixels wide (most, on meshes finer than the image) cost less in the
    // scalar loop than the vector constants do.
    if (x1 - x0 < 2)
        return rasterizeInTile<F, Float, Record>(t, bx0, by0, bx1, by1, depth, stride, mask, bits, fragments, passed,
                                                 rec);
    const int64_t a0 = t.a[0], a1 = t.a[1], a2 = t.a[2];
    const __m256i off0 = _mm256_set_epi64x(3 * a0, 2 * a0, a0, 0), step0 = _mm256_set1_epi64x(4 * a0);
    const __m256i off1 = _mm256_set_epi64x(3 * a1, 2 * a1, a1, 0), step1 = _mm256_set1_epi64x(4 * a1);
    const __m256i off2 = _mm256_set_epi64x(3 * a2, 2 * a2, a2, 0), step2 = _mm256_set1_epi64x(4 * a2);
    // Pixel centre i + l + 0.5 as double(i) + (l + 0.5): both exact, so the same value.
    const __m256d centres = _mm256_set_pd(3.5, 2.5, 1.5, 0.5);
    const __m256d planeX0 = _mm256_set1_pd(t.plane.x0), dzdx = _mm256_set1_pd(t.plane.dzdx);
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    const __m256d scale = _mm256_set1_pd(double(uint64_t(1) << bits)), magic = _mm256_set1_pd(0x1p52);
    const __m256i low32 = _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0);
    uint64_t frag = 0, pass = 0;
    for (int j = y0; j <= y1; ++j) {
        __m256i e0 = _mm256_add_epi64(_mm256_set1_epi64x(a0 * x0 + t.b[0] * j + t.c[0]), off0);
        __m256i e1 = _mm256_add_epi64(_mm256_set1_epi64x(a1 * x0 + t.b[1] * j + t.c[1]), off1);
        __m256i e2 = _mm256_add_epi64(_mm256_set1_epi64x(a2 * x0 + t.b[2] * j + t.c[2]), off2);
        const __m256d row = _mm256_set1_pd(t.plane.row(j));
        uint32_t* d = depth + size_t(j) * stride;
        for (int i = x0; i <= x1; i += 4, e0 = _mm256_add_epi64(e0, step0), e1 = _mm256_add_epi64(e1, step1),
                 e2 = _mm256_add_epi64(e2, step2)) {
            const int outside = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_or_si256(e0, _mm256_or_si256(e1, e2))));
            const int valid = x1 - i >= 3 ? 15 : (1 << (x1 - i + 1)) - 1;
            const int inside = ~outside & valid;
            if (inside == 0) continue;
            // clampDepth and the encoding of rules.h, lane by lane.
            __m256d z = _mm256_add_pd(row, _mm256_mul_pd(dzdx, _mm256_sub_pd(_mm256_add_pd(_mm256_set1_pd(double(i)), centres), planeX0)));
            z = _mm256_and_pd(z, _mm256_cmp_pd(z, zero, _CMP_GT_OQ));  // !(z > 0): +0 (NaN too)
            z = _mm256_blendv_pd(z, one, _mm256_cmp_pd(z, one, _CMP_GT_OQ));
            __m128i incoming;
            if constexpr (Float) {
                incoming = _mm_castps_si128(_mm256_cvtpd_ps(z));  // round to nearest, as float(z)
            } else {
                const __m256d a = _mm256_mul_pd(z, scale);
                const __m256d f = _mm256_round_pd(a, _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC);
                const __m256d r = _mm256_sub_pd(a, f);
                const __m256d up = _mm256_and_pd(_mm256_cmp_pd(r, half, _CMP_GE_OQ),
                                                 _mm256_cmp_pd(_mm256_sub_pd(r, half), z, _CMP_GE_OQ));
                const __m256d down = _mm256_and_pd(_mm256_cmp_pd(r, half, _CMP_LT_OQ),
                                                   _mm256_cmp_pd(_mm256_add_pd(r, half), z, _CMP_LT_OQ));
                const __m256d code = _mm256_sub_pd(_mm256_add_pd(f, _mm256_and_pd(up, one)), _mm256_and_pd(down, one));
                // An integer below 2^32 plus 2^52 holds it in its low 32 bits.
                incoming = _mm256_castsi256_si128(
                    _mm256_permutevar8x32_epi32(_mm256_castpd_si256(_mm256_add_pd(code, magic)), low32));
            }
            if constexpr (Record) {
                FragGroup* g = rec++;
                g->pixel = uint32_t(size_t(j) * stride + size_t(i));
                g->lanes = uint32_t(inside);
                _mm_storeu_si128(reinterpret_cast<__m128i*>(g->z), incoming);
            }
            const __m128i lanes = _mm_load_si128(reinterpret_cast<const __m128i*>(kLaneMasks[inside]));
            const __m128i stored = _mm_maskload_epi32(reinterpret_cast<const int*>(d + i), lanes);
            const __m128i ok = depthTest4<F>(incoming, stored, lanes);
            const int okBits = _mm_movemask_ps(_mm_castsi128_ps(ok));
            frag += uint64_t(std::popcount(unsigned(inside)));
            pass += uint64_t(std::popcount(unsigned(okBits)));
            if (mask && okBits != 0) _mm_maskstore_epi32(reinterpret_cast<int*>(d + i), ok, incoming);
        }
    }
    fragments += frag;
    passed += pass;
}
#endif

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
        const __m128i lanes = _mm_load_si128(reinterpret_cast<const __m128i*>(kLaneMasks[g->lanes]));
        const __m128i incoming = _mm_loadu_si128(reinterpret_cast<const __m128i*>(g->z));
        int* d = reinterpret_cast<int*>(depth + g->pixel);
        const __m128i ok = depthTest4<F>(incoming, _mm_maskload_epi32(d, lanes), lanes);
        const int okBits = _mm_movemask_ps(_mm_castsi128_ps(ok));
        frag += uint64_t(std::popcount(g->lanes));
        pass += uint64_t(std::popcount(unsigned(okBits)));
        if (mask && okBits != 0) _mm_maskstore_epi32(d, ok, incoming);
    }
    fragments += frag;
    passed += pass;
}
#endif

// Conservative mode (rules 10-13): a record and its fast-path edge functions.
struct ConsRec {
    detail::ConsTri t;
    detail::ConsEdges e;
};

// One conservative record clipped to a pixel rectangle: test and/or merge intervals.
void rasterizeConservative(const ConsRec& r, int bx0, int by0, int bx1, int by1, uint32_t* ilo, uint32_t* ihi,
                           size_t stride, bool test, bool write, const DepthFormat& format, uint64_t& fragments,
                           uint64_t& passed) {
    const detail::ConsTri& t = r.t;
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
            detail::consInterval(t, i, j, format, lo, hi);
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

using RasterFn = void (*)(const EdgeTri&, int, int, int, int, uint32_t*, size_t, bool, int, uint64_t&, uint64_t&,
                          FragGroup*&);
using ReplayFn = void (*)(const FragGroup*, const FragGroup*, uint32_t*, bool, uint64_t&, uint64_t&);

// The pixel loops for one CPU and depth format, indexed by DepthFunc: rasterizing (raster),
// rasterizing and recording (record), replaying (replay).
struct RasterTable {
    std::array<RasterFn, 8> raster, record;
    std::array<ReplayFn, 8> replay;
};

template <template <DepthFunc, bool, bool> class K, bool Float, size_t... F>
constexpr RasterTable makeTable(std::index_sequence<F...>) {
    return {std::array<RasterFn, 8>{K<DepthFunc(F), Float, false>::run...},
            std::array<RasterFn, 8>{K<DepthFunc(F), Float, true>::run...},
            std::array<ReplayFn, 8>{K<DepthFunc(F), Float, false>::replay...}};
}

template <DepthFunc F, bool Float, bool Record>
struct ScalarKernel {
    static constexpr RasterFn run = &rasterizeInTile<F, Float, Record>;
    static constexpr ReplayFn replay = &replayFragments<F>;
};

#ifdef CULLIDE_RASTER_AVX2
template <DepthFunc F, bool Float, bool Record>
struct Avx2Kernel {
    static constexpr RasterFn run = &rasterizeInTileAvx2<F, Float, Record>;
    static constexpr ReplayFn replay = &replayFragmentsAvx2<F>;
};
#endif

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

// First index in [lo, hi) of `v` with v[idx] >= key, searching outwards from `hint` (galloping).
size_t gallopLowerBound(const uint32_t* v, size_t n, size_t hint, uint32_t key) {
    if (hint > n) hint = n;
    if (hint < n && v[hint] < key) {  // forward
        size_t step = 1, lo = hint + 1;
        while (hint + step < n && v[hint + step] < key) {
            lo = hint + step + 1;
            step *= 2;
        }
        const size_t hi = std::min(n, hint + step);
        return size_t(std::lower_bound(v + lo, v + hi, key) - v);
    }
    // backward: v[hint] >= key (or hint == n)
    size_t step = 1, hi = hint;
    while (step <= hint && v[hint - step] >= key) {
        hi = hint - step;
        step *= 2;
    }
    const size_t lo = step <= hint ? hint - step + 1 : 0;
    return size_t(std::lower_bound(v + lo, v + hi, key) - v);
}

class CpuBackendImpl final : public CpuBackend {
public:
    explicit CpuBackendImpl(const CpuBackendOptions& options)
        : options_(options), arena_(options.threads > 0 ? options.threads : tbb::task_arena::automatic) {}

    std::string describe() const override {
        std::string s = options_.scalarReference ? "cpu scalar reference" : "cpu reference";
        s += " (" + std::to_string(options_.subpixelBits) + " subpixel bits, " + toString(options_.fillRule) +
             " fill rule";
        if (!options_.scalarReference)
            s += ", " + std::to_string(options_.tileSize) + " px tiles, " +
                 (options_.threads > 0 ? std::to_string(options_.threads) : std::string("default")) + " threads";
        return s + ")";
    }

    const CpuBackendOptions& options() const override { return options_; }
    const RasterStats& lastStats() const override { return stats_; }
    bool supportsConservative() const override { return true; }

    IntervalImage readIntervals() override {
        IntervalImage img;
        if (!haveView_) return img;
        img.width = view_.width;
        img.height = view_.height;
        img.format = view_.depth;
        ensureIntervals();
        img.lo = ilo_;
        img.hi = ihi_;
        return img;
    }

    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override {
        const size_t n = positions.size();
        for (size_t t = 0; t < triangles.size(); ++t)
            for (uint32_t v : triangles[t])
                if (v >= n)
                    throw InputError("geometry", "triangle " + std::to_string(t) + " refers to vertex " +
                                                     std::to_string(v) + " of " + std::to_string(n));
        if (triangles.size() >= size_t(UINT32_MAX))
            throw InputError("geometry", "too many triangles for 32-bit indices");
        positions_.assign(positions.begin(), positions.end());
        triangles_.assign(triangles.begin(), triangles.end());
        windowValid_ = false;
    }

    void setView(const OrthoView& view) override {
        view.validate();
        const bool resize = !haveView_ || view.width != view_.width || view.height != view_.height ||
                            !(view.depth == view_.depth);
        view_ = view;
        haveView_ = true;
        windowValid_ = false;
        params_.subpixelBits = options_.subpixelBits;
        params_.fillRule = options_.fillRule;
        params_.width = view.width;
        params_.height = view.height;
        if (resize) {
            depth_.assign(size_t(view.width) * size_t(view.height), encodeDepth(1.0, view.depth));
            tilesX_ = (view.width + options_.tileSize - 1) / options_.tileSize;
            tilesY_ = (view.height + options_.tileSize - 1) / options_.tileSize;
            tileOut_.assign(size_t(tilesX_) * size_t(tilesY_), TileOut{});
            ilo_.clear();  // the interval buffer is made (empty) on first use
            ihi_.clear();
        }
    }

    std::vector<uint64_t> execute(const CommandList& list) override {
        if (!haveView_) throw InputError("command list", "execute() before setView()");
        if (list.queryOpen()) throw InputError("command list", "a query is left open at the end of the list");
        for (const Command& c : list.commands())
            if ((c.op == Command::Op::Draw || c.op == Command::Op::DrawConservative) &&
                uint64_t(c.first) + c.count > triangles_.size())
                throw InputError("command list", "draw range [" + std::to_string(c.first) + ", " +
                                                     std::to_string(uint64_t(c.first) + c.count) +
                                                     ") exceeds the geometry's " + std::to_string(triangles_.size()) +
                                                     " triangles");
        stats_ = RasterStats{};
        std::vector<uint64_t> results;
        inArena([&] {
            updateWindow();
            if (list.conservativeCount() > 0) {
                ensureIntervals();
                if (!consErrValid_) consErr_ = detail::windowError(view_, positions_);
                consErrValid_ = true;
            }
            if (options_.scalarReference)
                results = detail::executeReference(list, window_, triangles_, params_, view_.depth, state_, depth_,
                                                   stats_, {&ilo_, &ihi_, consErr_});
            else
                results = executeFast(list);
        });
        return results;
    }

    DepthImage readDepth() override {
        DepthImage img;
        if (!haveView_) return img;
        img.width = view_.width;
        img.height = view_.height;
        img.format = view_.depth;
        img.values = depth_;
        return img;
    }

private:
    void ensureIntervals() {
        const size_t n = size_t(view_.width) * size_t(view_.height);
        if (ilo_.size() == n) return;
        ilo_.assign(n, kEmptyIntervalLo);
        ihi_.assign(n, kEmptyIntervalHi);
    }

    // Conservative records of the union of the conservative draw ranges (rules 10-12), compacted
    // in triangle order like setupDrawn's: a draw [first, first+count) is the record range
    // [consBegin_[first], consEnd_[first+count-1]).
    void setupConservativeDrawn(const CommandList& list) {
        std::vector<std::array<uint32_t, 2>> rs, merged;
        for (const Command& c : list.commands())
            if (c.op == Command::Op::DrawConservative && c.count > 0) rs.push_back({c.first, c.first + c.count});
        std::sort(rs.begin(), rs.end());
        for (const auto& r : rs) {
            if (!merged.empty() && r[0] <= merged.back()[1]) merged.back()[1] = std::max(merged.back()[1], r[1]);
            else merged.push_back(r);
        }
        std::vector<std::array<uint32_t, 2>> chunks;
        for (const auto& r : merged)
            for (uint32_t b = r[0]; b < r[1]; b += kSetupChunk) chunks.push_back({b, std::min(r[1], b + kSetupChunk)});
        if (consFlags_.size() < triangles_.size()) {
            consFlags_.resize(triangles_.size());
            consBegin_.resize(triangles_.size());
            consEnd_.resize(triangles_.size());
        }
        std::vector<std::vector<ConsRec>> recs(chunks.size());
        std::vector<std::vector<TileRect>> tiles(chunks.size());
        const int ts = options_.tileSize;
        parallelFor(0, chunks.size(), 1, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t ci = r.begin(); ci != r.end(); ++ci) {
                for (uint32_t t = chunks[ci][0]; t < chunks[ci][1]; ++t) {
                    const Triangle& tri = triangles_[t];
                    consBegin_[t] = uint32_t(recs[ci].size());
                    ConsRec rec;
                    const bool ok =
                        detail::setupConservative(window_[tri[0]], window_[tri[1]], window_[tri[2]], params_, consErr_, rec.t);
                    consFlags_[t] = ok ? 0 : detail::kRejected;
                    if (ok) {
                        rec.e = detail::consEdges(rec.t, params_.subpixelBits);
                        recs[ci].push_back(rec);
                        tiles[ci].push_back(TileRect{uint16_t(rec.t.x0 / ts), uint16_t(rec.t.y0 / ts),
                                                     uint16_t(rec.t.x1 / ts), uint16_t(rec.t.y1 / ts)});
                    }
                    consEnd_[t] = uint32_t(recs[ci].size());
                }
            }
        });
        size_t total = 0;
        std::vector<size_t> offset(chunks.size() + 1, 0);
        for (size_t ci = 0; ci < chunks.size(); ++ci) offset[ci + 1] = offset[ci] + recs[ci].size();
        total = offset.back();
        CULLIDE_CHECK(total < size_t(UINT32_MAX), "too many conservative records for 32-bit indices");
        consRecords_.resize(total);
        consTiles_.resize(total);
        parallelFor(0, chunks.size(), 1, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t ci = r.begin(); ci != r.end(); ++ci) {
                std::copy(recs[ci].begin(), recs[ci].end(), consRecords_.begin() + ptrdiff_t(offset[ci]));
                std::copy(tiles[ci].begin(), tiles[ci].end(), consTiles_.begin() + ptrdiff_t(offset[ci]));
                for (uint32_t t = chunks[ci][0]; t < chunks[ci][1]; ++t) {
                    consBegin_[t] += uint32_t(offset[ci]);
                    consEnd_[t] += uint32_t(offset[ci]);
                }
            }
        });
    }

    void updateWindow() {
        if (windowValid_) return;
        consErrValid_ = false;
        window_.resize(positions_.size());
        snapped_.resize(positions_.size());
        parallelFor(0, positions_.size(), 4096, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t v = r.begin(); v != r.end(); ++v) {
                const Vec3d w = view_.toWindow(positions_[v]);
                window_[v] = {w.x(), w.y(), w.z()};
                SnapVertex& s = snapped_[v];
                s.inside = detail::insideClipVolume(window_[v], params_);
                s.x = s.inside ? int32_t(snapToFixed(w.x(), params_.subpixelBits)) : 0;
                s.y = s.inside ? int32_t(snapToFixed(w.y(), params_.subpixelBits)) : 0;
            }
        });
        windowValid_ = true;
    }

    // Step 3: set up the union of the drawn ranges, once per triangle.
    void setupDrawn(const CommandList& list) {
        // The union of the drawn ranges as sorted disjoint intervals: by sorting the ranges when
        // there are few, else by a difference array over the touched triangle span.
        ranges_.clear();
        uint32_t lo = UINT32_MAX, hi = 0;
        for (const Command& c : list.commands()) {
            if (c.op != Command::Op::Draw || c.count == 0) continue;
            const std::array<uint32_t, 2> r{c.first, c.first + c.count};
            if (!ranges_.empty() && ranges_.back() == r) continue;  // repeated draw of one object
            ranges_.push_back(r);
            lo = std::min(lo, r[0]);
            hi = std::max(hi, r[1]);
        }
        std::vector<std::array<uint32_t, 2>> merged;
        if (ranges_.size() * 16 < size_t(hi - lo) || ranges_.size() < 64) {
            std::sort(ranges_.begin(), ranges_.end());
            for (const auto& r : ranges_) {
                if (!merged.empty() && r[0] <= merged.back()[1])
                    merged.back()[1] = std::max(merged.back()[1], r[1]);
                else
                    merged.push_back(r);
            }
        } else {
            coverDiff_.assign(size_t(hi - lo) + 1, 0);
            for (const auto& r : ranges_) {
                ++coverDiff_[r[0] - lo];
                --coverDiff_[r[1] - lo];
            }
            int32_t depth = 0;
            for (uint32_t t = lo; t < hi; ++t) {
                const int32_t before = depth;
                depth += coverDiff_[t - lo];
                if (before == 0 && depth > 0) merged.push_back({t, t});
                if (depth > 0) merged.back()[1] = t + 1;
            }
        }
        chunks_.clear();
        for (const auto& r : merged)
            for (uint32_t b = r[0]; b < r[1]; b += kSetupChunk) chunks_.push_back({b, std::min(r[1], b + kSetupChunk)});
        SetupParams params = params_;
        params.dropEmpty = true;

        if (triFlags_.size() < triangles_.size()) {
            triFlags_.resize(triangles_.size());
            recBegin_.resize(triangles_.size());
            recEnd_.resize(triangles_.size());
        }
        if (chunkRecords_.size() < chunks_.size()) {
            chunkRecords_.resize(chunks_.size());
            chunkTiles_.resize(chunks_.size());
        }
        const int ts = options_.tileSize;
        parallelFor(0, chunks_.size(), 1, [&](const tbb::blocked_range<size_t>& r) {
            SnappedTri sub[detail::kMaxSubTriangles];
            for (size_t ci = r.begin(); ci != r.end(); ++ci) {
                std::vector<EdgeTri>& recs = chunkRecords_[ci];
                std::vector<TileRect>& tiles = chunkTiles_[ci];
                recs.clear();
                tiles.clear();
                for (uint32_t t = chunks_[ci][0]; t < chunks_[ci][1]; ++t) {
                    const Triangle& tri = triangles_[t];
                    int n = 0;
                    const WinVertex &v0 = window_[tri[0]], &v1 = window_[tri[1]], &v2 = window_[tri[2]];
                    const SnapVertex &s0 = snapped_[tri[0]], &s1 = snapped_[tri[1]], &s2 = snapped_[tri[2]];
                    if (s0.inside && s1.inside && s2.inside) {  // the common case: vertices snapped once
                        if (detail::trivialReject(v0, v1, v2, params)) {
                            triFlags_[t] = detail::kRejected;
                        } else {
                            const int64_t sx[3] = {s0.x, s1.x, s2.x}, sy[3] = {s0.y, s1.y, s2.y};
                            triFlags_[t] = detail::setupUnclipped(v0, v1, v2, sx, sy, params, sub, n);
                        }
                    } else {
                        triFlags_[t] = detail::setupTriangle(v0, v1, v2, params, sub, n);
                    }
                    recBegin_[t] = uint32_t(recs.size());
                    for (int s = 0; s < n; ++s) {
                        EdgeTri e;
                        if (!detail::makeEdgeTri(sub[s], params, e)) continue;
                        recs.push_back(e);
                        tiles.push_back(TileRect{uint16_t(e.x0 / ts), uint16_t(e.y0 / ts), uint16_t(e.x1 / ts),
                                                 uint16_t(e.y1 / ts)});
                    }
                    recEnd_[t] = uint32_t(recs.size());
                }
            }
        });
        chunkOffset_.resize(chunks_.size() + 1);
        chunkOffset_[0] = 0;
        for (size_t ci = 0; ci < chunks_.size(); ++ci) chunkOffset_[ci + 1] = chunkOffset_[ci] + chunkRecords_[ci].size();
        const size_t total = chunkOffset_.back();
        CULLIDE_CHECK(total < size_t(UINT32_MAX), "too many triangle records for 32-bit indices");
        records_.resize(total);
        recTiles_.resize(total);
        parallelFor(0, chunks_.size(), 1, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t ci = r.begin(); ci != r.end(); ++ci) {
                const uint32_t off = uint32_t(chunkOffset_[ci]);
                std::copy(chunkRecords_[ci].begin(), chunkRecords_[ci].end(), records_.begin() + off);
                std::copy(chunkTiles_[ci].begin(), chunkTiles_[ci].end(), recTiles_.begin() + off);
                for (uint32_t t = chunks_[ci][0]; t < chunks_[ci][1]; ++t) {
                    recBegin_[t] += off;
                    recEnd_[t] += off;
                }
            }
        });
    }

    // Generic CSR binning of `n` items to tiles, each tile's list in item order. `rectOf(i)` gives
    // item i's tile rectangle. Deterministic for any chunking.
    template <typename RectOf>
    void binToTiles(size_t n, RectOf rectOf, std::vector<uint32_t>& start, std::vector<uint32_t>& items) {
        binToTileSets(
            n,
            [&](size_t i, auto&& visit) {
                const TileRect t = rectOf(i);
                for (int ty = t.ty0; ty <= t.ty1; ++ty)
                    for (int tx = t.tx0; tx <= t.tx1; ++tx) visit(size_t(ty) * size_t(tilesX_) + size_t(tx));
            },
            start, items);
    }

    // The same for items whose tiles are any set: `tilesOf(i, visit)` calls visit(tile) once for
    // each tile of item i.
    template <typename TilesOf>
    void binToTileSets(size_t n, TilesOf tilesOf, std::vector<uint32_t>& start, std::vector<uint32_t>& items) {
        const size_t tiles = size_t(tilesX_) * size_t(tilesY_);
        const size_t nChunks = std::clamp<size_t>((n + kBinChunk - 1) / kBinChunk, 1, kMaxBinChunks);
        const size_t per = (n + nChunks - 1) / nChunks;
        binCounts_.assign(nChunks * tiles, 0);
        parallelFor(0, nChunks, 1, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t c = r.begin(); c != r.end(); ++c) {
                uint32_t* counts = binCounts_.data() + c * tiles;
                for (size_t i = c * per; i < std::min(n, (c + 1) * per); ++i) tilesOf(i, [&](size_t tile) { ++counts[tile]; });
            }
        });
        start.resize(tiles + 1);
        uint64_t running = 0;
        for (size_t tile = 0; tile < tiles; ++tile) {
            start[tile] = uint32_t(running);
            for (size_t c = 0; c < nChunks; ++c) {
                const uint32_t cnt = binCounts_[c * tiles + tile];
                binCounts_[c * tiles + tile] = uint32_t(running);  // becomes the chunk's write cursor
                running += cnt;
            }
        }
        CULLIDE_CHECK(running < uint64_t(UINT32_MAX), "too many tile entries for 32-bit indices");
        start[tiles] = uint32_t(running);
        items.resize(running);
        parallelFor(0, nChunks, 1, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t c = r.begin(); c != r.end(); ++c) {
                uint32_t* cursor = binCounts_.data() + c * tiles;
                for (size_t i = c * per; i < std::min(n, (c + 1) * per); ++i)
                    tilesOf(i, [&](size_t tile) { items[cursor[tile]++] = uint32_t(i); });
            }
        });
    }

    std::vector<uint64_t> executeFast(const CommandList& list) {
        setupDrawn(list);
        binToTiles(records_.size(), [&](size_t i) { return recTiles_[i]; }, tileRecStart_, tileRecs_);

        const bool conservative = list.conservativeCount() > 0;
        if (conservative) {
            setupConservativeDrawn(list);
            binToTiles(consRecords_.size(), [&](size_t i) { return consTiles_[i]; }, consTileStart_, consTileRecs_);
        }

        // Step 5: events with their state.
        events_.clear();
        std::vector<QueryKind> kinds(list.queryCount());
        int32_t query = -1, nextQuery = 0;
        const TileRect all{0, 0, uint16_t(tilesX_ - 1), uint16_t(tilesY_ - 1)};
        for (const Command& c : list.commands()) {
            switch (c.op) {
                case Command::Op::Clear: {
                    Event e;
                    e.clear = true;
                    e.clearValue = encodeDepth(c.clearDepth, view_.depth);
                    e.tiles = all;
                    events_.push_back(e);
                    break;
                }
                case Command::Op::SetDepthFunc: state_.func = c.func; break;
                case Command::Op::SetDepthMask: state_.mask = c.mask; break;
                case Command::Op::BeginQuery:
                    query = nextQuery++;
                    kinds[size_t(query)] = c.queryKind;
                    break;
                case Command::Op::EndQuery: query = -1; break;
                case Command::Op::ClearIntervals: {
                    Event e;
                    e.intervalClear = true;
                    e.tiles = all;
                    events_.push_back(e);
                    break;
                }
                case Command::Op::DrawConservative: {
                    ++stats_.draws;
                    stats_.triangles += c.count;
                    if (c.count == 0) break;
                    Event e;
                    e.conservative = true;
                    e.test = c.test;
                    e.write = c.write;
                    e.query = query;
                    e.first = c.first;
                    e.count = c.count;
                    e.recBegin = consBegin_[c.first];
                    e.recEnd = consEnd_[c.first + c.count - 1];
                    events_.push_back(e);
                    break;
                }
                case Command::Op::Draw: {
                    ++stats_.draws;
                    stats_.triangles += c.count;
                    if (c.count == 0) break;
                    Event e;
                    e.func = state_.func;
                    e.mask = state_.mask;
                    e.query = query;
                    e.first = c.first;
                    e.count = c.count;
                    e.recBegin = recBegin_[c.first];
                    e.recEnd = recEnd_[c.first + c.count - 1];
                    events_.push_back(e);
                    break;
                }
            }
        }
        // Tile rectangles of the draws and their setup statistics, O(triangles drawn).
        eventStats_.assign(events_.size(), {0, 0, 0});
        parallelFor(0, events_.size(), 256, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t k = r.begin(); k != r.end(); ++k) {
                Event& e = events_[k];
                if (e.clear || e.intervalClear) continue;
                const std::vector<TileRect>& rects = e.conservative ? consTiles_ : recTiles_;
                int tx0 = tilesX_, ty0 = tilesY_, tx1 = -1, ty1 = -1;
                for (uint32_t i = e.recBegin; i < e.recEnd; ++i) {
                    const TileRect& t = rects[i];
                    tx0 = std::min<int>(tx0, t.tx0);
                    ty0 = std::min<int>(ty0, t.ty0);
                    tx1 = std::max<int>(tx1, t.tx1);
                    ty1 = std::max<int>(ty1, t.ty1);
                }
                e.tiles = tx1 < 0 ? TileRect{1, 1, 0, 0} : TileRect{uint16_t(tx0), uint16_t(ty0), uint16_t(tx1), uint16_t(ty1)};
                std::array<uint32_t, 3>& s = eventStats_[k];
                if (e.conservative) {  // only rejections: nothing is clipped, zero area is drawn
                    for (uint32_t t = e.first; t < e.first + e.count; ++t) s[0] += consFlags_[t] ? 1 : 0;
                    continue;
                }
                for (uint32_t t = e.first; t < e.first + e.count; ++t) {
                    const uint8_t f = triFlags_[t];
                    s[0] += (f & detail::kRejected) ? 1 : 0;
                    s[1] += (f & detail::kClipped) ? 1 : 0;
                    s[2] += (f & detail::kZeroArea) ? 1 : 0;
                }
            }
        });
        for (const auto& s : eventStats_) {
            stats_.rejected += s[0];
            stats_.clipped += s[1];
            stats_.zeroArea += s[2];
        }
        // Each draw goes to the tiles its records touch, not to every tile of their bounding
        // rectangle: a draw of 16 triangles scattered through a scan's file order would visit
        // about 5x more tiles (bunny75k: 634,560 visits instead of 128,116), each for nothing.
        // Draws of more than kExactTilesUpTo records keep their rectangle (one thread walks each
        // draw's records here: a whole mesh would cost more than it saves).
        const size_t nTiles = size_t(tilesX_) * size_t(tilesY_);
        constexpr size_t kEventBlock = 256;
        const size_t eventBlocks = (events_.size() + kEventBlock - 1) / kEventBlock;
        eventTileStart_.assign(events_.size() + 1, 0);
        auto eachTile = [&](const Event& e, std::vector<uint32_t>& stamp, uint32_t k, auto&& visit) {
            if (e.clear || e.intervalClear) {
                for (size_t t = 0; t < nTiles; ++t) visit(t);
                return;
            }
            const int rectTiles = (e.tiles.tx1 - e.tiles.tx0 + 1) * (e.tiles.ty1 - e.tiles.ty0 + 1);
            // Large draws cover their rectangle anyway; a rectangle of one or two tiles wastes
            // at most one visit, less than finding the exact set costs.
            if (rectTiles <= 2 || e.recEnd - e.recBegin > kExactTilesUpTo) {
                for (int ty = e.tiles.ty0; ty <= e.tiles.ty1; ++ty)
                    for (int tx = e.tiles.tx0; tx <= e.tiles.tx1; ++tx) visit(size_t(ty) * size_t(tilesX_) + size_t(tx));
                return;
            }
            const std::vector<TileRect>& rects = e.conservative ? consTiles_ : recTiles_;
            for (uint32_t i = e.recBegin; i < e.recEnd; ++i)
                for (int ty = rects[i].ty0; ty <= rects[i].ty1; ++ty)
                    for (int tx = rects[i].tx0; tx <= rects[i].tx1; ++tx) {
                        const size_t t = size_t(ty) * size_t(tilesX_) + size_t(tx);
                        if (stamp[t] != k) stamp[t] = k, visit(t);
                    }
        };
        // A draw of the same records as the event before it (reducePCS draws each object twice in
        // a row) has the same tiles: copied, within a block.
        auto sameAsPrevious = [&](size_t k, size_t blockStart) {
            if (k == blockStart) return false;
            const Event &e = events_[k], &f = events_[k - 1];
            return !e.clear && !e.intervalClear && !f.clear && !f.intervalClear && e.conservative == f.conservative &&
                   e.recBegin == f.recBegin && e.recEnd == f.recEnd;
        };
        // One pass per block into the block's list, then the blocks concatenated.
        if (blockTiles_.size() < eventBlocks) blockTiles_.resize(eventBlocks);
        parallelForEach(0, eventBlocks, [&](size_t blk) {
            std::vector<uint32_t> stamp(nTiles, UINT32_MAX);
            std::vector<uint32_t>& out = blockTiles_[blk];
            out.clear();
            for (size_t k = blk * kEventBlock; k < std::min(events_.size(), (blk + 1) * kEventBlock); ++k) {
                const size_t before = out.size();
                if (sameAsPrevious(k, blk * kEventBlock)) {
                    const size_t n = eventTileStart_[k];  // the previous event's count, the last n entries
                    out.resize(before + n);
                    std::copy_n(out.begin() + ptrdiff_t(before - n), n, out.begin() + ptrdiff_t(before));
                } else {
                    eachTile(events_[k], stamp, uint32_t(k), [&](size_t t) { out.push_back(uint32_t(t)); });
                }
                eventTileStart_[k + 1] = out.size() - before;
            }
        });
        for (size_t k = 0; k < events_.size(); ++k) eventTileStart_[k + 1] += eventTileStart_[k];
        eventTiles_.resize(eventTileStart_.back());
        parallelForEach(0, eventBlocks, [&](size_t blk) {
            std::copy(blockTiles_[blk].begin(), blockTiles_[blk].end(),
                      eventTiles_.begin() + ptrdiff_t(eventTileStart_[blk * kEventBlock]));
        });
        binToTileSets(
            events_.size(),
            [&](size_t i, auto&& visit) {
                for (size_t k = eventTileStart_[i]; k < eventTileStart_[i + 1]; ++k) visit(eventTiles_[k]);
            },
            tileEvStart_, tileEvs_);

        // Step 6: one task per tile.
        const size_t tiles = size_t(tilesX_) * size_t(tilesY_);
        const bool isFloat = view_.depth.kind == DepthFormat::Kind::Float32;
        const RasterTable table = pickRasterTable(isFloat, options_.simd);
        const int bits = view_.depth.bits, ts = options_.tileSize, W = view_.width, H = view_.height;
        parallelFor(0, tiles, 1, [&](const tbb::blocked_range<size_t>& r) {
            for (size_t tile = r.begin(); tile != r.end(); ++tile) {
                TileOut& out = tileOut_[tile];
                out.queries.clear();
                out.fragments = out.passed = 0;
                const int bx0 = int(tile % size_t(tilesX_)) * ts, by0 = int(tile / size_t(tilesX_)) * ts;
                const int bx1 = std::min(bx0 + ts, W) - 1, by1 = std::min(by0 + ts, H) - 1;
                const uint32_t* recs = tileRecs_.data() + tileRecStart_[tile];
                const size_t nrecs = tileRecStart_[tile + 1] - tileRecStart_[tile];
                size_t hint = 0, consHint = 0;
                FragCache& cache = frags_.local();
                cache.reset(tileEvStart_[tile + 1] - tileEvStart_[tile]);
                for (uint32_t k = tileEvStart_[tile]; k < tileEvStart_[tile + 1]; ++k) {
                    const Event& e = events_[tileEvs_[k]];
                    if (e.clear) {
                        for (int j = by0; j <= by1; ++j)
                            std::fill_n(depth_.data() + size_t(j) * size_t(W) + size_t(bx0), bx1 - bx0 + 1, e.clearValue);
                        continue;
                    }
                    if (e.intervalClear) {
                        for (int j = by0; j <= by1; ++j) {
                            std::fill_n(ilo_.data() + size_t(j) * size_t(W) + size_t(bx0), bx1 - bx0 + 1, kEmptyIntervalLo);
                            std::fill_n(ihi_.data() + size_t(j) * size_t(W) + size_t(bx0), bx1 - bx0 + 1, kEmptyIntervalHi);
                        }
                        continue;
                    }
                    if (e.conservative) {
                        const uint32_t* crecs = consTileRecs_.data() + consTileStart_[tile];
                        const size_t ncrecs = consTileStart_[tile + 1] - consTileStart_[tile];
                        size_t p = gallopLowerBound(crecs, ncrecs, consHint, e.recBegin);
                        const uint64_t before = out.passed;
                        for (; p < ncrecs && crecs[p] < e.recEnd; ++p)
                            rasterizeConservative(consRecords_[crecs[p]], bx0, by0, bx1, by1, ilo_.data(), ihi_.data(),
                                                  size_t(W), e.test, e.write, view_.depth, out.fragments, out.passed);
                        consHint = p;
                        const uint64_t n = out.passed - before;
                        if (e.query >= 0 && n > 0) {
                            if (!out.queries.empty() && out.queries.back().query == uint32_t(e.query))
                                out.queries.back().count += n;
                            else
                                out.queries.push_back({uint32_t(e.query), n});
                        }
                        continue;
                    }
                    const uint64_t before = out.passed;
                    FragCache::Entry& seen = cache.find(e.recBegin, e.recEnd);
                    if (seen.recBegin == e.recBegin && seen.recEnd == e.recEnd) {
                        table.replay[size_t(e.func)](cache.groups.data() + seen.start, cache.groups.data() + seen.stop,
                                                     depth_.data(), e.mask, out.fragments, out.passed);
                    } else {
                        // Rasterize and record, while the groups fit.
                        FragGroup* const groups = cache.groups.data();
                        FragGroup* w = groups + cache.used;
                        bool record = true;
                        size_t p = gallopLowerBound(recs, nrecs, hint, e.recBegin);
                        for (; p < nrecs && recs[p] < e.recEnd; ++p) {
                            // A tile's records are scattered through records_: fetch ahead (no
                            // effect on results).
                            if (p + kPrefetch < nrecs) {
                                const char* ahead = reinterpret_cast<const char*>(&records_[recs[p + kPrefetch]]);
                                __builtin_prefetch(ahead);
                                __builtin_prefetch(ahead + 64);
                            }
                            const EdgeTri& tri = records_[recs[p]];
                            if (record) {  // room for one group per pixel of the clipped rectangle
                                const int64_t cw = std::min<int>(tri.x1, bx1) - std::max<int>(tri.x0, bx0) + 1;
                                const int64_t ch = std::min<int>(tri.y1, by1) - std::max<int>(tri.y0, by0) + 1;
                                record = cw <= 0 || ch <= 0 || int64_t(groups + kFragCap - w) >= cw * ch;
                            }
                            (record ? table.record : table.raster)[size_t(e.func)](
                                tri, bx0, by0, bx1, by1, depth_.data(), size_t(W), e.mask, bits, out.fragments,
                                out.passed, w);
                        }
                        hint = p;
                        if (record) {
                            seen = {e.recBegin, e.recEnd, uint32_t(cache.used), uint32_t(w - groups)};
                            cache.used = size_t(w - groups);
                        }
                    }
                    const uint64_t n = out.passed - before;
                    if (e.query >= 0 && n > 0) {
                        if (!out.queries.empty() && out.queries.back().query == uint32_t(e.query))
                            out.queries.back().count += n;
                        else
                            out.queries.push_back({uint32_t(e.query), n});
                    }
                }
            }
        });
        (void)H;

        // Step 7: sum.
        std::vector<uint64_t> results(list.queryCount(), 0);
        for (const TileOut& out : tileOut_) {
            for (const QueryCount& q : out.queries) results[q.query] += q.count;
            stats_.fragments += out.fragments;
            stats_.passed += out.passed;
        }
        for (size_t q = 0; q < results.size(); ++q)
            if (kinds[q] == QueryKind::AnySamplesPassed) results[q] = results[q] > 0 ? 1 : 0;
        return results;
    }

    // arena_.execute(f), with the hand-over annotated for ThreadSanitizer (cullide/parallel.h).
    template <typename F>
    void inArena(const F& f) {
        executeIn(arena_, f);
    }

    CpuBackendOptions options_;
    tbb::task_arena arena_;
    std::vector<Vec3f> positions_;
    std::vector<Triangle> triangles_;
    OrthoView view_;
    bool haveView_ = false;
    SetupParams params_;
    std::vector<WinVertex> window_;
    std::vector<SnapVertex> snapped_;  // window_ snapped once per vertex (fast path)
    bool windowValid_ = false;
    std::vector<uint32_t> depth_;
    detail::PipelineState state_;
    RasterStats stats_;

    // Fast-path scratch, reused across lists (capacity kept).
    int tilesX_ = 0, tilesY_ = 0;
    std::vector<std::array<uint32_t, 2>> ranges_, chunks_;
    std::vector<int32_t> coverDiff_;
    std::vector<uint8_t> triFlags_;
    std::vector<uint32_t> recBegin_, recEnd_;
    std::vector<std::vector<EdgeTri>> chunkRecords_;
    std::vector<std::vector<TileRect>> chunkTiles_;
    std::vector<size_t> chunkOffset_;
    std::vector<EdgeTri> records_;
    std::vector<TileRect> recTiles_;
    std::vector<uint32_t> binCounts_;
    std::vector<uint32_t> tileRecStart_, tileRecs_;
    std::vector<Event> events_;
    std::vector<std::array<uint32_t, 3>> eventStats_;
    std::vector<uint32_t> tileEvStart_, tileEvs_;
    std::vector<size_t> eventTileStart_;  // per event, its run in eventTiles_
    std::vector<uint32_t> eventTiles_;    // the tiles each event's records touch
    std::vector<std::vector<uint32_t>> blockTiles_;  // eventTiles_ per block of events, before concatenation
    std::vector<TileOut> tileOut_;
    tbb::enumerable_thread_specific<FragCache> frags_;  // per thread

    // Conservative mode: the interval buffer, toWindow's error bound, records and bins.
    std::vector<uint32_t> ilo_, ihi_;
    detail::WindowError consErr_;
    bool consErrValid_ = false;
    std::vector<uint8_t> consFlags_;
    std::vector<uint32_t> consBegin_, consEnd_;
    std::vector<ConsRec> consRecords_;
    std::vector<TileRect> consTiles_;
    std::vector<uint32_t> consTileStart_, consTileRecs_;
};

}  // namespace

std::unique_ptr<CpuBackend> makeCpuBackend(const CpuBackendOptions& options) {
    if (options.subpixelBits < kMinSubpixelBits || options.subpixelBits > kMaxSubpixelBits)
        throw InputError("cpu backend options", "subpixel bits must be " + std::to_string(kMinSubpixelBits) + ".." +
                                                    std::to_string(kMaxSubpixelBits) + ", got " +
                                                    std::to_string(options.subpixelBits));
    if (options.threads < 0 || options.threads > 1024)
        throw InputError("cpu backend options", "threads must be 0 (default) to 1024, got " + std::to_string(options.threads));
    if (options.tileSize < 8 || options.tileSize > 1024)
        throw InputError("cpu backend options", "tile size must be 8..1024 pixels, got " + std::to_string(options.tileSize));
    if (options.fillRule != FillRule::BottomLeft && options.fillRule != FillRule::TopLeft)
        throw InputError("cpu backend options", "unknown fill rule");
    return std::make_unique<CpuBackendImpl>(options);
}

}  // namespace cullide::raster
