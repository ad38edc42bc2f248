// The direct path of the CPU backend: a command list run in order on one thread, each triangle set
// up and rasterized over the whole viewport as it comes, with no records, bins or tiles. Private
// to raster/.
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
#pragma once

#include "command_state.h"
#include "records.h"
#include "tile_kernels.h"

#include "cullide/raster/cpu_backend.h"

#include <cstdint>
#include <vector>

namespace cullide::raster::detail {

// Whether `list` suits the direct path: plain draws only (no conservative draw or interval
// clear), and no range drawn twice (nothing to replay).
bool directEligible(const CommandList& list);

// Runs `list` on the direct path into `depth` (params.width x params.height), adding to `stats`
// (zeroed by the caller); returns the query results.
std::vector<uint64_t> executeDirect(const CommandList& list, const SetupInput& in, const RasterTable& table,
                                    const DepthFormat& format, PipelineState& state, uint32_t* depth,
                                    RasterStats& stats);

}  // namespace cullide::raster::detail
