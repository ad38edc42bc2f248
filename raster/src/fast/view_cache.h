// Fragments of the whole geometry under one view, kept across command lists, for the fast path of
// the CPU backend (cpu_backend.cpp). Private to raster/.
//
// Cullide's first levels draw every triangle under the same views, level after level: while the
// PCS is the whole geometry, each direction's view is the one fitted to the whole geometry
// (core/src/cullide.cpp, wholeFit), so levels 1 and 2 of a 270k bunny set up and rasterize again,
// in 12 of its 18 such lists, what level 0 did in the same view. A triangle's fragments and their
// incoming depths depend only on the triangle, the view and the rasterization options, never on
// the list or the GL state. So a list that draws every triangle runs as usual and its fragments
// are captured, per tile and in record order; a later list under the same view (any
// draws, any state, no conservative draws) replays them instead of setting up and rasterizing.
// Within a draw and a tile, the normal path meets the same fragments in the same order (its
// records in record order, each one's pixels in the kernel's order), so the depth buffer, the
// counts and the statistics are the same, bit for bit (test Differential.ViewCacheReplaysLaterLists).
//
// Memory: 8 bytes per fragment (about 2.1 MB per view of 500 x 500 for a mesh of any size, since
// small triangles cover each pixel about once), within CpuBackendOptions::viewCacheBytes.
#pragma once

#include "command_state.h"
#include "fast/records.h"
#include "fast/tile_kernels.h"

#include "cullide/depth_backend.h"
#include "cullide/raster/cpu_options.h"

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace cullide::raster::detail {

// A fragment in 64 bits: its triangle above its incoming depth code above its place in the tile
// (placeBits), for a geometry, tile size, viewport and depth format whose widths fit
// (FragLayout::of). With the triangle on top, a tile's fragments (in triangle order) are below
// t << triShift exactly for the triangles below t, so binary searches find a draw's run.
// The place is the depth-buffer index from the tile's first pixel (y * width + x), which spares
// the replay a multiplication per fragment (and the capture a division per group); where that
// does not fit (a wide viewport with float depth and a large geometry), x and y in axisBits each.
struct FragLayout {
    int placeBits = 0, zBits = 0, triBits = 0;
    int axisBits = 0;  // 0: the place is an index; else x | y << axisBits
    // The layout for these, or placeBits 0 when they need more than 64 bits (then no capture).
    static FragLayout of(size_t triangles, int tileSize, int width, int height, const DepthFormat& format);
    int zShift() const { return placeBits; }
    int triShift() const { return placeBits + zBits; }
    uint64_t pack(uint32_t tri, uint32_t z, uint32_t place) const {
        return uint64_t(tri) << triShift() | uint64_t(z) << zShift() | place;
    }
};

// One tile's fragments: those of its records, in the order of its list (records in triangle
// order, each one's fragments in its kernel's order).
struct TileFragments {
    std::vector<uint64_t> frag;  // FragLayout::pack
};

struct ViewFragments {
    OrthoView view;  // the key (the backend empties the cache when the geometry changes)
    FragLayout layout;
    std::vector<TileFragments> tiles;
    // The triangles with kRejected, kClipped or kZeroArea, ascending, and those flags (RasterStats).
    std::vector<uint32_t> flagged;
    std::vector<uint8_t> flags;

    size_t bytes() const {
        size_t b = tiles.capacity() * sizeof(TileFragments) + flagged.capacity() * 4 + flags.capacity();
        for (const TileFragments& t : tiles) b += t.frag.capacity() * 8;
        return b;
    }
};

// Whether the two views give the same window coordinates, viewport and depth codes.
bool sameView(const OrthoView& a, const OrthoView& b);
// A hash of what sameView compares: views that are the same hash alike.
size_t viewHash(const OrthoView& v);

// The captured views of one geometry within a byte budget, found by their view in constant time.
// A call drawn in tiles sets a view per tile (a 500 x 500 call at 4 pixels per side: 15,625), and
// each is captured, so a search through the views kept would cost every list time in proportion
// to all the tiles before it.
class ViewCache {
public:
    explicit ViewCache(size_t budgetBytes = 0) : budget_(budgetBytes) {}
    // The fragments captured under a view that is the same as `view` (sameView), or null.
    const ViewFragments* find(const OrthoView& view) const;
    // Keeps `v` if it fits the budget; else keeps nothing more until clear() (the views of one
    // geometry are alike in size).
    void add(ViewFragments&& v);
    // Whether a capture may still be kept: a budget, and not yet over it.
    bool accepting() const { return budget_ > 0 && !full_; }
    bool empty() const { return views_.empty(); }
    void clear();

private:
    size_t budget_ = 0, bytes_ = 0;
    bool full_ = false;
    std::vector<ViewFragments> views_;
    std::unordered_multimap<size_t, size_t> index_;  // viewHash -> place in views_
};

// Whether `list` may be replayed from a view's fragments: no conservative draws.
bool replayable(const CommandList& list);

// Whether the drawn triangles, as setup's chunks of `plain` (their union, cut in order), are all
// `triangles` of the geometry (so a capture holds them all).
bool drawsEverything(const RecordSet<EdgeTri>& plain, size_t triangles);

// A capture, for a list that draws every triangle: the list runs as usual, each tile noting
// in a TileCapture the groups that runTile recorded for its records (Cullide's lists draw each
// range at least twice, so the first draw records them), then captureTile turns them into
// fragments with their triangles, before the thread's FragCache moves on to another tile. A tile
// whose records were not all recorded when first met (a draw drawn once, too many groups for the
// cache) is rasterized again under ALWAYS without writing.
//
// Tile `tile`'s fragments into `out`: from `cache`'s groups as `capture` locates them, or from its
// records rasterized again with `table` (`depth` keeps its values; code bits `bits`; `scratch`: a
// thread's buffer). `width`, `height`: the viewport's.
void captureTile(const RecordSet<EdgeTri>& plain, size_t triangles, const TileGrid& grid, size_t tile, int width,
                 int height, const FragCache& cache, const TileCapture& capture, const RasterTable& table,
                 uint32_t* depth, int bits, const FragLayout& layout, std::vector<FragGroup>& scratch,
                 TileFragments& out);

// The triangles of `plain` (`triangles` of the geometry) with kRejected, kClipped or kZeroArea,
// into `out`.
void captureFlags(const RecordSet<EdgeTri>& plain, size_t triangles, ViewFragments& out);

// Steps 5 and 6 of the fast path for `list` from `frags` instead of records: each tile walks the
// list's clears and draws in order, replaying a draw's fragments (those of its triangles in the
// tile) under its state. Counts into `tileOut` (one per tile), statistics into `stats`; the query
// results are then summed as for the normal path.
void runFromView(const CommandList& list, const ViewFragments& frags, const TileGrid& grid, const DepthFormat& format,
                 StateWalker& walk, RasterStats& stats, uint32_t* depth, int width, int height,
                 std::vector<TileOut>& tileOut);

}  // namespace cullide::raster::detail
