// The direct path of the CPU backend: a command list run in order, each triangle set up and
// rasterized over the whole viewport as it comes, with no records, bins or tiles. Private to
// raster/.
//
// With one thread the tiles buy no parallelism; what they cost is every record written (96
// bytes a triangle), binned, and read back scattered through memory, tile by tile. Here a block
// of triangles is counted and set up into a small array that stays in the cache, then rasterized
// at once. The same setup (records.h: countHints, setupInsideEdgeTri4, setupTriangle), the same
// pixel loops (tile_kernels.h) over the viewport instead of a tile, the same order of fragments
// at every pixel (command order, then triangle order, then sub-triangle order), so the same
// depth buffer, query results and statistics bit for bit. It re-rasterizes a range drawn again
// where the tiles replay it (frag_cache.h), so the backend takes it only for lists that draw
// every range once (directEligible).
//
// A record whose pixel box is at most 2 x 2 (most, for triangles of about a pixel) is not
// rasterized by the pixel loop: the four-wide setup computes its fragments and depth codes from
// its lanes (SmallFrags) and writes no record, and runRecords only tests and writes them in order,
// without a branch on their outcome. On several threads blocks are set up in parallel and
// rasterized by the calling thread, for lists of small triangles (smallTriangles).
#pragma once

#include "command_state.h"
#include "fast/records.h"
#include "fast/tile_kernels.h"

#include "cullide/raster/cpu_options.h"

#include <cstdint>
#include <span>
#include <vector>

namespace cullide::raster::detail {

// Whether `list` suits the direct path: plain draws only (no conservative draw or interval
// clear), and no range drawn twice (nothing to replay).
bool directEligible(const CommandList& list);

// A block of a draw's triangles [lo, hi) (at most kBlock): prepareBlock's results for runBlock.
// Its records 12 KiB, their small forms 3 KiB: in the L1 cache while they are rasterized.
inline constexpr uint32_t kBlock = 128;
struct Block {
    uint32_t lo = 0, hi = 0;
    uint32_t n = 0;  // records
    uint32_t clips = 0;  // clipped triangles
    uint64_t rejected = 0, zeroArea = 0;  // of the triangles without a record
    uint8_t hint[kBlock];
    InsideBatch batch[kBlock / 4];
    EdgeTri recs[kBlock];
    SmallFrags small[kBlock];
    uint32_t clipAt[kBlock][2];  // the clipped triangles: triangle, records before it
};

// The blocks prepared in parallel, kept by the backend from list to list (fresh pages cost more
// than the work on them).
struct DirectScratch {
    std::vector<Block> blocks;
};

// Whether most of the triangles `list` draws are small: of about 64 spread over them, three in four
// or more have snapped vertices inside the clip volume less than two pixels apart on each axis.
// With several threads the direct path is taken for such lists only: its blocks are set up in
// parallel but rasterized by one thread, which for larger triangles (rasterizing most of the
// work) would leave the other threads idle where the tiles rasterize in parallel.
bool smallTriangles(const CommandList& list, std::span<const Triangle> triangles, const SnapVertex* snapped,
                    int subpixelBits);

// Runs `list` on the direct path into `depth` (params.width x params.height), adding to `stats`
// (zeroed by the caller); returns the query results. With `threads` > 1 (the caller's task arena),
// a draw's blocks are counted and set up in parallel, a batch of them at a time, then rasterized
// in order by the calling thread (which keeps the depth buffer in its cache): the same results as
// on one thread. `scratch`: the batch's blocks (null: the call's own).
std::vector<uint64_t> executeDirect(const CommandList& list, const SetupInput& in, const RasterTable& table,
                                    const DepthFormat& format, PipelineState& state, uint32_t* depth,
                                    RasterStats& stats, int threads = 1, DirectScratch* scratch = nullptr);

}  // namespace cullide::raster::detail
