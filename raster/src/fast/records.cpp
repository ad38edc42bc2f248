// Triangle records for the fast path of the CPU backend (records.h).
#include "fast/records.h"

#include "setup/snap_lanes.h"

#include "cullide/error.h"
#include "cullide/parallel.h"

#include <oneapi/tbb/blocked_range.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cullide::raster::detail {

namespace {

constexpr uint32_t kSetupChunk = 1024;  // triangles per setup task (and per slot)

// set.chunks: the union of the ranges of `op` commands as sorted disjoint intervals (by sorting
// the ranges when there are few, else by a difference array over the touched triangle span), cut
// into chunks of at most kSetupChunk triangles.
template <typename Rec>
void drawnChunks(const CommandList& list, Command::Op op, RecordSet<Rec>& set) {
    set.ranges.clear();
    uint32_t lo = UINT32_MAX, hi = 0;
    for (const Command& c : list.commands()) {
        if (c.op != op || c.count == 0) continue;
        const std::array<uint32_t, 2> r{c.first, c.first + c.count};
        if (!set.ranges.empty() && set.ranges.back() == r) continue;  // repeated draw of one object
        set.ranges.push_back(r);
        lo = std::min(lo, r[0]);
        hi = std::max(hi, r[1]);
    }
    std::vector<std::array<uint32_t, 2>> merged;
    if (set.ranges.size() * 16 < size_t(hi - lo) || set.ranges.size() < 64) {
        std::sort(set.ranges.begin(), set.ranges.end());
        for (const auto& r : set.ranges) {
            if (!merged.empty() && r[0] <= merged.back()[1]) merged.back()[1] = std::max(merged.back()[1], r[1]);
            else merged.push_back(r);
        }
    } else {
        set.coverDiff.assign(size_t(hi - lo) + 1, 0);
        for (const auto& r : set.ranges) {
            ++set.coverDiff[r[0] - lo];
            --set.coverDiff[r[1] - lo];
        }
        int32_t depth = 0;
        for (uint32_t t = lo; t < hi; ++t) {
            const int32_t before = depth;
            depth += set.coverDiff[t - lo];
            if (before == 0 && depth > 0) merged.push_back({t, t});
            if (depth > 0) merged.back()[1] = t + 1;
        }
    }
    set.chunks.clear();
    for (const auto& r : merged)
        for (uint32_t b = r[0]; b < r[1]; b += kSetupChunk) set.chunks.push_back({b, std::min(r[1], b + kSetupChunk)});
}

TileRect tileRectOf(const EdgeTri& r, const TileGrid& grid) {
    return grid.of(r.x0, r.y0, r.x1, r.y1);
}
TileRect tileRectOf(const ConsRec& r, const TileGrid& grid) {
    return grid.of(r.t.x0, r.t.y0, r.t.x1, r.t.y1);
}

// Resizes `v` to n elements, reallocating to exactly n when it must grow: the contents are about
// to be overwritten, so the old buffer goes first (no peak of both, no doubled capacity).
template <typename T>
void resizeForOverwrite(RecordArray<T>& v, size_t n) {
    if (v.capacity() < n) {
        RecordArray<T>().swap(v);
        v.reserve(n);
    }
    v.resize(n);
}

// Lays the slots out again when chunks spilled (clipped triangles with several records): each
// chunk's slot grows to what it used, the records move, begin/end follow. Rare; costs one copy.
template <typename Rec>
void relayoutSpilled(RecordSet<Rec>& set) {
    const std::vector<std::array<uint32_t, 2>>& chunks = set.chunks;
    std::vector<size_t> start(chunks.size() + 1, 0);
    for (size_t ci = 0; ci < chunks.size(); ++ci)
        start[ci + 1] = start[ci] + std::max<size_t>(set.slotStart[ci + 1] - set.slotStart[ci], set.used[ci]);
    CULLIDE_CHECK(start.back() < size_t(UINT32_MAX), "too many triangle records for 32-bit indices");
    RecordArray<Rec> records(start.back());
    RecordArray<TileRect> tiles(start.back(), kNoTiles);
    parallelFor(0, chunks.size(), 1, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t ci = r.begin(); ci != r.end(); ++ci) {
            const bool spilled = !set.spillRecords[ci].empty();
            const Rec* from = spilled ? set.spillRecords[ci].data() : set.records.data() + set.slotStart[ci];
            const TileRect* fromTiles = spilled ? set.spillTiles[ci].data() : set.tiles.data() + set.slotStart[ci];
            std::copy_n(from, set.used[ci], records.begin() + ptrdiff_t(start[ci]));
            std::copy_n(fromTiles, set.used[ci], tiles.begin() + ptrdiff_t(start[ci]));
            const uint32_t shift = uint32_t(start[ci] - set.slotStart[ci]);
            for (uint32_t t = chunks[ci][0]; t < chunks[ci][1]; ++t) {
                set.begin[t] += shift;
                set.end[t] += shift;
            }
        }
    });
    set.records.swap(records);
    set.tiles.swap(tiles);
    set.slotStart.swap(start);
    for (size_t ci = 0; ci < chunks.size(); ++ci) {
        std::vector<Rec>().swap(set.spillRecords[ci]);
        std::vector<TileRect>().swap(set.spillTiles[ci]);
    }
}

// Sets up the triangles of set.chunks, in parallel over chunks: `setupOne(t, scratch, emit,
// reserve)` calls emit(make) for each record of triangle t, make(record) filling it in place (and
// saying whether to keep it), and returns its TriFlags (`scratch`, a Scratch per task). Records go
// straight to their chunk's slot (records.h), sized by `countRange(lo, hi)`, the sum over the
// chunk's triangles of a cheap guess of their records: a guess too high leaves unused slots, one
// too low makes the chunk spill; the records are the same either way. Then they are binned to
// tiles.
// Deferred records, for setup in batches: reserve() hands out the next record and its tile
// rectangle in the slot, to be filled later ({null, null} when the slot is full or spilled); every
// reserved record must be filled before the next emit (which may move the slot's records) and
// before `finishChunk(scratch)` returns, called at the end of each chunk.
template <typename Rec>
struct Reserved {
    Rec* record;
    TileRect* tiles;
};

//
// `wholeChunk(lo, hi, slot, cap, recs, tiles, scratch)` may set up a chunk's triangles [lo, hi) in
// one go instead (writing their flags, begin and end, and the records of its slot, which starts at
// index `slot` and holds `cap`): it returns their records, or -1 to leave the chunk to setupOne.
template <typename Scratch, typename Rec, typename CountRange, typename SetupOne, typename FinishChunk,
          typename WholeChunk>
void buildRecords(RecordSet<Rec>& set, size_t triangles, const TileGrid& grid, const CountRange& countRange,
                  const SetupOne& setupOne, const FinishChunk& finishChunk, const WholeChunk& wholeChunk) {
    if (set.flags.size() < triangles) {
        set.flags.resize(triangles);
        set.begin.resize(triangles);
        set.end.resize(triangles);
    }
    const std::vector<std::array<uint32_t, 2>>& chunks = set.chunks;
    set.slotStart.resize(chunks.size() + 1);
    set.slotStart[0] = 0;
    parallelFor(0, chunks.size(), 1, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t ci = r.begin(); ci != r.end(); ++ci) {
            set.slotStart[ci + 1] = countRange(chunks[ci][0], chunks[ci][1]);
        }
    });
    for (size_t ci = 0; ci < chunks.size(); ++ci) set.slotStart[ci + 1] += set.slotStart[ci];
    CULLIDE_CHECK(set.slotStart.back() < size_t(UINT32_MAX), "too many triangle records for 32-bit indices");
    resizeForOverwrite(set.records, set.slotStart.back());
    resizeForOverwrite(set.tiles, set.slotStart.back());
    set.used.assign(chunks.size(), 0);
    if (set.spillRecords.size() < chunks.size()) {
        set.spillRecords.resize(chunks.size());
        set.spillTiles.resize(chunks.size());
    }
    std::atomic<bool> anySpilled{false};
    parallelFor(0, chunks.size(), 1, [&](const tbb::blocked_range<size_t>& r) {
        Scratch scratch;
        const TileGrid g = grid;
        for (size_t ci = r.begin(); ci != r.end(); ++ci) {
            const size_t slot = set.slotStart[ci], cap = set.slotStart[ci + 1] - slot;
            Rec* const recs = set.records.data() + slot;
            TileRect* const tiles = set.tiles.data() + slot;
            if (const int64_t whole = wholeChunk(chunks[ci][0], chunks[ci][1], slot, cap, recs, tiles, scratch);
                whole >= 0) {
                std::fill(tiles + whole, tiles + cap, kNoTiles);
                set.used[ci] = uint32_t(whole);
                continue;
            }
            std::vector<Rec>& spill = set.spillRecords[ci];
            std::vector<TileRect>& spillTiles = set.spillTiles[ci];
            size_t n = 0;
            // emit(make): make(record) fills a record and says whether to keep it. It writes in
            // place in the slot (no copy of the record) while the slot has room.
            auto emit = [&](auto&& make) {
                if (n < cap && spill.empty()) {
                    if (!make(recs[n])) return;
                    tiles[n] = tileRectOf(recs[n], g);
                    ++n;
                    return;
                }
                Rec rec;
                if (!make(rec)) return;
                if (spill.empty()) {  // outgrew the slot: move to the side vector
                    spill.assign(recs, recs + n);
                    spillTiles.assign(tiles, tiles + n);
                }
                spill.push_back(rec);
                spillTiles.push_back(tileRectOf(rec, g));
                ++n;
            };
            auto reserve = [&]() -> Reserved<Rec> {
                if (n < cap && spill.empty()) return {recs + n, tiles + n++};
                return {nullptr, nullptr};
            };
            for (uint32_t t = chunks[ci][0]; t < chunks[ci][1]; ++t) {
                set.begin[t] = uint32_t(slot + n);
                set.flags[t] = setupOne(t, scratch, emit, reserve);
                set.end[t] = uint32_t(slot + n);
            }
            finishChunk(scratch);
            if (spill.empty()) std::fill(tiles + n, tiles + cap, kNoTiles);
            else anySpilled.store(true, std::memory_order_relaxed);
            set.used[ci] = uint32_t(n);
        }
    });
    if (anySpilled.load()) relayoutSpilled(set);
    binToTiles(set.tiles, grid, set.counts, set.bins);
}

// setupDrawn's scratch: the sub-triangles of a clipped triangle, and up to four one-record
// triangles waiting for setupInsideEdgeTri4 in their reserved records.
struct SubTriangles {
    SnappedTri sub[kMaxSubTriangles];
    InsideBatch batch;
    EdgeTri* records[4];
    TileRect* tiles[4];
    int pending = 0;
    uint32_t ones[kSetupChunk];  // the whole-chunk path's one-record triangles
};
struct NoScratch {};

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))

// The count pass on the eight triangles tris[0..8) at once with AVX2: writes their hints to
// hint[0..8) and returns their records, as countHints does one by one (snapLanes8: the same
// verdicts).
__attribute__((target("avx2"))) uint32_t countHints8(const Triangle* tris, const SnapVertex* snapped,
                                                     const SetupParams& params, uint8_t* hint) {
    const SnapLanes8 s = snapLanes8(tris, snapped, params);
    const __m256i ones = _mm256_set1_epi32(-1);
    // clip ? kHintClip : one ? kHintOne | cw : rejected ? kRejected : flat ? kZeroArea : 0.
    __m256i h = _mm256_blendv_epi8(_mm256_and_si256(s.flat, _mm256_set1_epi32(kZeroArea)), _mm256_set1_epi32(kRejected),
                                   s.rejected);
    h = _mm256_blendv_epi8(
        h, _mm256_or_si256(_mm256_set1_epi32(kHintOne), _mm256_and_si256(s.cw, _mm256_set1_epi32(kHintCw))), s.one);
    h = _mm256_blendv_epi8(_mm256_set1_epi32(kHintClip), h, s.inside);
    // The low byte of each lane, eight bytes in triangle order.
    const __m256i low =
        _mm256_shuffle_epi8(h,
                            _mm256_setr_epi8(0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0, 4, 8, 12,
                                             -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1));
    const uint32_t first = uint32_t(_mm256_extract_epi32(low, 0)), second = uint32_t(_mm256_extract_epi32(low, 4));
    std::memcpy(hint, &first, 4);
    std::memcpy(hint + 4, &second, 4);
    const __m256i counted = _mm256_or_si256(_mm256_xor_si256(s.inside, ones), s.one);
    return uint32_t(std::popcount(uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(counted)))));
}

#else

uint32_t countHints8(const Triangle*, const SnapVertex*, const SetupParams&, uint8_t*) {
    CULLIDE_CHECK(false, "countHints8 without AVX2");
    return 0;
}

#endif

}  // namespace

uint32_t countHints(std::span<const Triangle> triangles, const SnapVertex* snapped, const SetupParams& params,
                    bool batched, uint32_t lo, uint32_t hi, uint8_t* hint) {
    auto countOne = [&](uint32_t t) -> uint32_t {
        uint8_t& h = hint[t - lo];
        const Triangle& tri = triangles[t];
        const SnapVertex &s0 = snapped[tri[0]], &s1 = snapped[tri[1]], &s2 = snapped[tri[2]];
        if (!(s0.inside && s1.inside && s2.inside)) return h = kHintClip, 1;
        const int64_t sx[3] = {s0.x, s1.x, s2.x}, sy[3] = {s0.y, s1.y, s2.y};
        const int64_t area2 = snappedArea2(sx, sy);
        const bool area = area2 != 0;
        if (area && boxHoldsCentre(sx, sy, params)) return h = uint8_t(kHintOne | (area2 < 0 ? kHintCw : 0)), 1;
        h = (s0.beyond & s1.beyond & s2.beyond) != 0 ? kRejected : area ? 0 : kZeroArea;
        return 0;
    };
    // Eight at a time where the CPU allows: the same hints and counts.
    uint32_t n = 0, t = lo;
    if (batched)
        for (; t + 8 <= hi; t += 8) n += countHints8(&triangles[t], snapped, params, hint + (t - lo));
    for (; t < hi; ++t) n += countOne(t);
    return n;
}

void setupDrawn(const CommandList& list, const SetupInput& in, RecordSet<EdgeTri>& out) {
    drawnChunks(list, Command::Op::Draw, out);
    SetupParams params = in.params;
    params.dropEmpty = true;
    // The count sizes each chunk's slot, and what it found is kept for the setup in the
    // triangles' flags (countHints), which the setup then overwrites.
    std::vector<uint8_t>& hint = out.flags;  // sized by buildRecords before it counts
    const bool batched = in.simd && haveSetupAvx2();
    auto countRange = [&](uint32_t lo, uint32_t hi) -> size_t {
        return countHints(in.triangles, in.snapped.data(), params, batched, lo, hi, &hint[lo]);
    };
    // One-record triangles are set up four at a time where the CPU allows (the records are the
    // same either way): each reserves its record, and a full batch fills all four.
    const TileGrid& grid = in.grid;
    auto flush = [&](SubTriangles& scratch) {
        if (scratch.pending == 0) return;
        const InsideBatch& b = scratch.batch;
        if (scratch.pending == 4) {
            setupInsideEdgeTri4(b, in.window.data(), in.snapped.data(), params, scratch.records);
        } else {
            for (int l = 0; l < scratch.pending; ++l)
                setupInsideLane(b, l, in.window.data(), in.snapped.data(), params, *scratch.records[l]);
        }
        for (int l = 0; l < scratch.pending; ++l) *scratch.tiles[l] = tileRectOf(*scratch.records[l], grid);
        scratch.pending = 0;
    };
    // Triangle t (hint h: kHintOne) joins the batch, to fill `record` and `tiles` when it is full.
    auto enqueue = [&](SubTriangles& scratch, uint32_t t, uint8_t h, EdgeTri* record, TileRect* tiles) {
        const int l = scratch.pending++;
        for (int k = 0; k < 3; ++k) scratch.batch.v[k][l] = in.triangles[t][k];
        scratch.batch.clockwise[l] = h & kHintCw ? -1 : 0;
        scratch.records[l] = record;
        scratch.tiles[l] = tiles;
        if (scratch.pending == 4) flush(scratch);
    };
    buildRecords<SubTriangles>(
        out, in.triangles.size(), in.grid, countRange,
        [&](uint32_t t, SubTriangles& scratch, auto&& emit, auto&& reserve) {
            const uint8_t h = hint[t];
            if ((h & (kHintOne | kHintClip)) == 0) return h;  // no record: the flags are known
            const Triangle& tri = in.triangles[t];
            const WinVertex &v0 = in.window[tri[0]], &v1 = in.window[tri[1]], &v2 = in.window[tri[2]];
            if (h & kHintOne) {  // area and a centre, so not rejected: one record, flags 0
                if (batched) {
                    if (const Reserved<EdgeTri> r = reserve(); r.record) {
                        enqueue(scratch, t, h, r.record, r.tiles);
                        return uint8_t(0);
                    }
                    flush(scratch);  // the slot is full: the records waiting go in before emit moves them
                }
                const SnapVertex &s0 = in.snapped[tri[0]], &s1 = in.snapped[tri[1]], &s2 = in.snapped[tri[2]];
                const int64_t sx[3] = {s0.x, s1.x, s2.x}, sy[3] = {s0.y, s1.y, s2.y};
                emit([&](EdgeTri& e) { return setupInsideEdgeTri(v0, v1, v2, sx, sy, h & kHintCw, params, e), true; });
                return uint8_t(0);
            }
            flush(scratch);  // before emit may move the slot's records
            SnappedTri* sub = scratch.sub;
            int n = 0;
            const uint8_t flags = setupTriangle(v0, v1, v2, params, sub, n);
            for (int s = 0; s < n; ++s) emit([&](EdgeTri& e) { return makeEdgeTri(sub[s], params, e); });
            return flags;
        },
        flush,
        // A chunk without clipped triangles (most): each has one record (kHintOne) or none, and the
        // count sized its slot exactly. Its begin, end and flags follow from the hints without a
        // branch per triangle (whether a small triangle has a record depends on its data, 82% of
        // the 270k bunny's in one view, so the branch mispredicted often), then the one-record
        // triangles are set up four at a time from a list. The same records and flags as setupOne's.
        [&](uint32_t lo, uint32_t hi, size_t slot, size_t cap, EdgeTri* recs, TileRect* tiles,
            SubTriangles& scratch) -> int64_t {
            if (!batched) return -1;
            uint8_t any = 0;
            for (uint32_t t = lo; t < hi; ++t) any |= hint[t];
            if (any & kHintClip) return -1;
            uint32_t* const ones = scratch.ones;
            uint32_t n = 0;
            for (uint32_t t = lo; t < hi; ++t) {
                const uint8_t h = hint[t];
                const uint32_t one = (h & kHintOne) != 0;
                out.begin[t] = uint32_t(slot) + n;
                ones[n] = t;
                n += one;
                out.end[t] = uint32_t(slot) + n;
            }
            CULLIDE_CHECK(n == cap, "setupDrawn: a chunk's records differ from its count");
            for (uint32_t k = 0; k < n; ++k) enqueue(scratch, ones[k], hint[ones[k]], recs + k, tiles + k);
            flush(scratch);
            // Last, as the hints are the flags' array: 0 with one record, else the flags already.
            for (uint32_t t = lo; t < hi; ++t) hint[t] &= uint8_t(~(kHintOne | kHintCw));
            return n;
        });
}

void setupConservativeDrawn(const CommandList& list, const SetupInput& in, const WindowError& err,
                            RecordSet<ConsRec>& out) {
    drawnChunks(list, Command::Op::DrawConservative, out);
    auto countRange = [](uint32_t lo, uint32_t hi) -> size_t { return hi - lo; };
    buildRecords<NoScratch>(
        out, in.triangles.size(), in.grid, countRange,
        [&](uint32_t t, NoScratch&, auto&& emit, auto&&) -> uint8_t {
            const Triangle& tri = in.triangles[t];
            bool kept = false;
            emit([&](ConsRec& rec) {
                kept =
                    setupConservative(in.window[tri[0]], in.window[tri[1]], in.window[tri[2]], in.params, err, rec.t);
                if (kept) rec.e = consEdges(rec.t, in.params.subpixelBits);
                return kept;
            });
            return kept ? uint8_t(0) : uint8_t(kRejected);
        },
        [](NoScratch&) {},
        [](uint32_t, uint32_t, size_t, size_t, ConsRec*, TileRect*, NoScratch&) { return int64_t(-1); });
}

}  // namespace cullide::raster::detail
