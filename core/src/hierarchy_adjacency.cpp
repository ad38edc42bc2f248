// The connectivity build's face adjacency (Builder::buildAdjacency), and the renumbering of a mesh
// whose neighbours lie far apart in memory (Builder::scattered, Builder::compact). hierarchy_builder.h.
#include "hierarchy_builder.h"

#include "cullide/error.h"

#include <algorithm>
#include <span>
#include <vector>

namespace cullide::detail::hierarchy {

namespace {

// Sorts a short run (an adjacency row: three entries on a manifold mesh) and drops repeats;
// returns the new end. Insertion sort: std::sort's setup costs more than the row.
uint32_t* sortUnique(uint32_t* first, uint32_t* last) {
    if (last - first < 2) return last;  // also an empty row whose storage is still null
    for (uint32_t* i = first + 1; i < last; ++i)
        for (uint32_t* j = i; j > first && j[-1] > j[0]; --j) std::swap(j[-1], j[0]);
    return std::unique(first, last);
}

}  // namespace

// Face adjacency through shared edges (by vertex index), neighbours in increasing triangle
// order. Triangles on a non-manifold edge are all adjacent to each other; degenerate edges
// (a == b) connect nothing. Built from the vertex -> triangle incidence (linear time): the
// triangles sharing edge (a, b) are among those incident to a.
//
// The incidence is built by the two halves of the triangles at once, each counting and then
// filling in its own triangles, the second half's after the first's in each vertex's list: the
// lists are in increasing triangle order, as one pass makes them, whatever the threads. (One
// pass, serial, was a tenth of a 1M build's wall time on two threads; the halves took 21-23 ->
// 9-12 ms there.) Their counts live in the root's queue where they fit, and the incidence array
// becomes the pieces' scratch: both are then written for the first time here, and their page
// faults are paid once.
void Builder::buildAdjacency() {
    const uint32_t n = uint32_t(mesh_.triangles.size());
    const size_t nv = mesh_.positions.size();
    std::vector<uint32_t> ownCounts;
    if (2 * (nv + 1) > queue_.size()) ownCounts.resize(2 * (nv + 1));
    // Per half, its count of each vertex's triangles, then its cursor in the vertex's list;
    // counts[1][-1] is a start of 0 for the starts below.
    uint32_t* const base = ownCounts.empty() ? queue_.data() : ownCounts.data();
    uint32_t* const counts[2] = {base, base + nv + 1};
    const Triangle* const tris = mesh_.triangles.data();
    const uint32_t halves[3] = {0, n / 2, n};
    auto bothHalves = [n](const auto& body) {  // a small mesh's halves on this thread: no task
        if (n >= kParallelNode) return parallelForEach(0, 2, body);
        body(0), body(1);
    };
    bothHalves([&](size_t h) {
        uint32_t* const c = counts[h];
        std::fill(c, c + nv, 0u);
        for (uint32_t t = halves[h]; t < halves[h + 1]; ++t)
            for (uint32_t v : tris[t]) ++c[v];
    });
    uint32_t at = 0;
    for (size_t v = 0; v < nv; ++v) {
        const uint32_t first = counts[0][v], second = counts[1][v];
        counts[0][v] = at, counts[1][v] = at + first;
        at += first + second;
    }
    Pages<uint32_t> incident(at);  // 3n
    bothHalves([&](size_t h) {
        uint32_t* const cursor = counts[h];
        uint32_t* const inc = incident.data();
        for (uint32_t t = halves[h]; t < halves[h + 1]; ++t)
            for (uint32_t v : tris[t]) inc[cursor[v]++] = t;
    });
    // The second half's cursors now end each vertex's list: vstart[v] is where v's list
    // starts, vstart[v + 1] where it ends.
    counts[1][-1] = 0;
    const std::span<const uint32_t> vstart(counts[1] - 1, nv + 1);

    // The rows, in parallel blocks: each row depends on the incidence only. A row longer than
    // three goes to overflow_, which is appended in triangle order afterwards (non-manifold
    // edges are rare), so the layout does not depend on the threads.
    Pages<uint32_t>& slots = rows_;
    slots.resize(3 * size_t(n));
    overflow_.clear();
    // The arrays as local pointers, and the triangle by value: push_back's out-of-line growth
    // may change anything the closure reaches, so GCC reloaded each of them per candidate.
    const uint32_t* const inc = incident.data();
    const uint32_t* const vs = vstart.data();
    // A triangle's neighbours across edges (a, b) and (c, a) are among a's triangles, those
    // across (b, c) among b's: two lists read, not three.
    auto rowOf = [tris, inc, vs](uint32_t t, std::vector<uint32_t>& row) {
        const Triangle tri = tris[t];
        const uint32_t a = tri[0], b = tri[1], c = tri[2];
        const bool ab = a != b, bc = b != c, ca = c != a;  // degenerate edges connect nothing
        row.clear();
        if (ab || ca) {
            for (const uint32_t *k = inc + vs[a], *end = inc + vs[a + 1]; k != end; ++k) {
                const Triangle& o = tris[*k];
                const bool hasB = (o[0] == b) | (o[1] == b) | (o[2] == b);
                const bool hasC = (o[0] == c) | (o[1] == c) | (o[2] == c);
                if (((hasB & ab) | (hasC & ca)) & (*k != t)) row.push_back(*k);
            }
        }
        const size_t fromA = row.size();
        if (bc) {
            for (const uint32_t *k = inc + vs[b], *end = inc + vs[b + 1]; k != end; ++k) {
                const Triangle& o = tris[*k];
                if (((o[0] == c) | (o[1] == c) | (o[2] == c)) & (*k != t)) row.push_back(*k);
            }
        }
        if (fromA == 2 && row.size() == 3) {
            // The usual row (a manifold edge each): two neighbours from a's list, in
            // increasing order, and one from b's, merged without a branch (the sort's went
            // either way). The 1M bunny's rows on one thread: three lists read and sorted
            // 81-83 ms, two lists 74-75 ms, and this merge 72-73 ms.
            const uint32_t x = row[0], y = row[1], z = row[2];
            if (x < y && z != x && z != y) {
                row[0] = std::min(x, z), row[1] = std::max(x, std::min(y, z)), row[2] = std::max(y, z);
                return;
            }
        }
        row.resize(size_t(sortUnique(row.data(), row.data() + row.size()) - row.data()));
    };
    constexpr uint32_t kBlock = 16384;
    const uint32_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<std::vector<uint32_t>> longRows(blocks);  // per block: its triangles with long rows
    parallelForEach(0, blocks, [&](size_t blk) {
        std::vector<uint32_t> row;
        for (uint32_t t = uint32_t(blk) * kBlock, e = std::min(n, t + kBlock); t < e; ++t) {
            rowOf(t, row);
            uint32_t* slot = slots.data() + 3 * size_t(t);
            if (row.size() <= 3) {
                for (size_t i = 0; i < 3; ++i) slot[i] = i < row.size() ? row[i] : t;
            } else {
                longRows[blk].push_back(t);
            }
        }
    });
    std::vector<uint32_t> row;
    for (const std::vector<uint32_t>& ts : longRows)
        for (uint32_t t : ts) {
            rowOf(t, row);
            CULLIDE_CHECK(overflow_.size() + row.size() < kNone, "overflow rows fit 32-bit offsets");
            uint32_t* slot = slots.data() + 3 * size_t(t);
            slot[0] = kEscape, slot[1] = uint32_t(overflow_.size()), slot[2] = uint32_t(row.size());
            overflow_.insert(overflow_.end(), row.begin(), row.end());
        }
    // The incidence array (3n entries, already written once) holds the bisections' pieces.
    pieces_ = std::move(incident);
}

// Neither triangles nor rows move during the bisections, so the mesh's own order decides
// whether a part's rows lie near each other in memory. Most meshes keep neighbours close (the
// subdivided bunny: 96% of its sampled neighbours within 4096 ids at 1M and 270k triangles,
// 99% at 5k); a mesh whose triangles were shuffled does not (1%), and the 1M bunny shuffled
// took 1.3 s to build, against 0.84 s when parts were still moved into place. Such a mesh,
// where fewer than half of the sampled neighbours lie within 4096 ids, is renumbered first
// (compact()).
bool Builder::scattered() const {
    const uint32_t n = uint32_t(mark_.size()), step = std::max<uint32_t>(1, n / 4096);
    uint64_t near = 0, all = 0;
    for (uint32_t t = 0; t < n; t += step)
        forNeighbours(t, [&](uint32_t u) {
            if (u == t) return;
            ++all;
            near += (u > t ? u - t : t - u) < 4096;
        });
    return 2 * near < all;
}

// Numbers the triangles for the build by a breadth-first order from triangle 0 (the other
// components' triangles after it, by id): rows_ and overflow_ then hold positions, and the
// list (out_.order) the positions of triangles 0, 1, ... until the build ends. The search is
// the one the root's bisection starts with (its farthest triangle is the root's seed), so
// only the renumbering is added. Ties and orders are by triangle id throughout (the rows keep
// their order), so the hierarchy is the same.
void Builder::compact() {
    const uint32_t n = uint32_t(mark_.size());
    uint32_t* mark = mark_.data();
    blocks(0, n, [&](uint32_t b, uint32_t e) { std::fill(mark + b, mark + e, kOpen); });
    uint32_t* order = queue_.data();  // position -> triangle
    order[0] = 0;
    mark[0] = kVisited;
    uint32_t size = grow(order, 0, 1);
    rootSeed_ = size - 1;
    for (uint32_t t = 0; t < n && size < n; ++t)
        if (mark[t] == kOpen) order[size++] = t;
    blocks(0, n, [&](uint32_t b, uint32_t e) {
        for (uint32_t j = b; j < e; ++j) mark[order[j]] = j;  // triangle -> position
    });
    // The rows, renumbered, into the incidence array; the old rows array becomes the scratch
    // (pieces at [0, n), the position -> triangle map at [n, 2n)).
    const uint32_t* rows = rows_.data();
    uint32_t* out = pieces_.data();
    blocks(0, n, [&](uint32_t b, uint32_t e) {
        for (uint32_t t = b; t < e; ++t) {
            const uint32_t* slot = rows + 3 * size_t(t);
            uint32_t* to = out + 3 * size_t(mark[t]);
            if (slot[0] == kEscape) {
                std::copy(slot, slot + 3, to);
                continue;
            }
            to[0] = mark[slot[0]], to[1] = mark[slot[1]], to[2] = mark[slot[2]];
        }
    });
    for (uint32_t& q : overflow_) q = mark[q];
    std::swap(rows_, pieces_);
    std::copy(order, order + n, pieces_.data() + n);
    blocks(0, n, [&](uint32_t b, uint32_t e) { std::copy(mark + b, mark + e, out_.order.data() + b); });
}

}  // namespace cullide::detail::hierarchy
