// Events and their tiles for the fast path of the CPU backend (binning.h).
#include "fast/binning.h"

#include "setup/triangle_setup.h"

namespace cullide::raster::detail {

void makeEvents(const CommandList& list, const DepthFormat& format, const TileGrid& grid, const RecordIndex& plain,
                const RecordIndex& conservative, StateWalker& walk, RasterStats& stats, EventList& out) {
    std::vector<Event>& events = out.events;
    events.clear();
    const TileRect all{0, 0, uint16_t(grid.tilesX - 1), uint16_t(grid.tilesY - 1)};
    for (const Command& c : list.commands()) {
        if (walk.apply(c)) continue;
        Event e;
        switch (c.op) {
            case Command::Op::Clear:
                e.clear = true;
                e.clearValue = encodeDepth(c.clearDepth, format);
                e.tiles = all;
                break;
            case Command::Op::ClearIntervals:
                e.intervalClear = true;
                e.tiles = all;
                break;
            case Command::Op::DrawConservative:
            case Command::Op::Draw: {
                ++stats.draws;
                stats.triangles += c.count;
                if (c.count == 0) continue;
                e.conservative = c.op == Command::Op::DrawConservative;
                const RecordIndex& recs = e.conservative ? conservative : plain;
                if (e.conservative) {
                    e.test = c.test;
                    e.write = c.write;
                } else {
                    e.func = walk.func();
                    e.mask = walk.mask();
                }
                e.query = int32_t(walk.query());
                e.first = c.first;
                e.count = c.count;
                e.recBegin = recs.begin[c.first];
                e.recEnd = recs.end[c.first + c.count - 1];
                break;
            }
            default: continue;  // state commands: walk.apply
        }
        events.push_back(e);
    }
    // Tile rectangles of the draws and their setup statistics, O(triangles drawn). A range drawn
    // again (reducePCS draws each node two to four times in a list) copies its first draw's.
    out.stats.assign(events.size(), {0, 0, 0});
    out.source.resize(events.size());
    out.firstDraw[0].clear(), out.firstDraw[1].clear();
    for (size_t k = 0; k < events.size(); ++k) {
        const Event& e = events[k];
        out.source[k] = uint32_t(k);
        if (e.clears()) continue;
        const uint64_t key = uint64_t(e.first) << 32 | e.count;
        out.source[k] = out.firstDraw[e.conservative ? 1 : 0].try_emplace(key, uint32_t(k)).first->second;
    }
    // A draw that a later one repeats (its source) is worth recording for replay.
    for (size_t k = 0; k < events.size(); ++k)
        if (out.source[k] != k) events[out.source[k]].drawnAgain = true;
    parallelFor(0, events.size(), 256, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            Event& e = events[k];
            if (e.clears() || out.source[k] != k) continue;
            const RecordIndex& recs = e.conservative ? conservative : plain;
            int tx0 = grid.tilesX, ty0 = grid.tilesY, tx1 = -1, ty1 = -1;
            for (uint32_t i = e.recBegin; i < e.recEnd; ++i) {
                const TileRect& t = recs.tiles[i];
                if (t.empty()) continue;  // an unused slot (records.h)
                tx0 = std::min<int>(tx0, t.tx0);
                ty0 = std::min<int>(ty0, t.ty0);
                tx1 = std::max<int>(tx1, t.tx1);
                ty1 = std::max<int>(ty1, t.ty1);
            }
            e.tiles = tx1 < 0 ? kNoTiles : TileRect{uint16_t(tx0), uint16_t(ty0), uint16_t(tx1), uint16_t(ty1)};
            // Conservative setup only rejects: nothing is clipped, zero area is drawn.
            std::array<uint32_t, 3>& s = out.stats[k];
            for (uint32_t t = e.first; t < e.first + e.count; ++t) {
                const uint8_t f = recs.flags[t];
                s[0] += (f & kRejected) ? 1 : 0;
                s[1] += (f & kClipped) ? 1 : 0;
                s[2] += (f & kZeroArea) ? 1 : 0;
            }
        }
    });
    for (size_t k = 0; k < events.size(); ++k)
        if (out.source[k] != k) {
            events[k].tiles = events[out.source[k]].tiles;
            out.stats[k] = out.stats[out.source[k]];
        }
    for (const auto& s : out.stats) {
        stats.rejected += s[0];
        stats.clipped += s[1];
        stats.zeroArea += s[2];
    }
}

namespace {

constexpr uint32_t kExactTilesUpTo = 4096;  // draws up to this many records: binned to their exact tiles
constexpr size_t kEventBlock = 256;  // events per task when finding their tiles

// Calls visit(tile) once for each tile event `e` (number k) touches. `stamp` is the task's
// per-tile scratch (the last event that visited each tile).
template <typename Visit>
void eachTile(const Event& e, const TileGrid& grid, const RecordIndex& plain, const RecordIndex& conservative,
              std::vector<uint32_t>& stamp, uint32_t k, const Visit& visit) {
    if (e.clears()) {
        for (size_t t = 0; t < grid.count(); ++t) visit(t);
        return;
    }
    const int rectTiles = (e.tiles.tx1 - e.tiles.tx0 + 1) * (e.tiles.ty1 - e.tiles.ty0 + 1);
    // Large draws cover their rectangle anyway; a rectangle of one or two tiles wastes at most
    // one visit, less than finding the exact set costs.
    if (rectTiles <= 2 || e.recEnd - e.recBegin > kExactTilesUpTo) {
        grid.forEach(e.tiles, visit);
        return;
    }
    const std::span<const TileRect> rects = (e.conservative ? conservative : plain).tiles;
    for (uint32_t i = e.recBegin; i < e.recEnd; ++i)
        grid.forEach(rects[i], [&](size_t t) {
            if (stamp[t] != k) stamp[t] = k, visit(t);
        });
}

// A draw of the same records as the event before it (reducePCS draws each object twice in a
// row) has the same tiles.
bool sameAsPrevious(const std::vector<Event>& events, size_t k) {
    const Event &e = events[k], &f = events[k - 1];
    return !e.clears() && !f.clears() && e.conservative == f.conservative && e.recBegin == f.recBegin &&
        e.recEnd == f.recEnd;
}

}  // namespace

// Each draw goes to the tiles its records touch, not to every tile of their bounding rectangle: a
// draw of 16 triangles scattered through a scan's file order would visit about 5x more tiles
// (bunny75k: 634,560 visits instead of 128,116), each for nothing. Draws of more than
// kExactTilesUpTo records keep their rectangle (one thread walks each draw's records here: a
// whole mesh would cost more than it saves).
void binEvents(const TileGrid& grid, const RecordIndex& plain, const RecordIndex& conservative, EventList& ev) {
    const std::vector<Event>& events = ev.events;
    const size_t nTiles = grid.count();
    const size_t eventBlocks = (events.size() + kEventBlock - 1) / kEventBlock;
    ev.tileStart.assign(events.size() + 1, 0);
    // One pass per block into the block's list, then the blocks concatenated.
    if (ev.blockTiles.size() < eventBlocks) ev.blockTiles.resize(eventBlocks);
    parallelForEach(0, eventBlocks, [&](size_t blk) {
        std::vector<uint32_t> stamp(nTiles, UINT32_MAX);
        std::vector<uint32_t>& out = ev.blockTiles[blk];
        out.clear();
        for (size_t k = blk * kEventBlock; k < std::min(events.size(), (blk + 1) * kEventBlock); ++k) {
            const size_t before = out.size();
            if (k != blk * kEventBlock && sameAsPrevious(events, k)) {  // copied, within a block
                const size_t n = ev.tileStart[k];  // the previous event's count, the last n entries
                out.resize(before + n);
                std::copy_n(out.begin() + ptrdiff_t(before - n), n, out.begin() + ptrdiff_t(before));
            } else {
                eachTile(events[k], grid, plain, conservative, stamp, uint32_t(k),
                         [&](size_t t) { out.push_back(uint32_t(t)); });
            }
            ev.tileStart[k + 1] = out.size() - before;
        }
    });
    for (size_t k = 0; k < events.size(); ++k) ev.tileStart[k + 1] += ev.tileStart[k];
    ev.tiles.resize(ev.tileStart.back());
    parallelForEach(0, eventBlocks, [&](size_t blk) {
        std::copy(ev.blockTiles[blk].begin(), ev.blockTiles[blk].end(),
                  ev.tiles.begin() + ptrdiff_t(ev.tileStart[blk * kEventBlock]));
    });
    binToTileSets(
        events.size(), nTiles,
        [&](size_t i, auto&& visit) {
            for (size_t k = ev.tileStart[i]; k < ev.tileStart[i + 1]; ++k) visit(ev.tiles[k]);
        },
        ev.counts, ev.bins);
}

}  // namespace cullide::raster::detail
