// Fragments of the whole geometry under one view, kept across command lists (view_cache.h).
#include "fast/view_cache.h"

#include "cullide/parallel.h"
#include "cullide/raster/rules.h"

#include <algorithm>
#include <array>
#include <bit>
#include <functional>
#include <type_traits>

namespace cullide::raster::detail {

bool sameView(const OrthoView& a, const OrthoView& b) {
    return a.right == b.right && a.up == b.up && a.dir == b.dir && a.xmin == b.xmin && a.xmax == b.xmax &&
        a.ymin == b.ymin && a.ymax == b.ymax && a.znear == b.znear && a.zfar == b.zfar && a.width == b.width &&
        a.height == b.height && a.depth == b.depth && a.originX == b.originX && a.originY == b.originY &&
        a.gridWidth == b.gridWidth && a.gridHeight == b.gridHeight;
}

size_t viewHash(const OrthoView& v) {
    size_t h = 0;
    auto mix = [&h](uint64_t x) { h ^= std::hash<uint64_t>{}(x) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2); };
    // sameView compares doubles with ==, under which 0.0 and -0.0 are equal: both hash as 0.0.
    auto real = [&mix](double x) { mix(std::bit_cast<uint64_t>(x == 0 ? 0.0 : x)); };
    for (const Vec3d* axis : {&v.right, &v.up, &v.dir})
        for (int k = 0; k < 3; ++k) real((*axis)[k]);
    for (double x : {v.xmin, v.xmax, v.ymin, v.ymax, v.znear, v.zfar}) real(x);
    for (int x : {v.width, v.height, v.originX, v.originY, v.gridWidth, v.gridHeight, v.depth.bits})
        mix(uint64_t(uint32_t(x)));
    mix(uint64_t(v.depth.kind));
    return h;
}

const ViewFragments* ViewCache::find(const OrthoView& view) const {
    const auto [first, last] = index_.equal_range(viewHash(view));
    for (auto it = first; it != last; ++it)
        if (sameView(views_[it->second].view, view)) return &views_[it->second];
    return nullptr;
}

void ViewCache::add(ViewFragments&& v) {
    if (!accepting()) return;
    if (bytes_ + v.bytes() > budget_) {
        full_ = true;
        return;
    }
    bytes_ += v.bytes();
    index_.emplace(viewHash(v.view), views_.size());
    views_.push_back(std::move(v));
}

void ViewCache::clear() {
    std::vector<ViewFragments>().swap(views_);
    std::unordered_multimap<size_t, size_t>().swap(index_);
    bytes_ = 0;
    full_ = false;
}

bool replayable(const CommandList& list) {
    return list.conservativeCount() == 0;
}

FragLayout FragLayout::of(size_t triangles, int tileSize, int width, int height, const DepthFormat& format) {
    FragLayout l;
    // A tile's last pixel (its columns and rows within the viewport).
    const uint64_t last =
        uint64_t(std::min(tileSize, height) - 1) * uint64_t(width) + uint64_t(std::min(tileSize, width) - 1);
    l.placeBits = std::max(1, int(std::bit_width(last)));
    l.zBits = format.kind == DepthFormat::Kind::Float32 ? 32 : format.bits;
    l.triBits = std::bit_width(uint64_t(triangles));  // up to `triangles` itself (a draw's end)
    if (l.placeBits + l.zBits + l.triBits > 64) {
        l.axisBits = std::bit_width(unsigned(std::max(tileSize, 2) - 1));
        l.placeBits = 2 * l.axisBits;
        if (l.placeBits + l.zBits + l.triBits > 64) l.placeBits = l.axisBits = 0;
    }
    return l;
}

bool drawsEverything(const RecordSet<EdgeTri>& plain, size_t triangles) {
    uint64_t covered = 0;  // [0, covered) is drawn
    for (const auto& c : plain.chunks) {
        if (c[0] != covered) return false;
        covered = c[1];
    }
    return triangles > 0 && covered == triangles;
}

namespace {

struct TileBounds {
    int x0, y0, x1, y1;  // inclusive pixel bounds
};

TileBounds boundsOf(const TileGrid& grid, size_t tile, int width, int height) {
    const int ts = grid.tileSize;
    const int x0 = int(tile % size_t(grid.tilesX)) * ts, y0 = int(tile / size_t(grid.tilesX)) * ts;
    return {x0, y0, std::min(x0 + ts, width) - 1, std::min(y0 + ts, height) - 1};
}

// The fragments of groups [g, e) of a record of triangle t (tile from (x0, y0) of a viewport
// `width` pixels wide), written from `dst` on with room for four a group; returns their end. A
// group's lanes lie in one row (every kernel opens a group per row), and each lane is written
// whether it is a fragment or not, the end advanced by its bit.
uint64_t* appendGroups(const FragGroup* g, const FragGroup* e, uint32_t t, uint32_t width, uint32_t x0, uint32_t y0,
                       const FragLayout& layout, uint64_t* dst) {
    const int zShift = layout.zShift(), axis = layout.axisBits;
    const uint64_t tri = layout.pack(t, 0, 0);
    const auto append = [&](auto&& placeOf) {
        for (; g != e; ++g) {
            const uint64_t at = tri | placeOf(g->pixel);  // + l: the lane's place, within the tile
            for (uint32_t l = 0; l < 4; ++l) {
                *dst = (at + l) | uint64_t(g->z[l]) << zShift;
                dst += g->lanes >> l & 1;
            }
        }
    };
    if (axis == 0) {
        const uint32_t origin = y0 * width + x0;
        append([origin](uint32_t pixel) { return uint64_t(pixel - origin); });
    } else {
        append([=](uint32_t pixel) {  // one division a group (per fragment, they were most of this loop)
            const uint32_t y = pixel / width, x = pixel - y * width;
            return uint64_t(y - y0) << axis | (x - x0);
        });
    }
    return dst;
}

// Fragments per lane bits (FragGroup::lanes & kGroupLanes): this file is built without POPCNT,
// where std::popcount is a call.
constexpr uint8_t kLaneCount[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};

}  // namespace

void captureTile(const RecordSet<EdgeTri>& plain, size_t triangles, const TileGrid& grid, size_t tile, int width,
                 int height, const FragCache& cache, const TileCapture& capture, const RasterTable& table,
                 uint32_t* depth, int bits, const FragLayout& layout, std::vector<FragGroup>& scratch,
                 TileFragments& out) {
    const TileBounds b = boundsOf(grid, tile, width, height);
    const uint32_t* recs = plain.bins.begin(tile);
    const size_t n = plain.bins.size(tile);
    out = {};
    // The triangle of each record: the first whose records end after it (the tile's records
    // ascend, and their triangles lie close: a gallop from the last).
    size_t t = 0;
    auto triangleOf = [&](uint32_t rec) {
        t = gallopLowerBound(plain.end.data(), triangles, t, rec + 1);
        return uint32_t(t);
    };
    if (capture.ok && capture.groupBegin.size() == n) {
        const FragGroup* groups = cache.groups.data();
        size_t count = 0;  // sized exactly but for the slot appendGroups writes past the last
        for (size_t p = 0; p < n; ++p)
            for (uint32_t g = capture.groupBegin[p]; g < capture.groupEnd[p]; ++g)
                count += kLaneCount[groups[g].lanes & kGroupLanes];
        out.frag.resize(count + 1);
        uint64_t* dst = out.frag.data();
        for (size_t p = 0; p < n; ++p)
            dst = appendGroups(groups + capture.groupBegin[p], groups + capture.groupEnd[p], triangleOf(recs[p]),
                               uint32_t(width), uint32_t(b.x0), uint32_t(b.y0), layout, dst);
        out.frag.resize(count);
        return;
    }
    // A record's groups in a tile: at most one per pixel of the tile.
    scratch.resize(size_t(grid.tileSize) * size_t(grid.tileSize));
    uint64_t fragments = 0, passed = 0;
    for (size_t p = 0; p < n; ++p) {
        // ALWAYS without writing: the kernel records every fragment and leaves the buffer as it is
        // (the scalar one stores each pixel's own value back).
        FragGroup* w = scratch.data();
        table.record[size_t(DepthFunc::Always)](plain.records[recs[p]], b.x0, b.y0, b.x1, b.y1, depth, size_t(width),
                                                false, bits, fragments, passed, w);
        const size_t at = out.frag.size();
        out.frag.resize(at + 4 * size_t(w - scratch.data()));
        const uint64_t* end = appendGroups(scratch.data(), w, triangleOf(recs[p]), uint32_t(width), uint32_t(b.x0),
                                           uint32_t(b.y0), layout, out.frag.data() + at);
        out.frag.resize(size_t(end - out.frag.data()));
    }
    out.frag.shrink_to_fit();
}

void captureFlags(const RecordSet<EdgeTri>& plain, size_t triangles, ViewFragments& out) {
    for (size_t t = 0; t < triangles; ++t)
        if (const uint8_t f = plain.flags[t] & (kRejected | kClipped | kZeroArea)) {
            out.flagged.push_back(uint32_t(t));
            out.flags.push_back(f);
        }
    out.flagged.shrink_to_fit(), out.flags.shrink_to_fit();
}

namespace {

// A clear or a draw, with the state it runs under.
struct ViewEvent {
    bool clear = false;
    uint32_t clearValue = 0;
    DepthFunc func = DepthFunc::Less;
    bool mask = true;
    int32_t query = -1;
    uint32_t first = 0, end = 0;  // draw: triangles [first, end)
};

// The fragments [f, e) of one tile (its pixels from (x0, y0)) under F: replayFragments' test and
// write, one fragment at a time. XY: the layout's place is x and y (FragLayout::axisBits).
template <DepthFunc F, bool XY>
void replayView(const uint64_t* f, const uint64_t* e, const FragLayout& layout, uint32_t* depth, size_t stride, int x0,
                int y0, bool mask, uint64_t& fragments, uint64_t& passed) {
    uint64_t pass = 0;
    uint32_t* const origin = depth + size_t(y0) * stride + size_t(x0);
    const int zShift = layout.zShift(), axis = layout.axisBits;
    const uint64_t placeMask = (uint64_t(1) << layout.placeBits) - 1, zMask = (uint64_t(1) << layout.zBits) - 1;
    const uint64_t axisMask = (uint64_t(1) << axis) - 1;
    const auto run = [&](auto write) {
        for (const uint64_t* i = f; i != e; ++i) {
            const uint64_t v = *i;
            uint32_t& d =
                XY ? origin[size_t(v >> axis & axisMask) * stride + size_t(v & axisMask)] : origin[v & placeMask];
            const uint32_t incoming = uint32_t(v >> zShift & zMask), stored = d;
            const bool ok = depthTest(F, incoming, stored);
            pass += ok;
            if (decltype(write)::value && ok) d = incoming;
        }
    };
    if (mask) run(std::true_type());  // the mask decided once, not per fragment
    else run(std::false_type());
    fragments += uint64_t(e - f);
    passed += pass;
}

using ReplayViewFn = void (*)(const uint64_t*, const uint64_t*, const FragLayout&, uint32_t*, size_t, int, int, bool,
                              uint64_t&, uint64_t&);

template <bool XY, size_t... F>
constexpr std::array<ReplayViewFn, 8> replayViewTable(std::index_sequence<F...>) {
    return {&replayView<DepthFunc(F), XY>...};
}
// By whether the layout's place is x and y (FragLayout::axisBits), then by DepthFunc.
constexpr std::array<ReplayViewFn, 8> kReplayView[2] = {replayViewTable<false>(std::make_index_sequence<8>()),
                                                        replayViewTable<true>(std::make_index_sequence<8>())};

}  // namespace

void runFromView(const CommandList& list, const ViewFragments& frags, const TileGrid& grid, const DepthFormat& format,
                 StateWalker& walk, RasterStats& stats, uint32_t* depth, int width, int height,
                 std::vector<TileOut>& tileOut) {
    std::vector<ViewEvent> events;
    for (const Command& c : list.commands()) {
        if (walk.apply(c)) continue;
        ViewEvent e;
        if (c.op == Command::Op::Clear) {
            e.clear = true;
            e.clearValue = encodeDepth(c.clearDepth, format);
        } else if (c.op == Command::Op::Draw) {
            // makeEvents' statistics: per drawn triangle, its flags in this view.
            ++stats.draws;
            stats.triangles += c.count;
            if (c.count == 0) continue;
            e.func = walk.func();
            e.mask = walk.mask();
            e.query = int32_t(walk.query());
            e.first = c.first;
            e.end = c.first + c.count;
            const auto lo = std::lower_bound(frags.flagged.begin(), frags.flagged.end(), e.first);
            const auto hi = std::lower_bound(lo, frags.flagged.end(), e.end);
            for (auto it = lo; it != hi; ++it) {
                const uint8_t f = frags.flags[size_t(it - frags.flagged.begin())];
                stats.rejected += (f & kRejected) ? 1 : 0;
                stats.clipped += (f & kClipped) ? 1 : 0;
                stats.zeroArea += (f & kZeroArea) ? 1 : 0;
            }
        } else {
            continue;  // conservative commands: not replayable (replayable())
        }
        events.push_back(e);
    }
    const std::array<ReplayViewFn, 8>& replay = kReplayView[frags.layout.axisBits != 0];
    parallelFor(0, grid.count(), 1, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t tile = r.begin(); tile != r.end(); ++tile) {
            TileOut& out = tileOut[tile];
            out.queries.clear();
            out.fragments = out.passed = 0;
            const TileBounds b = boundsOf(grid, tile, width, height);
            const std::vector<uint64_t>& tf = frags.tiles[tile].frag;
            const int triShift = frags.layout.triShift();
            // The last draw's triangles and run: Cullide's lists draw each range twice in a row
            // (written and tested), and in triangle order within a pass (forward, then reverse),
            // so a run is the last one again or found by galloping from it.
            uint32_t lastFirst = 1, lastEnd = 0;  // no draw yet (first > end)
            size_t f = 0, l = 0;
            for (const ViewEvent& e : events) {
                if (e.clear) {
                    for (int j = b.y0; j <= b.y1; ++j)
                        std::fill_n(depth + size_t(j) * size_t(width) + size_t(b.x0), b.x1 - b.x0 + 1, e.clearValue);
                    continue;
                }
                if (tf.empty()) continue;
                // The draw's fragments in this tile: those of its triangles, a run (the triangle on
                // top: each fragment of a lower triangle is below first << triShift, the others not).
                if (e.first != lastFirst || e.end != lastEnd) {
                    const size_t hint = e.first >= lastEnd ? l : f;
                    f = gallopLowerBound(tf.data(), tf.size(), hint, uint64_t(e.first) << triShift);
                    l = gallopLowerBound(tf.data(), tf.size(), f, uint64_t(e.end) << triShift);
                    lastFirst = e.first, lastEnd = e.end;
                }
                const uint64_t before = out.passed;
                const uint64_t* const run = tf.data() + f;
                replay[size_t(e.func)](run, run + (l - f), frags.layout, depth, size_t(width), b.x0, b.y0, e.mask,
                                       out.fragments, out.passed);
                countQuery(out, e.query, out.passed - before);
            }
        }
    });
}

}  // namespace cullide::raster::detail
