// Triangle records for the fast path of the CPU backend (cpu_backend.cpp, steps 2-4): every
// triangle drawn by a command list set up once (triangle_setup.h, conservative.h), the records
// compacted in triangle order and binned to tiles. Private to raster/.
#pragma once

#include "binning.h"
#include "conservative.h"
#include "triangle_setup.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace cullide::raster::detail {

// A vertex snapped once (rule 3); `inside` when it needs no clipping (then |x|, |y| <= 2^29).
struct SnapVertex {
    int32_t x, y;
    bool inside;
};

// Conservative mode (rules 10-13): a record and its fast-path edge functions.
struct ConsRec {
    ConsTri t;
    ConsEdges e;
};

// The records of the triangles a list draws, in triangle order: a draw [first, first + count) is
// the record range [begin[first], end[first + count - 1]). Capacity is kept across lists.
template <typename Rec>
struct RecordSet {
    std::vector<uint8_t> flags;  // per triangle drawn: TriFlags
    std::vector<uint32_t> begin, end;  // per triangle drawn: its records
    std::vector<Rec> records;
    std::vector<TileRect> tiles;  // per record: the tiles of its pixel rectangle
    TileBins bins;  // per tile: the records whose rectangle holds it

    // Scratch of setup and binning.
    std::vector<std::array<uint32_t, 2>> ranges, chunks;
    std::vector<int32_t> coverDiff;
    std::vector<std::vector<Rec>> chunkRecords;
    std::vector<std::vector<TileRect>> chunkTiles;
    std::vector<size_t> chunkOffset;
    std::vector<uint32_t> counts;

    RecordIndex index() const { return {begin, end, flags, tiles}; }
};

// What setup reads: the geometry in window coordinates and the rasterization parameters.
struct SetupInput {
    std::span<const Triangle> triangles;
    std::span<const WinVertex> window;
    std::span<const SnapVertex> snapped;
    const SetupParams& params;
    const TileGrid& grid;
};

// Sets up the union of the ranges drawn by `list`'s Draw commands, once per triangle (clip, snap,
// edge functions, depth plane, pixel bounding box), and bins the records to tiles.
void setupDrawn(const CommandList& list, const SetupInput& in, RecordSet<EdgeTri>& out);

// The same for the DrawConservative commands (rules 10-12), with toWindow's error bound `err`.
void setupConservativeDrawn(const CommandList& list, const SetupInput& in, const WindowError& err,
                            RecordSet<ConsRec>& out);

}  // namespace cullide::raster::detail
