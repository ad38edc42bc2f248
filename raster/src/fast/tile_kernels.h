// The per-tile work of the fast path of the CPU backend (cpu_backend.cpp, step 6): the pixel
// loops (scalar and AVX2, chosen at run time; the conservative loop) and the walk of one tile's
// events. Private to raster/.
#pragma once

#include "fast/binning.h"
#include "fast/frag_cache.h"
#include "fast/records.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace cullide::raster::detail {

using RasterFn = void (*)(const EdgeTri&, int, int, int, int, uint32_t*, size_t, bool, int, uint64_t&, uint64_t&,
                          FragGroup*&);
using ReplayFn = void (*)(const FragGroup*, const FragGroup*, uint32_t*, bool, uint64_t&, uint64_t&);

// runRecords(records, small, n, raster, width, height, depth, stride, mask, bits, fragments,
// passed): records [0, n) in order over the whole viewport, those with a small form
// (SmallFrags, from setupInsideEdgeTri4) from it, the others through `raster` (the same depth
// function's pixel loop); the same fragments, tests and writes as the pixel loop on every record.
// The scalar loops' form reads no small forms.
using RunRecordsFn = void (*)(const EdgeTri*, const SmallFrags*, uint32_t, RasterFn, int, int, uint32_t*, size_t, bool,
                              int, uint64_t&, uint64_t&);

// The pixel loops for one CPU and depth format, indexed by DepthFunc: rasterizing (raster),
// rasterizing and recording (record), replaying (replay), the direct path's runs of records
// (runRecords).
struct RasterTable {
    std::array<RasterFn, 8> raster, record;
    std::array<ReplayFn, 8> replay;
    std::array<RunRecordsFn, 8> runRecords;
};

// The hot loops for this CPU: AVX2 when asked for and present, else the scalar loops.
RasterTable pickRasterTable(bool isFloat, bool simd);

struct QueryCount {
    uint32_t query;
    uint64_t count;
};

// Per-tile results, padded against false sharing.
struct alignas(64) TileOut {
    std::vector<QueryCount> queries;  // sparse, in query order
    uint64_t fragments = 0, passed = 0;
};

// What the tiles read and write.
struct TileJob {
    const EventList& events;
    const RecordSet<EdgeTri>& plain;
    const RecordSet<ConsRec>& conservative;
    const RasterTable& table;
    const DepthFormat& format;
    int width, height;
    TileGrid grid;
    uint32_t* depth;  // width x height
    uint32_t* ilo;  // the interval buffer (conservative lists only)
    uint32_t* ihi;
};

// Adds `n` passed samples to query `query` (none: -1) in the tile's sparse list (in query order).
void countQuery(TileOut& out, int32_t query, uint64_t n);

// What runTile notes for a capture (view_cache.h): per record of the tile's list, in list order,
// its recorded groups [groupBegin, groupEnd) in the FragCache. ok: every record so far was
// rasterized with recording when first met, in list order (else the capture rasterizes the tile
// again).
struct TileCapture {
    std::vector<uint32_t> groupBegin, groupEnd;
    bool ok = true;
};

// Runs tile `tile`'s events in order into the buffers, its counts into `out`. For a draw it finds
// the draw's records in the tile's list by galloping from the previous position (cheap for
// reducePCS's runs of neighbouring and repeated ranges) and rasterizes them clipped to the tile,
// recording the fragments in `cache` (the thread's); a later draw of the same records in the
// tile replays them.
// With `capture`, notes each record's recorded groups there.
void runTile(const TileJob& job, size_t tile, FragCache& cache, TileOut& out, TileCapture* capture = nullptr);

}  // namespace cullide::raster::detail
