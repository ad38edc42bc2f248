// Triangle records for the fast path of the CPU backend (cpu_backend.cpp, steps 2-4): every
// triangle drawn by a command list set up once (triangle_setup.h, conservative.h), the records
// compacted in triangle order and binned to tiles. Private to raster/.
#pragma once

#include "fast/binning.h"
#include "setup/conservative.h"
#include "setup/triangle_setup.h"

#include "cullide/unwritten.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace cullide::raster::detail {

// Conservative mode (rules 10-13): a record and its fast-path edge functions.
struct ConsRec {
    ConsTri t;
    ConsEdges e;
};

// The record arrays: setup writes their elements before anything reads them (or marks them
// kNoTiles), so growing one leaves them unwritten (cullide/unwritten.h).
template <typename T>
using RecordArray = UnwrittenVector<T>;

// The records of the triangles a list draws, in triangle order: a draw [first, first + count) is
// the record range [begin[first], end[first + count - 1]). Setup writes the records in place: the
// drawn triangles are cut into chunks, and each chunk owns a slot sized by a cheap count of its
// records (records.cpp); a slot's unused tail stays in the range, with kNoTiles, so no tile ever
// lists it. A chunk that needs more than its slot (clipped triangles) spills to a side vector and
// the slots are then laid out again. Capacity is kept across lists, grown to the exact need
// (never doubled).
template <typename Rec>
struct RecordSet {
    std::vector<uint8_t> flags;  // per triangle drawn: TriFlags
    std::vector<uint32_t> begin, end;  // per triangle drawn: its records
    RecordArray<Rec> records;  // per slot
    RecordArray<TileRect> tiles;  // per slot: the tiles of its record's pixel rectangle, or kNoTiles
    TileBins bins;  // per tile: the records whose rectangle holds it

    // Scratch of setup and binning.
    std::vector<std::array<uint32_t, 2>> ranges, chunks;
    std::vector<int32_t> coverDiff;
    std::vector<size_t> slotStart;  // per chunk, and the end
    std::vector<uint32_t> used;  // per chunk: its records
    std::vector<std::vector<Rec>> spillRecords;  // per chunk that outgrew its slot
    std::vector<std::vector<TileRect>> spillTiles;
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
    bool simd = true;  // set up four triangles at a time with AVX2 where the CPU has it
};

// The count pass of setup, on triangles [lo, hi): a cheap guess of their records, exact for a
// triangle whose vertices need no clipping. setupTriangle gives such a triangle 0 or 1 record;
// the others count 1 (clipped ones with more spill). For vertices inside the clip volume
// trivialReject adds nothing: they are finite with depths in [0, 1], and three beyond one side of
// the viewport snap to a box that holds no centre; so the count reads the snapped vertices only,
// not the window ones (it was ~10% of a prune's time as a second gather). Its verdict goes to
// hint[t - lo]: kHintOne, one record, whose box is known to hold a centre (with kHintCw: the
// snapped triangle is clockwise); kHintClip, the clipping path; otherwise no record, and the
// hint is already the triangle's TriFlags (rejected, or zero area, or neither: no centre in its
// box), from the snapped vertices alone (setupTriangle's verdict: trivialReject by the vertices'
// sides). `batched`: eight at a time with AVX2 (haveSetupAvx2()), the same hints and counts.
enum : uint8_t { kHintCw = 0x20, kHintOne = 0x40, kHintClip = 0x80 };
static_assert(((kRejected | kClipped | kZeroArea) & (kHintCw | kHintOne | kHintClip)) == 0);
uint32_t countHints(std::span<const Triangle> triangles, const SnapVertex* snapped, const SetupParams& params,
                    bool batched, uint32_t lo, uint32_t hi, uint8_t* hint);

// Sets up the union of the ranges drawn by `list`'s Draw commands, once per triangle (clip, snap,
// edge functions, depth plane, pixel bounding box), and bins the records to tiles.
void setupDrawn(const CommandList& list, const SetupInput& in, RecordSet<EdgeTri>& out);

// The same for the DrawConservative commands (rules 10-12), with toWindow's error bound `err`.
void setupConservativeDrawn(const CommandList& list, const SetupInput& in, const WindowError& err,
                            RecordSet<ConsRec>& out);

}  // namespace cullide::raster::detail
