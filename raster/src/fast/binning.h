// Binning for the fast path of the CPU backend (cpu_backend.cpp, steps 4 and 5): tile rectangles,
// per-tile lists (CSR), and the events (clears and draws with their GL state) binned to the tiles
// they touch. Private to raster/.
#pragma once

#include "command_state.h"
#include "cullide/error.h"
#include "cullide/parallel.h"
#include "cullide/raster/cpu_options.h"

#include <oneapi/tbb/blocked_range.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

namespace cullide::raster::detail {

inline constexpr uint32_t kBinChunk = 4096;  // items per binning task
inline constexpr uint32_t kMaxBinChunks = 64;

// Tile rectangle [tx0, tx1] x [ty0, ty1], inclusive; tx0 > tx1 when empty.
struct TileRect {
    uint16_t tx0, ty0, tx1, ty1;
    bool empty() const { return tx0 > tx1; }
};
inline constexpr TileRect kNoTiles{1, 1, 0, 0};

// The viewport's tiles, row-major.
struct TileGrid {
    int tilesX = 0, tilesY = 0, tileSize = 64;
    // x / tileSize as (x * reciprocal) >> 32, for every pixel index x < 2^14 (viewports are at most
    // 16384 wide): reciprocal = floor(2^32 / d) + 1 overshoots x / d by x * (< 1) / 2^32 < 2^-18,
    // less than the 1/d (>= 2^-10) that separates x / d from the next integer. Setup bins every
    // record by four of these; integer division was a visible part of it.
    uint64_t reciprocal = (uint64_t(1) << 32) / 64 + 1;

    static TileGrid make(int width, int height, int tileSize) {
        TileGrid g;
        g.tileSize = tileSize;
        g.tilesX = (width + tileSize - 1) / tileSize;
        g.tilesY = (height + tileSize - 1) / tileSize;
        g.reciprocal = (uint64_t(1) << 32) / uint64_t(tileSize) + 1;
        return g;
    }
    size_t count() const { return size_t(tilesX) * size_t(tilesY); }
    size_t index(int tx, int ty) const { return size_t(ty) * size_t(tilesX) + size_t(tx); }
    uint16_t tileOf(int x) const { return uint16_t((uint64_t(x) * reciprocal) >> 32); }
    // The tiles of a pixel rectangle (inclusive bounds inside the viewport).
    TileRect of(int x0, int y0, int x1, int y1) const {
        return TileRect{tileOf(x0), tileOf(y0), tileOf(x1), tileOf(y1)};
    }
    // Calls visit(tile) for each tile of `r`, row by row.
    template <typename Visit>
    void forEach(const TileRect& r, const Visit& visit) const {
        for (int ty = r.ty0; ty <= r.ty1; ++ty)
            for (int tx = r.tx0; tx <= r.tx1; ++tx) visit(index(tx, ty));
    }
};

// Items binned to tiles: tile t's items are items[start[t], start[t + 1]), in item order.
struct TileBins {
    std::vector<uint32_t> start, items;
    const uint32_t* begin(size_t tile) const { return items.data() + start[tile]; }
    size_t size(size_t tile) const { return start[tile + 1] - start[tile]; }
};

// CSR binning of `n` items to `tiles` tiles, each tile's list in item order: `tilesOf(i, visit)`
// calls visit(tile) once for each tile of item i. Deterministic for any chunking. `counts` is
// scratch.
template <typename TilesOf>
void binToTileSets(size_t n, size_t tiles, const TilesOf& tilesOf, std::vector<uint32_t>& counts, TileBins& out) {
    const size_t nChunks = std::clamp<size_t>((n + kBinChunk - 1) / kBinChunk, 1, kMaxBinChunks);
    const size_t per = (n + nChunks - 1) / nChunks;
    counts.assign(nChunks * tiles, 0);
    parallelFor(0, nChunks, 1, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t c = r.begin(); c != r.end(); ++c) {
            uint32_t* mine = counts.data() + c * tiles;
            for (size_t i = c * per; i < std::min(n, (c + 1) * per); ++i)
                tilesOf(i, [&](size_t tile) { ++mine[tile]; });
        }
    });
    out.start.resize(tiles + 1);
    uint64_t running = 0;
    for (size_t tile = 0; tile < tiles; ++tile) {
        out.start[tile] = uint32_t(running);
        for (size_t c = 0; c < nChunks; ++c) {
            const uint32_t cnt = counts[c * tiles + tile];
            counts[c * tiles + tile] = uint32_t(running);  // becomes the chunk's write cursor
            running += cnt;
        }
    }
    CULLIDE_CHECK(running < uint64_t(UINT32_MAX), "too many tile entries for 32-bit indices");
    out.start[tiles] = uint32_t(running);
    out.items.resize(running);
    parallelFor(0, nChunks, 1, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t c = r.begin(); c != r.end(); ++c) {
            uint32_t* cursor = counts.data() + c * tiles;
            for (size_t i = c * per; i < std::min(n, (c + 1) * per); ++i)
                tilesOf(i, [&](size_t tile) { out.items[cursor[tile]++] = uint32_t(i); });
        }
    });
}

// The same for items with one tile rectangle each (`rects`).
inline void binToTiles(std::span<const TileRect> rects, const TileGrid& grid, std::vector<uint32_t>& counts,
                       TileBins& out) {
    binToTileSets(
        rects.size(), grid.count(), [rects, grid](size_t i, auto&& visit) { grid.forEach(rects[i], visit); }, counts,
        out);
}

// First index in [0, n) of `v` (sorted) with v[idx] >= key, searching outwards from `hint`
// (galloping).
template <typename T>
size_t gallopLowerBound(const T* v, size_t n, size_t hint, T key) {
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

// A clear or a draw with the GL state it runs under.
struct Event {
    bool clear = false;
    bool intervalClear = false;  // ClearIntervals
    bool conservative = false, test = false, write = false;  // DrawConservative
    DepthFunc func = DepthFunc::Less;
    bool mask = true;
    int32_t query = -1;
    uint32_t clearValue = 0;
    uint32_t recBegin = 0, recEnd = 0;  // draw: record range
    // Draw: a later draw of the list draws the same triangles (makeEvents' source), so its
    // fragments are worth recording for replay (FragCache); a draw of a range drawn once is
    // rasterized without recording.
    bool drawnAgain = false;
    uint32_t first = 0, count = 0;  // draw: triangle range
    TileRect tiles = kNoTiles;
    bool clears() const { return clear || intervalClear; }
};

// What the events need of a kind of records (plain or conservative, records.h): per triangle its
// record range [begin, end) and its TriFlags; per record its tile rectangle (kNoTiles for the
// unused slots between records).
struct RecordIndex {
    std::span<const uint32_t> begin, end;
    std::span<const uint8_t> flags;
    std::span<const TileRect> tiles;
};

// A list's events and their bins, with the scratch to make them (capacity kept across lists).
struct EventList {
    std::vector<Event> events;
    TileBins bins;  // per tile: the events that touch it, in command order
    std::vector<std::array<uint32_t, 3>> stats;  // per event: rejected, clipped, zero-area triangles
    std::vector<size_t> tileStart;  // per event, its run in tiles
    std::vector<uint32_t> tiles;  // the tiles each event's records touch
    std::vector<std::vector<uint32_t>> blockTiles;  // tiles per block of events, before concatenation
    std::vector<uint32_t> counts;  // binning scratch
    // makeEvents' scratch: per event, the first event drawing the same range (itself if none),
    // found through the first draw of each (first, count), plain and conservative.
    std::vector<uint32_t> source;
    std::unordered_map<uint64_t, uint32_t> firstDraw[2];
};

// Step 5a: the clears and draws of `list` as events, with the state that `walk` follows; each
// draw's tile rectangle; the draw and setup statistics into `stats`.
void makeEvents(const CommandList& list, const DepthFormat& format, const TileGrid& grid, const RecordIndex& plain,
                const RecordIndex& conservative, StateWalker& walk, RasterStats& stats, EventList& out);

// Step 5b: each event binned to the tiles its records touch (a clear touches all tiles).
void binEvents(const TileGrid& grid, const RecordIndex& plain, const RecordIndex& conservative, EventList& ev);

}  // namespace cullide::raster::detail
