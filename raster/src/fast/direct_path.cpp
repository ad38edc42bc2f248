// The direct path of the CPU backend (direct_path.h).
#include "fast/direct_path.h"

#include "cullide/parallel.h"

#include <algorithm>
#include <cstring>

namespace cullide::raster::detail {

bool directEligible(const CommandList& list) {
    std::vector<uint64_t> ranges;
    for (const Command& c : list.commands()) {
        if (c.op == Command::Op::DrawConservative || c.op == Command::Op::ClearIntervals) return false;
        if (c.op == Command::Op::Draw && c.count > 0) ranges.push_back(uint64_t(c.first) << 32 | c.count);
    }
    std::sort(ranges.begin(), ranges.end());
    return std::adjacent_find(ranges.begin(), ranges.end()) == ranges.end();
}

bool smallTriangles(const CommandList& list, std::span<const Triangle> triangles, const SnapVertex* snapped,
                    int subpixelBits) {
    uint64_t drawn = 0;
    for (const Command& c : list.commands())
        if (c.op == Command::Op::Draw) drawn += c.count;
    if (drawn == 0) return false;
    // About kSamples triangles evenly spread over the drawn ones.
    constexpr uint64_t kSamples = 64;
    const uint64_t step = std::max<uint64_t>(1, drawn / kSamples);
    const int64_t twoPixels = int64_t(2) << subpixelBits;
    uint64_t sampled = 0, small = 0, at = 0;
    for (const Command& c : list.commands()) {
        if (c.op != Command::Op::Draw) continue;
        for (uint64_t k = (step - at % step) % step; k < c.count; k += step) {
            const Triangle& t = triangles[c.first + k];
            const SnapVertex &a = snapped[t[0]], &b = snapped[t[1]], &d = snapped[t[2]];
            ++sampled;
            small += a.inside && b.inside && d.inside &&
                std::max({a.x, b.x, d.x}) - int64_t(std::min({a.x, b.x, d.x})) < twoPixels &&
                std::max({a.y, b.y, d.y}) - int64_t(std::min({a.y, b.y, d.y})) < twoPixels;
        }
        at += c.count;
    }
    return 4 * small >= 3 * sampled;
}

namespace {

// What one draw adds to the statistics.
struct DrawCounts {
    uint64_t fragments = 0, passed = 0, rejected = 0, clipped = 0, zeroArea = 0;
};

// The list's constants for both steps of a block.
struct Direct {
    const SetupInput& in;
    SetupParams params;
    const RasterTable& table;
    int width, height, bits;
    bool isFloat, batched;

    Direct(const SetupInput& input, const RasterTable& t, const DepthFormat& format)
        : in(input),
          params(input.params),
          table(t),
          width(params.width),
          height(params.height),
          bits(format.bits),
          isFloat(format.kind == DepthFormat::Kind::Float32),
          batched(input.simd && haveSetupAvx2()) {
        params.dropEmpty = true;  // as setupDrawn
    }

    // Counts and sets up triangles [b.lo, b.hi): the one-record triangles' small forms (or
    // records), eight at a time while the groups allow (setupSmallGroup8), then four at a time as
    // setupDrawn does; the clipped ones noted, the others' flags counted. Reads only the geometry:
    // blocks may be prepared in parallel.
    void prepareBlock(Block& b) const {
        const SetupInput& g = in;
        uint32_t t = b.lo, n = 0;
        uint64_t rejected = 0, zeroArea = 0;
        // Groups of eight small triangles (and triangles without a record), counted and set up at
        // once, while they last: a block of ~1 px triangles is these groups alone.
        if (batched)
            for (SmallGroup got; t + 8 <= b.hi; t += 8) {
                const SmallOut forms{b.small + n, size_t(width), bits, isFloat};
                if (!setupSmallGroup8(&g.triangles[t], g.window.data(), g.snapped.data(), params, forms, got)) break;
                n += got.forms;
                rejected += got.rejected;
                zeroArea += got.zeroArea;
            }
        // The rest counted, then set up four at a time: batch slot m holds the triangle of record
        // n0 + m.
        const uint32_t t0 = t, n0 = n;
        countHints(g.triangles, g.snapped.data(), params, batched, t0, b.hi, b.hint);
        uint32_t clips = 0;
        for (; t < b.hi; ++t) {
            const uint32_t m = n - n0;
            // Eight one-record triangles starting a batch (the common case of small triangles):
            // two whole batches, without the flags' bookkeeping.
            constexpr uint64_t kBytes = 0x0101010101010101;
            uint64_t h8 = 0;
            if (m % 4 == 0 && t + 8 <= b.hi) std::memcpy(&h8, &b.hint[t - t0], 8);
            if ((h8 & kBytes * (kHintOne | kHintClip)) == kBytes * kHintOne) {
                for (uint32_t q = 0; q < 8; ++q) {
                    InsideBatch& batch = b.batch[m / 4 + q / 4];
                    const Triangle& tri = g.triangles[t + q];
                    for (int k = 0; k < 3; ++k) batch.v[k][q % 4] = tri[k];
                    batch.clockwise[q % 4] = h8 >> (8 * q) & kHintCw ? -1 : 0;
                }
                n += 8;
                t += 7;
                continue;
            }
            // A triangle without a record is written to the next lane too, which the next one overwrites.
            const uint8_t h = b.hint[t - t0];
            InsideBatch& batch = b.batch[m / 4];
            for (int k = 0; k < 3; ++k) batch.v[k][m % 4] = g.triangles[t][k];
            batch.clockwise[m % 4] = h & kHintCw ? -1 : 0;
            if (h & kHintClip) {
                b.clipAt[clips][0] = t;
                b.clipAt[clips++][1] = n;
            }
            const bool none = (h & (kHintOne | kHintClip)) == 0;  // the hint is the flags
            rejected += none & ((h & kRejected) != 0);
            zeroArea += none & ((h & kZeroArea) != 0);
            n += (h & kHintOne) != 0;
        }
        b.n = n;
        b.clips = clips;
        b.rejected = rejected;
        b.zeroArea = zeroArea;
        // The four-wide setup makes the small forms too; the scalar step's records (at most three
        // a block without AVX2's setup, all of them without) keep the pixel loop.
        uint32_t k = 0;
        if (batched)
            for (; k + 4 <= n - n0; k += 4) {
                EdgeTri* const r = b.recs + n0 + k;
                EdgeTri* const out[4] = {r, r + 1, r + 2, r + 3};
                const SmallOut forms{b.small + n0 + k, size_t(width), bits, isFloat};
                setupInsideEdgeTri4(b.batch[k / 4], g.window.data(), g.snapped.data(), params, out, &forms);
            }
        for (; k < n - n0; ++k) {
            setupInsideLane(b.batch[k / 4], int(k % 4), g.window.data(), g.snapped.data(), params, b.recs[n0 + k]);
            b.small[n0 + k].lanes = kNotSmall;
        }
    }

    // Rasterizes a prepared block into `depth` in triangle order: the records between the clipped
    // triangles, and their sub-triangles.
    void runBlock(const Block& b, DepthFunc func, bool mask, uint32_t* depth, DrawCounts& counts) const {
        const RasterFn raster = table.raster[size_t(func)];
        const RunRecordsFn runRecords = table.runRecords[size_t(func)];
        const int W = width, H = height;
        FragGroup* noRecording = nullptr;  // the raster loops record nothing
        counts.rejected += b.rejected;
        counts.zeroArea += b.zeroArea;
        uint32_t done = 0;
        for (uint32_t m = 0;; ++m) {
            const uint32_t upTo = m < b.clips ? b.clipAt[m][1] : b.n;
            runRecords(b.recs + done, b.small + done, upTo - done, raster, W, H, depth, size_t(W), mask, bits,
                       counts.fragments, counts.passed);
            done = upTo;
            if (m == b.clips) break;
            const Triangle& tri = in.triangles[b.clipAt[m][0]];
            SnappedTri sub[kMaxSubTriangles];
            int count = 0;
            const uint8_t flags =
                setupTriangle(in.window[tri[0]], in.window[tri[1]], in.window[tri[2]], params, sub, count);
            counts.rejected += (flags & kRejected) != 0;
            counts.clipped += (flags & kClipped) != 0;
            counts.zeroArea += (flags & kZeroArea) != 0;
            for (int s = 0; s < count; ++s) {
                EdgeTri e;
                if (makeEdgeTri(sub[s], params, e))
                    raster(e, 0, 0, W - 1, H - 1, depth, size_t(W), mask, bits, counts.fragments, counts.passed,
                           noRecording);
            }
        }
    }
};

// The list's commands in order, a draw block by block: the state walk, clears, statistics and
// query counts, as executeDirect's callers see them.
class Walk {
public:
    Walk(const Direct& d, const DepthFormat& format, PipelineState& state, uint32_t* depth, RasterStats& stats,
         size_t queries)
        : d_(d), format_(format), depth_(depth), stats_(stats), walk_(state, queries), results_(queries, 0) {}

    // A command other than a draw.
    void command(const Command& c) {
        if (walk_.apply(c)) return;
        if (c.op == Command::Op::Clear)
            std::fill_n(depth_, size_t(d_.width) * size_t(d_.height), encodeDepth(c.clearDepth, format_));
        // directEligible: no conservative commands
    }
    // Draw c's next block (none for an empty draw), the first and the last of the draw flagged.
    void draw(const Command& c, const Block* b, bool first, bool last) {
        if (first) {
            ++stats_.draws;
            stats_.triangles += c.count;
            counts_ = DrawCounts{};
        }
        if (b) d_.runBlock(*b, walk_.func(), walk_.mask(), depth_, counts_);
        if (!last) return;
        stats_.rejected += counts_.rejected;
        stats_.clipped += counts_.clipped;
        stats_.zeroArea += counts_.zeroArea;
        stats_.fragments += counts_.fragments;
        stats_.passed += counts_.passed;
        if (walk_.query() >= 0) results_[size_t(walk_.query())] += counts_.passed;
    }
    std::vector<uint64_t> finish() {
        walk_.finish(results_);
        return std::move(results_);
    }

private:
    const Direct& d_;
    const DepthFormat& format_;
    uint32_t* depth_;
    RasterStats& stats_;
    StateWalker walk_;
    std::vector<uint64_t> results_;
    DrawCounts counts_;
};

}  // namespace

std::vector<uint64_t> executeDirect(const CommandList& list, const SetupInput& in, const RasterTable& table,
                                    const DepthFormat& format, PipelineState& state, uint32_t* depth,
                                    RasterStats& stats, int threads, DirectScratch* scratch) {
    const Direct d(in, table, format);
    Walk walk(d, format, state, depth, stats, list.queryCount());
    // Blocks prepared at once: 32 per thread, at most 256 (4.5 MiB), for enough work between a
    // fork and its join (8 per thread gave two threads no gain over one).
    const uint32_t batch = threads > 1 ? uint32_t(std::min(32 * threads, 256)) : 1;
    DirectScratch own;
    std::vector<Block>& blocks = (scratch ? *scratch : own).blocks;
    if (blocks.size() < batch) blocks.resize(batch);
    for (const Command& c : list.commands()) {
        if (c.op != Command::Op::Draw) {
            walk.command(c);
            continue;
        }
        if (c.count == 0) walk.draw(c, nullptr, true, true);
        const uint32_t end = c.first + c.count;
        for (uint32_t lo = c.first; lo < end;) {
            uint32_t n = 0;
            for (; n < batch && lo < end; ++n, lo = blocks[n - 1].hi) {
                blocks[n].lo = lo;
                blocks[n].hi = std::min(end, lo + kBlock);
            }
            if (n == 1) d.prepareBlock(blocks[0]);
            else parallelForEach(0, n, [&](size_t k) { d.prepareBlock(blocks[k]); });
            for (uint32_t k = 0; k < n; ++k) walk.draw(c, &blocks[k], blocks[k].lo == c.first, blocks[k].hi == end);
        }
    }
    return walk.finish();
}

}  // namespace cullide::raster::detail
