// Broad phase on a uniform grid (the default; see broad_phase.h): every box goes into the cells
// it overlaps, the (cell, box) entries are radix-sorted, and each cell tests its boxes pairwise.
// A pair is reported by one cell only: the one holding the lower corner of the two boxes'
// intersection, which both boxes overlap. Boxes that would cover too many cells are tested
// against every box instead. Every pair of overlapping boxes is reported exactly once, in
// ascending (object, primitive) order.
#include "broad_phase.h"

#include "cullide/parallel.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <memory>
#include <stdexcept>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace cullide::oracle::detail {
namespace {

double seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

bool overlap(const Box& a, const Box& b) {
    return a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] && a.lo[2] <= b.hi[2] &&
        b.lo[2] <= a.hi[2];
}

constexpr uint32_t kMaxCellsPerBox = 64;  // beyond: tested against every box
constexpr uint64_t kDirectCells = uint64_t(1) << 18;  // a counting sort by cell up to this many cells
constexpr size_t kBatch = 1024;  // candidates handed to the callback at once
constexpr size_t kChunk = 256;  // a box's partners in a cell tested between flushes
constexpr uint32_t kIndexMask = (uint32_t(1) << 29) - 1;  // entries: cell << 32 | low axes << 29 | box

struct Grid {
    double origin[3];
    double inv;  // 1 / cell size
    uint32_t dims[3];
    // floor((x - origin) * inv), clamped to the grid: the truncation equals the floor where it
    // is kept (c > 0), and std::floor is a libm call on the x86-64 baseline.
    uint32_t cell(float x, int k) const {
        const double c = (double(x) - origin[k]) * inv;
        return c <= 0 ? 0 : c >= double(dims[k] - 1) ? dims[k] - 1 : uint32_t(c);
    }
    uint64_t key(uint32_t x, uint32_t y, uint32_t z) const { return (uint64_t(x) * dims[1] + y) * dims[2] + z; }
};

}  // namespace

namespace {

// Per-block counts of each top digit (blocks x 256, block-major) become each block's first write
// position for that digit, digits in order and blocks in order within a digit (so a scatter by
// blocks is stable); bucket[d] is digit d's first position, bucket[256] the total, returned.
size_t digitOffsets(std::vector<size_t>& counts, size_t blocks, std::array<size_t, 257>& bucket) {
    size_t sum = 0;
    for (size_t d = 0; d < 256; ++d) {
        bucket[d] = sum;
        for (size_t b = 0; b < blocks; ++b) {
            const size_t k = counts[b * 256 + d];
            counts[b * 256 + d] = sum;
            sum += k;
        }
    }
    bucket[256] = sum;
    return sum;
}

// Sorts the m values at `from` by the bits [32, 32 + 8 * lowPasses) (stable), leaving them in
// `from` when lowPasses is even and in `to` when odd (`to`: m values of scratch). LSD passes of
// one byte each; a small bucket (most of them on small meshes, where the 256 counters of each
// pass cost more than the values) by insertion, then copied where the passes would end.
void sortBucket(uint64_t* from, uint64_t* to, size_t m, int lowPasses) {
    if (lowPasses == 0 || m == 0) return;
    if (m <= 64) {
        const uint64_t mask = lowPasses >= 4 ? ~uint64_t(0) : (uint64_t(1) << (8 * lowPasses)) - 1;
        auto key = [&](uint64_t x) { return (x >> 32) & mask; };
        for (size_t i = 1; i < m; ++i) {
            const uint64_t x = from[i];
            size_t j = i;
            for (; j > 0 && key(from[j - 1]) > key(x); --j) from[j] = from[j - 1];
            from[j] = x;
        }
        if (lowPasses % 2 == 1) std::copy(from, from + m, to);
        return;
    }
    for (int p = 0; p < lowPasses; ++p) {
        const int shift = 32 + 8 * p;
        size_t c[256] = {};
        for (size_t i = 0; i < m; ++i) ++c[(from[i] >> shift) & 0xff];
        size_t at = 0;
        for (size_t& k : c) {
            const size_t x = k;
            k = at;
            at += x;
        }
        for (size_t i = 0; i < m; ++i) to[c[(from[i] >> shift) & 0xff]++] = from[i];
        std::swap(from, to);
    }
}

}  // namespace

uint64_t* radixSortHigh(uint64_t* v, uint64_t* tmp, size_t n, int keyBits) {
    const int passes = (keyBits + 7) / 8;
    if (passes == 0 || n < 2) return v;
    // The top digit first (MSD, in parallel over fixed blocks of the input: per-block counts,
    // then each block scatters to its own slots, so the pass is stable), then each of the 256
    // buckets on its own (LSD on the lower digits, stable, in cache): a stable sort on the
    // whole key whatever the thread count.
    constexpr size_t kBlock = size_t(1) << 15;
    const size_t blocks = (n + kBlock - 1) / kBlock;
    const int top = 32 + 8 * (passes - 1);
    std::vector<size_t> count(blocks * 256, 0);
    parallelForEach(0, blocks, [&](size_t b) {
        size_t* c = count.data() + b * 256;
        for (size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i) ++c[(v[i] >> top) & 0xff];
    });
    std::array<size_t, 257> bucket{};
    digitOffsets(count, blocks, bucket);
    parallelForEach(0, blocks, [&](size_t b) {
        size_t* c = count.data() + b * 256;
        for (size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i) tmp[c[(v[i] >> top) & 0xff]++] = v[i];
    });
    if (passes == 1) return tmp;
    // Every bucket takes passes - 1 more passes between tmp and v, so all end in the same array.
    parallelForEach(
        0, 256, [&](size_t d) { sortBucket(tmp + bucket[d], v + bucket[d], bucket[d + 1] - bucket[d], passes - 1); });
    return passes % 2 == 1 ? tmp : v;
}

namespace {

// The boxes of every object as one array, by global index g: objects one after another, primitives
// in order, so that g ascending is (object, primitive) ascending. One object (self-intersection):
// its boxes as they are.
struct JoinedBoxes {
    std::vector<size_t> offset;  // object o's first g
    std::vector<Box> joined;  // several objects: their boxes one after another
    std::vector<uint32_t> objectOf;  // several objects: per g, its object
    std::span<const Box> boxes;
    size_t n = 0;

    explicit JoinedBoxes(std::span<const std::span<const Box>> objects) : offset(objects.size() + 1, 0) {
        for (size_t o = 0; o < objects.size(); ++o) offset[o + 1] = offset[o] + objects[o].size();
        n = offset.back();
        if (n == 0) return;
        if (n > kIndexMask) throw std::length_error("grid broad phase: more than 2^29 boxes");
        if (objects.size() > 1) {
            joined.resize(n);
            objectOf.resize(n);
            for (size_t o = 0; o < objects.size(); ++o) {
                std::copy(objects[o].begin(), objects[o].end(), joined.begin() + std::ptrdiff_t(offset[o]));
                std::fill(objectOf.begin() + std::ptrdiff_t(offset[o]),
                          objectOf.begin() + std::ptrdiff_t(offset[o + 1]), uint32_t(o));
            }
        }
        boxes = objects.size() > 1 ? std::span<const Box>(joined) : objects[0];
    }
    JoinedBoxes(const JoinedBoxes&) = delete;  // `boxes` may point into `joined`
    JoinedBoxes& operator=(const JoinedBoxes&) = delete;

    Candidate candidate(size_t a, size_t b) const {  // a < b
        if (objectOf.empty()) return Candidate{0, uint32_t(a), 0, uint32_t(b)};
        const uint32_t oa = objectOf[a], ob = objectOf[b];
        return Candidate{oa, uint32_t(a - offset[oa]), ob, uint32_t(b - offset[ob])};
    }
};

// The grid: cells about the median box's largest extent; at most 2^32 cells. Bounds per fixed
// block, then combined in block order (min/max: the same whatever the threads).
Grid makeGrid(std::span<const Box> boxes, GridScratch& scratch) {
    const size_t n = boxes.size();
    constexpr size_t kBlock = 16384;
    const size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<std::array<double, 6>> blockBounds(blocks);
    Buffer<float>& extent = scratch.extent;
    extent.clear();
    extent.resize(n);
    parallelForEach(0, blocks, [&](size_t blk) {
        std::array<double, 6> bb{1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
        for (size_t g = blk * kBlock, e = std::min(n, g + kBlock); g < e; ++g) {
            const Box& b = boxes[g];
            for (int k = 0; k < 3; ++k)
                bb[k] = std::min(bb[k], double(b.lo[k])), bb[3 + k] = std::max(bb[3 + k], double(b.hi[k]));
            extent[g] = std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
        }
        blockBounds[blk] = bb;
    });
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (const auto& bb : blockBounds)
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], bb[k]), hi[k] = std::max(hi[k], bb[3 + k]);
    std::nth_element(extent.data(), extent.data() + n / 2, extent.data() + n);
    // 1.5 x the median extent: on bunny75k, 1 costs 10% more, 0.75 35% more, 0.5 sets most boxes
    // aside (over kMaxCellsPerBox cells); 2 and 2.5 cost the same within noise.
    double size = std::max(double(extent[n / 2]) * 1.5, 1e-30);
    if (!scratch.keep) Buffer<float>().swap(extent);
    Grid grid;
    for (;;) {
        double cells = 1;
        for (int k = 0; k < 3; ++k) cells *= std::floor((hi[k] - lo[k]) / size) + 1;
        if (cells < 0x1p31) break;
        size *= 1.25;
    }
    for (int k = 0; k < 3; ++k) grid.origin[k] = lo[k], grid.dims[k] = uint32_t(std::floor((hi[k] - lo[k]) / size) + 1);
    grid.inv = 1 / size;
    return grid;
}

// Calls out(entry) for each entry (cell << 32 | low axes << 29 | g) of box g in order; false
// (nothing called) when the box is set aside (over kMaxCellsPerBox cells).
template <typename Out>
inline bool forEachEntry(const Grid& grid, std::span<const Box> boxes, size_t g, Out&& out) {
    const Box& b = boxes[g];
    uint32_t l[3], h[3];
    uint64_t c = 1;
    for (int k = 0; k < 3; ++k) {
        l[k] = grid.cell(b.lo[k], k), h[k] = grid.cell(b.hi[k], k);
        c *= h[k] - l[k] + 1;
    }
    if (c > kMaxCellsPerBox) return false;
    // Bits 29-31: the axes on which this cell holds the box's lower corner.
    for (uint32_t x = l[0]; x <= h[0]; ++x)
        for (uint32_t y = l[1]; y <= h[1]; ++y)
            for (uint32_t z = l[2]; z <= h[2]; ++z) {
                const uint64_t low = uint64_t(x == l[0]) | uint64_t(y == l[1]) << 1 | uint64_t(z == l[2]) << 2;
                out(grid.key(x, y, z) << 32 | low << 29 | g);
            }
    return true;
}

// Few cells (up to kDirectCells; meshes up to ~100k triangles): the entries into scratch.entries,
// sorted by one counting sort by cell, serial, on the entries generated once (a 6k mesh spent a
// sixth of its time generating them twice and in the parallel passes' and the 256 buckets' fixed
// costs). Cells ascending, g ascending within a cell; boxes set aside into `big`.
void entriesByCounting(const Grid& grid, uint64_t cellCount, std::span<const Box> boxes, GridScratch& scratch,
                       std::vector<uint32_t>& big) {
    const size_t n = boxes.size();
    Buffer<uint64_t>& entryBuffer = scratch.entries;
    Buffer<uint64_t>& raw = scratch.raw;
    Buffer<uint32_t>& start = scratch.start;  // cell c's entries from start[c]
    start.assign(cellCount + 1, 0);
    // Written through local pointers (push_back reloaded and stored the vector's end for
    // every entry, which the counters might alias: 1-2% of the oracle on 5.8k-46k
    // triangles); room for a box's entries is made before each box.
    raw.clear();
    raw.resize(4 * n + kMaxCellsPerBox);
    size_t used = 0;
    uint64_t* out = raw.data();
    uint32_t* const counts = start.data() + 1;  // cell c's count at start[c + 1]
    for (size_t g = 0; g < n; ++g) {
        if (raw.size() - used < kMaxCellsPerBox) raw.resize(2 * raw.size()), out = raw.data();
        uint64_t* at = out + used;
        if (!forEachEntry(grid, boxes, g, [&](uint64_t entry) {
                *at++ = entry;
                ++counts[entry >> 32];
            }))
            big.push_back(uint32_t(g));
        used = size_t(at - out);
    }
    for (size_t c = 0; c < cellCount; ++c) start[c + 1] += start[c];
    entryBuffer.resize(used);
    for (size_t i = 0; i < used; ++i) entryBuffer[start[raw[i] >> 32]++] = raw[i];
    if (!scratch.keep) {
        Buffer<uint64_t>().swap(raw);  // the allocators swap too: each frees through its own
        Buffer<uint32_t>().swap(start);
    }
}

// Many cells: the entries into scratch.entries, sorted by key, g ascending within a cell; boxes
// set aside into `big`. The first pass of radixSortHigh (the top digit) is fused with the
// generation: each fixed block of boxes counts its entries per top digit, then writes them
// straight to their slots, so that the entries take one buffer (8 bytes each), not two plus a
// per-box offset (25 + 25 + 8 MB on a 1M-triangle bunny); the lower digits are sorted per bucket
// with a bucket-sized scratch. The order is radixSortHigh's on the entries in g order (stable: g
// ascending per cell). The top digit: the key's highest 8 bits (so that 256 buckets share the
// entries, and each bucket's scratch is small), then lowPasses bytes from bit 32 up for the rest.
void entriesByDigits(const Grid& grid, int keyBits, std::span<const Box> boxes, GridScratch& scratch,
                     std::vector<uint32_t>& big) {
    const size_t n = boxes.size();
    Buffer<uint64_t>& entryBuffer = scratch.entries;
    const int top = 32 + std::max(0, keyBits - 8), lowPasses = (top - 32 + 7) / 8;
    constexpr size_t kBoxBlock = 4096;
    const size_t boxBlocks = (n + kBoxBlock - 1) / kBoxBlock;
    std::vector<size_t> slots(boxBlocks * 256, 0);
    std::vector<std::vector<uint32_t>> blockBig(boxBlocks);
    parallelForEach(0, boxBlocks, [&](size_t blk) {
        size_t* c = slots.data() + blk * 256;
        for (size_t g = blk * kBoxBlock, e = std::min(n, g + kBoxBlock); g < e; ++g)
            if (!forEachEntry(grid, boxes, g, [&](uint64_t entry) { ++c[(entry >> top) & 0xff]; }))
                blockBig[blk].push_back(uint32_t(g));
    });
    for (const auto& bb : blockBig) big.insert(big.end(), bb.begin(), bb.end());
    blockBig = {};
    std::array<size_t, 257> bucket{};
    const size_t entryCount = digitOffsets(slots, boxBlocks, bucket);
    // Not value-initialised (every element is written): the parallel loop touches it first.
    entryBuffer.resize(entryCount);
    uint64_t* const entries = entryBuffer.data();
    parallelForEach(0, boxBlocks, [&](size_t blk) {
        size_t* c = slots.data() + blk * 256;
        for (size_t g = blk * kBoxBlock, e = std::min(n, g + kBoxBlock); g < e; ++g)
            forEachEntry(grid, boxes, g, [&](uint64_t entry) { entries[c[(entry >> top) & 0xff]++] = entry; });
    });
    slots = {};
    parallelForEach(0, 256, [&](size_t d) {
        const size_t m = bucket[d + 1] - bucket[d];
        if (m < 2 || lowPasses == 0) return;
        std::unique_ptr<uint64_t[]> tmp(new uint64_t[m]);
        sortBucket(entries + bucket[d], tmp.get(), m, lowPasses);
        if (lowPasses % 2 == 1) std::copy(tmp.get(), tmp.get() + m, entries + bucket[d]);
    });
}

// Each cell's boxes are copied next to each other when the cell is tested (in cache), with the
// axes on which the cell is the box's lower corner's cell: a pair's owner cell (the larger lower
// cell on each axis, cell() being monotone) is this cell iff on every axis one of the two starts
// here. The corners as 4 floats each (the 4th 0 in both), so that a pair's six comparisons are
// two 4-wide ones where SSE is there (the pair loop was a sixth of the oracle on small meshes).
struct PackedBox {
    float lo[4], hi[4];
    uint32_t g, low;  // low: bit k when the box's lower corner is in this cell along k
};

// Whether a and b overlap (closed boxes).
inline bool overlapping(const PackedBox& a, const PackedBox& b) {
#if defined(__SSE__)
    const __m128 le0 = _mm_cmple_ps(_mm_loadu_ps(a.lo), _mm_loadu_ps(b.hi));
    const __m128 le1 = _mm_cmple_ps(_mm_loadu_ps(b.lo), _mm_loadu_ps(a.hi));
    return _mm_movemask_ps(_mm_and_ps(le0, le1)) == 15;
#else
    return (a.lo[0] <= b.hi[0]) & (b.lo[0] <= a.hi[0]) & (a.lo[1] <= b.hi[1]) & (b.lo[1] <= a.hi[1]) &
        (a.lo[2] <= b.hi[2]) & (b.lo[2] <= a.hi[2]);
#endif
}

// Every cell's pairs that the cell owns, to fn in batches. The cells: each fixed block of entries
// takes the cells that start in it (to their end).
void testCells(const JoinedBoxes& all, const Buffer<uint64_t>& entryBuffer, CandidateFn fn, void* user) {
    const size_t entryCount = entryBuffer.size();
    const uint64_t* const entries = entryBuffer.data();
    const std::span<const Box> boxes = all.boxes;
    constexpr size_t kEntryBlock = 2048;
    const size_t entryBlocks = (entryCount + kEntryBlock - 1) / kEntryBlock;
    auto cellStart = [&](size_t i) { return i == 0 || i >= entryCount || entries[i] >> 32 != entries[i - 1] >> 32; };
    parallelFor(0, entryBlocks, 1, [&](const tbb::blocked_range<size_t>& r) {
        // Branch-free inner loop: a pair's test is hard to predict (22-29% pass on the bundled
        // meshes), so every pair is written and the write position advances only on a hit.
        std::array<std::array<uint32_t, 2>, kBatch> hits;
        std::array<Candidate, kBatch> batch;
        size_t count = 0;
        auto flush = [&] {
            for (size_t k = 0; k < count; ++k) batch[k] = all.candidate(hits[k][0], hits[k][1]);
            fn(user, batch.data(), uint32_t(count));
            count = 0;
        };
        std::vector<PackedBox> packed;
        size_t begin = r.begin() * kEntryBlock;
        const size_t stop = std::min(entryCount, r.end() * kEntryBlock);
        while (begin < stop && !cellStart(begin)) ++begin;
        while (begin < stop) {
            size_t end = begin + 1;
            while (!cellStart(end)) ++end;
            const size_t e = end - begin, cellFirst = begin;
            begin = end;
            if (e < 2) continue;
            packed.resize(e);
            for (size_t i = 0; i < e; ++i) {
                const uint32_t g = uint32_t(entries[cellFirst + i]) & kIndexMask;
                const Box& b = boxes[g];
                packed[i] = {{b.lo[0], b.lo[1], b.lo[2], 0},
                             {b.hi[0], b.hi[1], b.hi[2], 0},
                             g,
                             uint32_t(entries[cellFirst + i] >> 29) & 7};
            }
            for (size_t i = 0; i + 1 < e; ++i) {
                const PackedBox& ea = packed[i];
                for (size_t from = i + 1; from < e; from += kChunk) {
                    const size_t to = std::min(e, from + kChunk);
                    if (count + (to - from) > kBatch) flush();  // room for every pair of the chunk
                    for (size_t j = from; j < to; ++j) {
                        const PackedBox& eb = packed[j];
                        const bool hit = ((ea.low | eb.low) == 7) & overlapping(ea, eb);
                        hits[count] = {ea.g, eb.g};
                        count += hit;
                    }
                }
            }
        }
        if (count > 0) flush();
    });
}

// Boxes sorted by their lower x (value, box), for the sweeps of the boxes set aside.
std::vector<std::pair<double, uint32_t>> byLowerX(std::span<const Box> boxes, std::span<const uint32_t> which) {
    std::vector<std::pair<double, uint32_t>> out;
    out.reserve(which.size());
    for (uint32_t g : which) out.push_back({double(boxes[g].lo[0]), g});
    std::sort(out.begin(), out.end());
    return out;
}

// The boxes set aside, against every other box (a pair of two such boxes once). Not against all n
// boxes each: the grid's boxes span at most kMaxCellsPerBox cells, so their widths along x are
// bounded by the widest of them, and a set-aside box meets only those whose lower x lies within
// that width of its own interval (a binary search in the grid's boxes sorted by lower x); the set-
// aside boxes meet each other in a sweep along x. On a scene of large and small triangles (two
// cows of 5.8k triangles around a 75k bunny: the cows' boxes set aside) this tests a few percent
// of the pairs that every-box-against-all tested.
void testSetAside(const JoinedBoxes& all, const std::vector<uint32_t>& big, CandidateFn fn, void* user) {
    const size_t n = all.n;
    const std::span<const Box> boxes = all.boxes;
    std::vector<char> isBig(n, 0);
    for (uint32_t g : big) isBig[g] = 1;
    std::vector<uint32_t> held;  // the grid's boxes
    held.reserve(n - big.size());
    double widest = 0;  // in double, with room to spare: the search may only take too many
    for (size_t g = 0; g < n; ++g)
        if (!isBig[g]) held.push_back(uint32_t(g)), widest = std::max(widest, double(boxes[g].hi[0]) - boxes[g].lo[0]);
    widest *= 1.001;
    const std::vector<std::pair<double, uint32_t>> heldByX = byLowerX(boxes, held), bigByX = byLowerX(boxes, big);
    parallelFor(0, bigByX.size(), 16, [&](const tbb::blocked_range<size_t>& r) {
        std::vector<Candidate> batch;
        batch.reserve(kBatch);
        const auto emit = [&](uint32_t a, uint32_t b) {
            if (!overlap(boxes[a], boxes[b])) return;
            batch.push_back(a < b ? all.candidate(a, b) : all.candidate(b, a));
            if (batch.size() == kBatch) fn(user, batch.data(), uint32_t(batch.size())), batch.clear();
        };
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const uint32_t a = bigByX[i].second;
            const Box& box = boxes[a];
            // Held boxes with lower x in [lo - widest, hi]: the only ones whose x-interval can meet a's.
            auto it = std::lower_bound(heldByX.begin(), heldByX.end(), std::pair{box.lo[0] - widest, uint32_t(0)});
            const double hiX = box.hi[0];
            for (; it != heldByX.end() && it->first <= hiX; ++it) emit(a, it->second);
            // Set-aside boxes after a in x order whose lower x is within a's interval (each pair once).
            for (size_t j = i + 1; j < bigByX.size() && bigByX[j].first <= hiX; ++j) emit(a, bigByX[j].second);
        }
        if (!batch.empty()) fn(user, batch.data(), uint32_t(batch.size()));
    });
}

}  // namespace

BroadPhaseTimes collideGrid(std::span<const std::span<const Box>> objects, CandidateFn fn, void* user,
                            GridScratch& scratch) {
    BroadPhaseTimes times;
    auto t0 = std::chrono::steady_clock::now();
    const JoinedBoxes all(objects);
    if (all.n == 0) return times;
    const Grid grid = makeGrid(all.boxes, scratch);
    const uint64_t cellCount = uint64_t(grid.dims[0]) * grid.dims[1] * grid.dims[2];
    int keyBits = 0;
    while (keyBits < 32 && (uint64_t(1) << keyBits) < cellCount) ++keyBits;
    // Entries (key << 32 | low << 29 | g), sorted by key, g ascending within a cell (the pair
    // loop reports (a, b) with a < b); boxes over too many cells set aside.
    std::vector<uint32_t> big;
    scratch.entries.clear();
    if (cellCount <= kDirectCells) entriesByCounting(grid, cellCount, all.boxes, scratch, big);
    else entriesByDigits(grid, keyBits, all.boxes, scratch, big);
    times.buildSeconds = seconds(t0);

    t0 = std::chrono::steady_clock::now();
    testCells(all, scratch.entries, fn, user);
    if (!big.empty()) testSetAside(all, big, fn, user);
    if (!scratch.keep) Buffer<uint64_t>().swap(scratch.entries);
    times.collideSeconds = seconds(t0);
    return times;
}

}  // namespace cullide::oracle::detail
