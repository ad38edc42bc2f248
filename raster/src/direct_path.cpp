// The direct path of the CPU backend (direct_path.h).
#include "direct_path.h"

#include <algorithm>

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

std::vector<uint64_t> executeDirect(const CommandList& list, const SetupInput& in, const RasterTable& table,
                                    const DepthFormat& format, PipelineState& state, uint32_t* depth,
                                    RasterStats& stats) {
    std::vector<uint64_t> results(list.queryCount(), 0);
    StateWalker walk(state, list.queryCount());
    SetupParams params = in.params;
    params.dropEmpty = true;  // as setupDrawn
    const int W = params.width, H = params.height, bits = format.bits;
    const bool isFloat = format.kind == DepthFormat::Kind::Float32;
    const bool batched = in.simd && haveSetupAvx2();
    // A block's records: 12 KiB, and their small forms 3 KiB, in the L1 cache while they are rasterized.
    constexpr uint32_t kBlock = 128;
    uint8_t hint[kBlock];
    InsideBatch batch[kBlock / 4];
    EdgeTri recs[kBlock];
    SmallFrags small[kBlock];
    uint32_t clipAt[kBlock][2];  // the block's clipped triangles: triangle, records before it
    SnappedTri sub[kMaxSubTriangles];
    FragGroup* noRecording = nullptr;  // the raster loops record nothing
    for (const Command& c : list.commands()) {
        if (walk.apply(c)) continue;
        if (c.op == Command::Op::Clear) {
            std::fill_n(depth, size_t(W) * size_t(H), encodeDepth(c.clearDepth, format));
            continue;
        }
        if (c.op != Command::Op::Draw) continue;  // directEligible: no conservative commands
        ++stats.draws;
        stats.triangles += c.count;
        const RasterFn raster = table.raster[size_t(walk.func())];
        const RunRecordsFn runRecords = table.runRecords[size_t(walk.func())];
        const bool mask = walk.mask();
        uint64_t fragments = 0, passed = 0, rejected = 0, clipped = 0, zeroArea = 0;
        const uint32_t end = c.first + c.count;
        for (uint32_t lo = c.first; lo < end; lo += kBlock) {
            const uint32_t hi = std::min(end, lo + kBlock);
            countHints(in.triangles, in.snapped.data(), params, batched, lo, hi, hint);
            // The one-record triangles, set up four at a time as setupDrawn does (a triangle
            // without a record is written to the next lane too, which the next one overwrites);
            // the clipped ones noted, the others' flags counted.
            uint32_t n = 0, clips = 0;
            for (uint32_t t = lo; t < hi; ++t) {
                const uint8_t h = hint[t - lo];
                InsideBatch& b = batch[n / 4];
                for (int k = 0; k < 3; ++k) b.v[k][n % 4] = in.triangles[t][k];
                b.clockwise[n % 4] = h & kHintCw ? -1 : 0;
                if (h & kHintClip) {
                    clipAt[clips][0] = t;
                    clipAt[clips++][1] = n;
                }
                const bool none = (h & (kHintOne | kHintClip)) == 0;  // the hint is the flags
                rejected += none & ((h & kRejected) != 0);
                zeroArea += none & ((h & kZeroArea) != 0);
                n += (h & kHintOne) != 0;
            }
            // With the pixel loops' preparation (AVX2), the four-wide setup makes the small forms
            // too; the scalar step's records are prepared from the records.
            uint32_t k = 0;
            if (batched)
                for (; k + 4 <= n; k += 4) {
                    EdgeTri* const out[4] = {&recs[k], &recs[k + 1], &recs[k + 2], &recs[k + 3]};
                    const SmallOut forms{small + k, size_t(W), bits, isFloat};
                    setupInsideEdgeTri4(batch[k / 4], in.window.data(), in.snapped.data(), params, out,
                                        table.prepare ? &forms : nullptr);
                }
            const uint32_t scalarFrom = k;
            for (; k < n; ++k)
                setupInsideLane(batch[k / 4], int(k % 4), in.window.data(), in.snapped.data(), params, recs[k]);
            if (table.prepare) table.prepare(recs + scalarFrom, n - scalarFrom, size_t(W), bits, small + scalarFrom);
            // In triangle order: the records between the clipped triangles, and their sub-triangles.
            uint32_t done = 0;
            for (uint32_t m = 0; m <= clips; ++m) {
                const uint32_t upTo = m < clips ? clipAt[m][1] : n;
                runRecords(recs + done, small + done, upTo - done, raster, W, H, depth, size_t(W), mask, bits,
                           fragments, passed);
                done = upTo;
                if (m == clips) break;
                const Triangle& tri = in.triangles[clipAt[m][0]];
                int count = 0;
                const uint8_t flags =
                    setupTriangle(in.window[tri[0]], in.window[tri[1]], in.window[tri[2]], params, sub, count);
                rejected += (flags & kRejected) != 0;
                clipped += (flags & kClipped) != 0;
                zeroArea += (flags & kZeroArea) != 0;
                for (int s = 0; s < count; ++s) {
                    EdgeTri e;
                    if (makeEdgeTri(sub[s], params, e))
                        raster(e, 0, 0, W - 1, H - 1, depth, size_t(W), mask, bits, fragments, passed, noRecording);
                }
            }
        }
        stats.rejected += rejected;
        stats.clipped += clipped;
        stats.zeroArea += zeroArea;
        stats.fragments += fragments;
        stats.passed += passed;
        if (walk.query() >= 0) results[size_t(walk.query())] += passed;
    }
    walk.finish(results);
    return results;
}

}  // namespace cullide::raster::detail
