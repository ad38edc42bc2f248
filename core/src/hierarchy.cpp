// Per-frame hierarchies of sub-objects for Cullide.
//
// References: the seed paper (docs/paper.md#section-6-1), Section 6.1 (random vs
// connectivity-based hierarchies); CULLIDE (Govindaraju et al. 2003), Section 4 (sub-objects).
// The connectivity split is recursive graph-growing bisection on the face-adjacency graph (the
// breadth-first "graph growing" of METIS' initial partitioning, Karypis and Kumar 1998), from a
// pseudo-peripheral start (the farthest triangle in hops from an arbitrary one).
#include "cullide/hierarchy.h"

#include "cullide/error.h"
#include "cullide/parallel.h"
#include "cullide/unwritten.h"

#include <algorithm>
#include <atomic>
#include <limits>
#include <random>
#include <span>
#include <vector>

namespace cullide {

const char* toString(HierarchyKind kind) {
    return kind == HierarchyKind::Connectivity ? "connectivity" : "random";
}

HierarchyKind parseHierarchyKind(const std::string& text) {
    if (text == "connectivity") return HierarchyKind::Connectivity;
    if (text == "random") return HierarchyKind::Random;
    throw InputError("option --hierarchy", "unknown hierarchy '" + text + "' (expected connectivity or random)");
}

uint32_t Hierarchy::depth() const {
    uint32_t d = 0;
    for (const HierarchyNode& n : nodes) d = std::max(d, n.depth);
    return d;
}

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Sorts a short run (an adjacency row: three entries on a manifold mesh) and drops repeats;
// returns the new end. Insertion sort: std::sort's setup costs more than the row.
uint32_t* sortUnique(uint32_t* first, uint32_t* last) {
    if (last - first < 2) return last;  // also an empty row whose storage is still null
    for (uint32_t* i = first + 1; i < last; ++i)
        for (uint32_t* j = i; j > first && j[-1] > j[0]; --j) std::swap(j[-1], j[0]);
    return std::unique(first, last);
}

// Builds the hierarchy over flat arrays sized once per build (no allocation per node).
//
// Connectivity works in position space: a node, and every part of its recursive bisection, is a
// range [lo, hi) of positions in out_.order, and its face adjacency is kept restricted to that
// range: the row of position p holds the positions of p's neighbours inside the range, in
// increasing order of their triangle ids (the order of the searches this follows). After each
// bisection the rows of both halves are rebuilt, restricted to themselves, into the other of two
// row arrays (so no copy back; a range's rows are in one, its halves' in the other). So a search
// needs no membership test, and a patch's triangles sit next to each other in memory.
// That holds down to nodes of kInPlaceNode triangles; a smaller node's subtree is split in place
// (Builder::InPlace): its parts are lists of positions, told apart by their labels.
//
// A row is three slots (a triangle has three edges), unused ones holding the position itself: a
// triangle is labelled kVisited before its row is read, so it never passes for an open or first
// neighbour; searches run without branches on row lengths, and a rebuild is a scatter by new
// position. (One shared sentinel position would chain every search step through its label.)
// A triangle with more than three neighbours (on a non-manifold edge) has slot 0 = kEscape and
// its neighbours' triangle ids in overflow_ (slots 1, 2: offset and count), found through posOf_
// (triangle id -> position) and tested against the range.
// The build's arrays: written before they are read, and mapped with pages of their own, so that
// the scratch a parallel subtree frees goes back to the system (cullide/unwritten.h).
template <typename T>
using Pages = UnwrittenVector<T, true>;

// A part of a node's partition: its size, whether its order is a breadth-first order of the
// whole part from its first position (see partition()), and which of the two row arrays
// (Builder::rows_) holds its rows.
struct Part {
    uint32_t size;
    bool searched;
    uint8_t rows;
};

// What one thread's splits write besides the shared arrays, indexed from the start of the range
// being split: queue (breadth-first order, then the new triangle ids), and the small stacks.
// (The pieces of a bisection and its rebuilt rows go to the row array its range does not use.)
//
// The queue is a view: the root's is the build's own (Builder::queue_), and a parallel subtree's
// is a slice of its parent's, not an array of its own. Fresh pages cost a page fault each on
// first write, and on the shared build machine's VM a 4 KiB fault costs ~17 us
// (4 ms per MiB): the subtrees' own scratch (40 MB in 4 KiB-page arrays for 1M triangles) was
// about a fifth of a 1M build. The memory is the same: a parent's scratch was freed before its
// children allocated theirs, as large together.
// For a range of m positions, queue holds m + slack entries (a search writes one past its last
// entry, so slack >= 1, and siblings' slices must not overlap there).
struct Scratch {
    uint32_t* queue = nullptr;
    size_t slack = 0;
    std::vector<Part> sizes;
    std::vector<uint32_t> pieceStart;
    std::vector<uint8_t> moved;
    Pages<uint32_t> ownQueue;  // only where the parent's slack ran out

    void allocate(uint32_t n) {  // a queue of its own, for ranges of up to n positions
        ownQueue.resize(size_t(n) + 1);
        queue = ownQueue.data(), slack = 1;
    }
};

// Nodes of at least this many triangles split their children in parallel (a 1M-triangle build
// has 16 such nodes at leaf size 16, branching 4; smaller subtrees are not worth a task).
constexpr uint32_t kParallelNode = 1 << 16;
// Nodes of fewer triangles are split in place (Builder::InPlace).
constexpr uint32_t kInPlaceNode = 1 << 16;
static_assert(kInPlaceNode <= kParallelNode, "a subtree split in place runs on one thread");

class Builder {
public:
    Builder(const Mesh& mesh, const HierarchyOptions& options, Hierarchy& out)
        : mesh_(mesh), opt_(options), out_(out), rng_(options.seed) {}

    void build() {
        const uint32_t n = uint32_t(mesh_.triangles.size());
        out_.order.clear();
        out_.order.reserve(n);  // written once, without a zeroing pass first
        for (uint32_t t = 0; t < n; ++t) out_.order.push_back(t);
        if (opt_.kind == HierarchyKind::Random) {
            // Fisher-Yates with our own bounded draws (std's distributions are implementation-defined).
            for (uint32_t i = n; i > 1; --i) std::swap(out_.order[i - 1], out_.order[uniform(i)]);
        }
        out_.nodes.clear();
        out_.nodes.push_back({0, n, 0, 0, 0});
        if (n <= opt_.leafSize) return;  // a leaf root: no adjacency to build
        if (opt_.kind == HierarchyKind::Connectivity) {
            CULLIDE_CHECK(n < kFirst - kInPlaceNode, "triangle count leaves room for the labels");
            // Slack for a slice per parallel subtree: each level of parallel subtrees divides it
            // by the branching (a 1M build has two such levels); where it runs out, a subtree
            // allocates its own scratch.
            const size_t slack = 1 + n / 1024;
            queue_.resize(n + slack);
            buildAdjacency();
            mark_.resize(n);
            root_.queue = queue_.data(), root_.slack = slack;
        }
        split(out_.nodes, 0, root_, {n, false, 0});
    }

private:
    uint32_t uniform(uint32_t bound) {  // in [0, bound), by rejection: unbiased, portable
        const uint64_t limit = std::numeric_limits<uint64_t>::max() - std::numeric_limits<uint64_t>::max() % bound;
        uint64_t x;
        do x = rng_();
        while (x >= limit);
        return uint32_t(x % bound);
    }

    // Face adjacency through shared edges (by vertex index), neighbours in increasing triangle
    // order. Triangles on a non-manifold edge are all adjacent to each other; degenerate edges
    // (a == b) connect nothing. Built from the vertex -> triangle incidence (linear time): the
    // triangles sharing edge (a, b) are among those incident to a. Positions are triangle ids at
    // the root.
    //
    // The incidence array becomes the second row array (3n entries), and the vertex starts
    // live in the root's queue where they fit: both are then written for the first time here, and
    // their page faults are paid once.
    void buildAdjacency() {
        const uint32_t n = uint32_t(mesh_.triangles.size());
        const size_t nv = mesh_.positions.size();
        std::vector<uint32_t> ownStart;
        if (nv + 1 > queue_.size()) ownStart.resize(nv + 1);
        const std::span<uint32_t> vstart = ownStart.empty() ? std::span(queue_.data(), nv + 1) : std::span(ownStart);
        std::fill(vstart.begin(), vstart.end(), 0u);
        for (const Triangle& tri : mesh_.triangles)
            for (uint32_t v : tri) ++vstart[v + 1];
        for (size_t v = 0; v < nv; ++v) vstart[v + 1] += vstart[v];
        Pages<uint32_t> incident(vstart[nv]);  // vstart[nv] = 3n
        // Fill by advancing each vertex's start to its end, then shift the starts back: no array
        // of cursors.
        for (uint32_t t = 0; t < n; ++t)
            for (uint32_t v : mesh_.triangles[t]) incident[vstart[v]++] = t;  // increasing t per vertex
        for (size_t v = nv; v > 0; --v) vstart[v] = vstart[v - 1];
        vstart[0] = 0;

        // The rows, in parallel blocks: each row depends on the incidence only. A row longer than
        // three goes to overflow_, which is appended in triangle order afterwards (non-manifold
        // edges are rare), so the layout does not depend on the threads.
        Pages<uint32_t>& slots = rows_[0];
        slots.resize(3 * size_t(n));
        overflow_.clear();
        // The arrays as local pointers, and the triangle by value: push_back's out-of-line growth
        // may change anything the closure reaches, so GCC reloaded each of them per candidate.
        const Triangle* const tris = mesh_.triangles.data();
        const uint32_t* const inc = incident.data();
        const uint32_t* const vs = vstart.data();
        auto rowOf = [tris, inc, vs](uint32_t t, std::vector<uint32_t>& row) {
            const Triangle tri = tris[t];
            row.clear();
            for (int e = 0; e < 3; ++e) {
                const uint32_t a = tri[e], b = tri[(e + 1) % 3];
                if (a == b) continue;
                for (const uint32_t *k = inc + vs[a], *end = inc + vs[a + 1]; k != end; ++k) {
                    const uint32_t u = *k;
                    if (u == t) continue;
                    const Triangle& other = tris[u];
                    if (other[0] == b || other[1] == b || other[2] == b) row.push_back(u);
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
        if (!overflow_.empty()) {
            posOf_.resize(n);
            for (uint32_t t = 0; t < n; ++t) posOf_[t] = t;
        }
        // A bisection writes its halves' rows to the other row array (no copy back): the incidence
        // array (3n entries, as many as the slots, already written once) serves as that.
        rows_[1] = std::move(incident);
    }

    // A subtree of fewer than kInPlaceNode triangles is split in place: its bisections reorder a
    // list of its positions (ord) and leave the positions, their rows and their triangle ids
    // where they are; the triangle ids move once, when the whole subtree is split. A search keeps
    // to its part by labels alone: the rows reach the whole subtree, where every position outside
    // the part is labelled neither kOpen nor the part's first-part label (each bisection has its
    // own, counting down from kFirst). Above that size each bisection moves its positions and
    // rebuilds its halves' rows (partition()), which keeps a part compact in memory but costs two
    // passes over it; below, the passes cost more than the compactness saved. The 1M-triangle
    // bunny on one thread, in place below 2^10, 2^12, 2^14, 2^16 triangles: 470-480, 466-470,
    // 454, 440-446 ms, against 514-517 ms moving at every bisection (the same hierarchy).
    struct InPlace {
        uint32_t lo, hi;  // the subtree's positions
        const uint32_t* rows;  // their rows, restricted to [lo, hi)
        uint32_t* pieces;  // the pieces of the part at ord + j go to pieces + j
        uint32_t* ord;  // the subtree's order: position ord[j] ends at lo + j
        uint32_t first;  // the next bisection's first-part label
    };

    void splitInPlace(std::vector<HierarchyNode>& nodes, uint32_t i, Scratch& s, Part part) {
        const uint32_t lo = nodes[i].first, n = nodes[i].count;
        // The other row array's slots of the range are free: the subtree writes no rows.
        uint32_t* other = rows_[1 - part.rows].data() + 3 * size_t(lo);
        InPlace in{lo, lo + n, rows_[part.rows].data(), other, other + n, kFirst};
        for (uint32_t j = 0; j < n; ++j) in.ord[j] = lo + j;
        split(nodes, i, s, part, &in);
        // The triangle ids in the subtree's order (the queue is free by now).
        for (uint32_t j = 0; j < n; ++j) s.queue[j] = out_.order[in.ord[j]];
        std::copy(s.queue, s.queue + n, out_.order.begin() + lo);
        if (!posOf_.empty())
            for (uint32_t p = lo; p < lo + n; ++p)  // read concurrently by forNeighbours of other ranges
                std::atomic_ref<uint32_t>(posOf_[out_.order[p]]).store(p, std::memory_order_relaxed);
    }

    // partition() in a subtree split in place: reorders in.ord[at, at + n) into k parts.
    void partitionInPlace(Scratch& s, InPlace& in, uint32_t at, uint32_t n, uint32_t k, uint32_t hint, bool searched) {
        if (k < 2 || n < 2) {
            s.sizes.push_back({n, searched, 0});
            return;
        }
        const uint32_t half = k / 2;
        const uint32_t target = uint32_t(std::max<size_t>(1, size_t(n) * half / k));
        uint32_t* list = in.ord + at;
        const auto [f, firstSearched, secondSearched] =
            bisect(s, in.rows, in.pieces + at, in.lo, in.hi, list, n, target, hint, in.first--);
        std::copy(s.queue, s.queue + n, list);
        partitionInPlace(s, in, at, f, half, list[f - 1], firstSearched);
        partitionInPlace(s, in, at + f, n - f, k - half, list[n - 1], secondSearched);
    }

    // Splits nodes[i] and its descendants, appending them to `nodes` depth first: a node's
    // children are contiguous, followed by the first child's descendants, then the second's, ...
    //
    // A large node's children are split in parallel, each subtree in a list of its own (its root
    // at 0, its descendants after it) with scratch of its own, then appended in child order with
    // their indices shifted: the same nodes, in the same order, as one thread would make. The
    // subtrees' positions are disjoint ranges, so they share the arrays indexed by position or by
    // triangle id (each writes only its own part) and read the overflow rows only.
    //
    // `part`: the node as a part of its parent's partition. part.searched: the node's order is a
    // breadth-first order of the whole node from its first position, so that search's farthest
    // position is known: the last one. part.rows: the row array holding the node's rows.
    //
    // `in`: the subtree this node lies in, when that is split in place (see InPlace).
    void split(std::vector<HierarchyNode>& nodes, uint32_t i, Scratch& s, Part part, InPlace* in = nullptr) {
        const HierarchyNode node = nodes[i];
        if (node.count <= opt_.leafSize) return;
        if (opt_.kind == HierarchyKind::Connectivity && !in && node.count < kInPlaceNode) {
            splitInPlace(nodes, i, s, part);
            return;
        }
        const uint32_t k = std::min<uint32_t>(opt_.branching, node.count);
        // s.sizes is a stack: this node's children stay on it while their subtrees push theirs.
        const size_t base = s.sizes.size();
        if (in) {
            const uint32_t at = node.first - in->lo;
            partitionInPlace(s, *in, at, node.count, k, part.searched ? in->ord[at + node.count - 1] : kNone,
                             part.searched);
        } else if (opt_.kind == HierarchyKind::Connectivity) {
            const uint32_t hi = node.first + node.count;
            partition(s, node.first, hi, k, part.searched ? hi - 1 : kNone, part.searched, part.rows);
        } else {
            for (uint32_t c = 0; c < k; ++c)
                s.sizes.push_back({node.count / k + (c < node.count % k ? 1 : 0), false, 0});
        }

        const uint32_t firstChild = uint32_t(nodes.size());
        const uint32_t childCount = uint32_t(s.sizes.size() - base);
        nodes[i].firstChild = firstChild;
        nodes[i].childCount = childCount;
        uint32_t first = node.first;
        for (size_t c = base; c < s.sizes.size(); ++c) {
            const uint32_t size = s.sizes[c].size;
            CULLIDE_CHECK(size > 0 && size < node.count, "a child is smaller than its parent and not empty");
            nodes.push_back({first, size, 0, 0, node.depth + 1});
            first += size;
        }
        if (node.count < kParallelNode) {
            for (uint32_t c = 0; c < childCount; ++c) split(nodes, firstChild + c, s, s.sizes[base + c], in);
            s.sizes.resize(base);
            return;
        }
        // A node this large is the root or a parallel task's own root, so its scratch serves no
        // later sibling: its children work in slices of it. Child c's slices start c slacks after
        // its first position's, and hold its range and one slack more: disjoint.
        const size_t childSlack = s.slack / childCount;
        std::vector<Part> parts(s.sizes.begin() + std::ptrdiff_t(base), s.sizes.end());
        s.sizes.resize(base);
        std::vector<std::vector<HierarchyNode>> sub(childCount);
        parallelForEach(0, childCount, [&](size_t c) {
            sub[c] = {nodes[firstChild + c]};
            Scratch local;
            if (opt_.kind == HierarchyKind::Connectivity) {
                const size_t offset = sub[c][0].first - node.first;
                if (childSlack >= 1) {
                    local.queue = s.queue + offset + c * childSlack, local.slack = childSlack;
                } else {
                    local.allocate(sub[c][0].count);
                }
            }
            split(sub[c], 0, local, parts[c]);
        });
        for (uint32_t c = 0; c < childCount; ++c) {
            // Local index j >= 1 lands at nodes.size() + j - 1; leaves keep firstChild 0.
            const uint32_t shift = uint32_t(nodes.size()) - 1;
            auto shifted = [&](HierarchyNode n) {
                if (!n.isLeaf()) n.firstChild += shift;
                return n;
            };
            nodes[firstChild + c] = shifted(sub[c][0]);
            for (size_t j = 1; j < sub[c].size(); ++j) nodes.push_back(shifted(sub[c][j]));
        }
    }

    // Calls f(q) for the neighbours q of position p in the range [lo, hi), in increasing order
    // of triangle id, and for p itself in unused slots (p is labelled kVisited by then). `rows`:
    // the row array holding the range's rows.
    template <class F>
    void forNeighbours(const uint32_t* rows, uint32_t p, uint32_t lo, uint32_t hi, F&& f) const {
        const uint32_t* slot = rows + 3 * size_t(p);
        if (slot[0] != kEscape) {
            f(slot[0]), f(slot[1]), f(slot[2]);
            return;
        }
        for (uint32_t i = slot[1]; i < slot[1] + slot[2]; ++i) {
            // Relaxed: the neighbour may lie in a range another thread is renumbering (parallel
            // halves or subtrees); its old and new positions are both outside [lo, hi), so either
            // value gives the same test, but the read must not be a data race.
            const uint32_t q =
                std::atomic_ref<uint32_t>(const_cast<uint32_t&>(posOf_[overflow_[i]])).load(std::memory_order_relaxed);
            if (q >= lo && q < hi) f(q);
        }
    }

    // Breadth-first search over kOpen positions of [lo, hi), labelling them kVisited: the queue
    // holds [head, size); returns its new end. With `stop`, it expands only the positions before
    // queue index `stop` (the queue then holds all their neighbours). Branch-free: whether a
    // neighbour is open is a coin toss the branch predictor loses, so each neighbour is written at
    // the queue's end and kept only if it was open.
    // The row of the triangle 16 places ahead in the queue is prefetched: near the top of the
    // tree the rows lie beyond the caches, and the search would wait on each (5-10% of a 1M build).
    // A three-slot row reads its three labels before writing any: its entries are distinct but
    // for repeats of the position itself (kVisited, left as is), so no write changes a label read
    // after it, and the loads no longer wait on the stores (the compiler cannot know that).
    uint32_t grow(const uint32_t* rows, uint32_t* queue, uint32_t head, uint32_t size, uint32_t lo, uint32_t hi,
                  uint32_t stop = kNone) {
        uint32_t* mark = mark_.data();
        for (; head < size && head < stop; ++head) {
            if (head + 16 < size) __builtin_prefetch(rows + 3 * size_t(queue[head + 16]));
            const uint32_t* slot = rows + 3 * size_t(queue[head]);
            if (slot[0] != kEscape) {
                const uint32_t a = slot[0], b = slot[1], c = slot[2];
                const uint32_t la = mark[a], lb = mark[b], lc = mark[c];
                queue[size] = a;
                size += la == kOpen;
                queue[size] = b;
                size += lb == kOpen;
                queue[size] = c;
                size += lc == kOpen;
                mark[a] = la == kOpen ? kVisited : la;
                mark[b] = lb == kOpen ? kVisited : lb;
                mark[c] = lc == kOpen ? kVisited : lc;
                continue;
            }
            forNeighbours(rows, queue[head], lo, hi, [&](uint32_t u) {
                const uint32_t label = mark[u];
                queue[size] = u;
                size += label == kOpen;
                mark[u] = label == kOpen ? kVisited : label;
            });
        }
        return size;
    }

    // One bisection of a set of positions (the range [lo, hi) or, with `list`, the positions
    // list[0, n) inside it) into a first part of `target` positions or a few more and the rest:
    // writes the set's new order to s.queue[0, n) and returns the first part's size f. A set
    // given by a list is searched among labels the range's other positions hold (none kOpen, none
    // `first`): its rows reach the whole range. `first`: the label of the first part's positions
    // while the rest is searched.
    struct Bisection {
        uint32_t f;
        bool firstSearched, secondSearched;
    };
    Bisection bisect(Scratch& s, const uint32_t* rows, uint32_t* pieces, uint32_t lo, uint32_t hi, const uint32_t* list,
                     uint32_t n, uint32_t target, uint32_t hint, uint32_t first) {
        auto position = [&](uint32_t j) { return list ? list[j] : lo + j; };
        auto labelOpen = [&] {
            if (!list) {
                // (At the root this is also the first write of mark_: the threads share its page faults.)
                blocks(lo, hi, [&](uint32_t b, uint32_t e) { std::fill(mark_.begin() + b, mark_.begin() + e, kOpen); });
                return;
            }
            for (uint32_t j = 0; j < n; ++j) mark_[list[j]] = kOpen;
        };
        labelOpen();
        uint32_t seed = hint;
        if (seed == kNone) {
            // The position farthest in hops from the set's first one (ties: the last reached).
            uint32_t* queue = s.queue;
            queue[0] = position(0);
            mark_[queue[0]] = kVisited;
            seed = queue[grow(rows, queue, 0, 1, lo, hi) - 1];
            labelOpen();
        }
        uint32_t* bfs = s.queue;
        uint32_t size = 0, firstComponent = 0, pieceEnd = 0;
        // Labels bfs[0, size) as the first part (the first `target`) and the rest kOpen, then
        // finds the pieces of the rest, one after another in `pieces`, started in the order of bfs.
        auto findPieces = [&] {
            for (uint32_t i = 0; i < size; ++i) mark_[bfs[i]] = i < target ? first : kOpen;
            pieceEnd = 0;
            s.pieceStart.clear();
            for (uint32_t i = target; i < size; ++i) {
                if (mark_[bfs[i]] != kOpen) continue;
                s.pieceStart.push_back(pieceEnd);
                mark_[bfs[i]] = kVisited;
                pieces[pieceEnd++] = bfs[i];
                pieceEnd = grow(rows, pieces, pieceEnd - 1, pieceEnd, lo, hi);
            }
            s.pieceStart.push_back(pieceEnd);
        };
        // The search from the seed stops once the first part is expanded: the queue then holds
        // every neighbour of the first part, in the order the whole search would put them. Each
        // piece of the rest inside the seed's component is reached from the first part, so its
        // first position in the whole search is among those: the pieces, and their order, are the
        // whole search's. When they do not cover the rest (other components; rare: the halves
        // of a connected mesh are connected), the whole search runs after all. (This halves the
        // search from the seed: a third of a bisection's searches.)
        mark_[seed] = kVisited;
        bfs[size++] = seed;
        size = grow(rows, bfs, 0, size, lo, hi, target);
        bool whole = size <= target;  // the seed's component ends within the first part
        if (!whole) {
            firstComponent = size;  // at most its size; only target <= firstComponent is read
            findPieces();
            whole = pieceEnd != n - target;
        }
        if (whole) {
            // The whole search over the set: when a component is exhausted, go on from the
            // first unvisited position (in the set's order).
            labelOpen();
            size = 0, firstComponent = 0;
            uint32_t scan = 0, start = seed;
            while (size < n) {
                mark_[start] = kVisited;
                bfs[size++] = start;
                size = grow(rows, bfs, size - 1, size, lo, hi);
                if (firstComponent == 0) firstComponent = size;
                while (scan < n && mark_[position(scan)] != kOpen) ++scan;
                if (scan < n) start = position(scan);
            }
            findPieces();
        }
        const size_t pieceCount = s.pieceStart.size() - 1;
        auto pieceSize = [&](size_t p) { return s.pieceStart[p + 1] - s.pieceStart[p]; };
        size_t largest = 0;
        for (size_t p = 1; p < pieceCount; ++p)
            if (pieceSize(p) > pieceSize(largest)) largest = p;

        // The new order, in bfs: the first part (its prefix is in place), then the second.
        s.moved.assign(pieceCount, 0);
        uint32_t f = target, kept = uint32_t(pieceCount);
        for (size_t p = 0; p < pieceCount; ++p) {
            if (p == largest) continue;  // stays in the second part whatever it touches
            bool touchesFirst = false;
            for (uint32_t i = s.pieceStart[p]; i < s.pieceStart[p + 1] && !touchesFirst; ++i)
                forNeighbours(rows, pieces[i], lo, hi, [&](uint32_t u) { touchesFirst |= mark_[u] == first; });
            if (!touchesFirst) continue;
            s.moved[p] = 1;
            --kept;
            f = uint32_t(std::copy(pieces + s.pieceStart[p], pieces + s.pieceStart[p + 1], bfs + f) - bfs);
        }
        for (size_t p = 0, e = f; p < pieceCount; ++p)
            if (!s.moved[p]) e = std::copy(pieces + s.pieceStart[p], pieces + s.pieceStart[p + 1], bfs + e) - bfs;

        // Which parts are breadth-first orders of themselves from their first position, for the
        // nodes they may become (split() then needs no search for a peripheral start): the first
        // part when it is a prefix of the seed's search alone (the searches restricted to a prefix
        // of a breadth-first order find the prefix in the same order: each triangle of it is
        // reached from an earlier one), the second when it is one piece (its own search).
        return {f, target <= firstComponent && f == target, kept == 1};
    }

    // Whether a part of a bisection will be bisected again, or become a node that is split: only
    // then does it need rows.
    bool needsRows(uint32_t count, uint32_t k) const { return count > opt_.leafSize || (k >= 2 && count >= 2); }

    // Reorders the positions [lo, hi) into k consecutive parts (their sizes pushed on s.sizes),
    // each a compact patch connected through shared edges where the mesh allows: recursive
    // graph-growing bisection. The first part of a bisection is a prefix of the breadth-first
    // order from a pseudo-peripheral triangle (a prefix of a breadth-first order is connected),
    // sized in proportion to its share of the k parts; the second part is the rest, whose stray
    // pieces (cut off from its largest piece, so bordered by the first part) move to the first
    // part. Sizes are therefore near-equal, not exact.
    // `hint`: a position on the range's periphery, when the caller knows one (kNone otherwise).
    // `searched`: the range's order is a breadth-first order of the whole range from lo (pushed
    // with its size when the range is a part).
    // `r`: the row array holding the range's rows (rows_[r]); the halves' rows go to the other.
    void partition(Scratch& s, uint32_t lo, uint32_t hi, uint32_t k, uint32_t hint, bool searched, uint8_t r) {
        const uint32_t n = hi - lo;
        if (k < 2 || n < 2) {
            s.sizes.push_back({n, searched, r});
            return;
        }
        const uint32_t* rows = rows_[r].data();
        uint32_t* other = rows_[1 - r].data();
        const uint32_t half = k / 2;
        const uint32_t target = uint32_t(std::max<size_t>(1, size_t(n) * half / k));
        // The pieces go to the other row array's slots of the range, free until the halves' rows
        // are written there.
        const auto [f, firstSearched, secondSearched] =
            bisect(s, rows, other + 3 * size_t(lo), lo, hi, nullptr, n, target, hint, kFirst);
        uint32_t* bfs = s.queue;

        // Apply it. mark_ maps each old position to its new one, and the triangle ids and rows
        // are scattered by it (reading old positions in order, where a gather by new position
        // would read them at random). Each position writes entries of its own, so a large range
        // is applied in parallel blocks.
        blocks(lo, hi, [&](uint32_t b, uint32_t e) {
            for (uint32_t j = b; j < e; ++j) mark_[bfs[j - lo]] = j;
        });
        blocks(lo, hi, [&](uint32_t b, uint32_t e) {
            for (uint32_t p = b; p < e; ++p) bfs[mark_[p] - lo] = out_.order[p];  // bfs is read by now
        });
        blocks(lo, hi, [&](uint32_t b, uint32_t e) {
            std::copy(bfs + (b - lo), bfs + (e - lo), out_.order.begin() + b);
            if (!posOf_.empty())
                for (uint32_t p = b; p < e; ++p)  // read concurrently by forNeighbours of other ranges
                    std::atomic_ref<uint32_t>(posOf_[out_.order[p]]).store(p, std::memory_order_relaxed);
        });
        if (needsRows(f, half) || needsRows(n - f, k - half)) {
            // Each half's rows keep the neighbours in that half, in place (the position itself
            // elsewhere), written to the other row array: the halves read them from there.
            // Whether a neighbour q lies in np's half [a, a + w) is one unsigned comparison, and
            // the row is written without a branch on it (which went either way at a half's rim).
            // The arrays as locals: through the closure GCC reloaded them every position.
            const uint32_t mid = lo + f;
            const uint32_t* const mark = mark_.data();
            blocks(lo, hi, [=](uint32_t begin, uint32_t end) {
                for (uint32_t p = begin; p < end; ++p) {
                    const uint32_t np = mark[p];
                    const uint32_t a = np < mid ? lo : mid, w = np < mid ? mid - lo : hi - mid;
                    const uint32_t* slot = rows + 3 * size_t(p);
                    uint32_t* out = other + 3 * size_t(np);
                    if (slot[0] == kEscape) {
                        std::copy(slot, slot + 3, out);
                        continue;
                    }
                    const uint32_t q0 = mark[slot[0]], q1 = mark[slot[1]], q2 = mark[slot[2]];
                    out[0] = q0 - a < w ? q0 : np;
                    out[1] = q1 - a < w ? q1 : np;
                    out[2] = q2 - a < w ? q2 : np;
                }
            });
        }

        // Peripheral starts for the halves, for free: the first part is a ball around the seed
        // whose last-reached triangle lies on its rim; the second part's first triangle borders
        // the first part. (The second part is a breadth-first order too, so its rim is its end.)
        // Two large halves that are both bisected again are partitioned in parallel (at the top
        // of the tree there are fewer nodes than threads), each in a slice of the scratch (as
        // split() slices it for children) and with a stack of its own, the second's parts pushed
        // after the first's: the same parts in the same order.
        const size_t g = s.slack / 2;
        if (n >= kParallelNode && half >= 2 && f >= 2 && n - f >= 2 && g >= 1) {
            Scratch first, second;
            first.queue = s.queue, first.slack = g;
            second.queue = s.queue + f + g, second.slack = g;
            parallelForEach(0, 2, [&](size_t i) {
                if (i == 0) partition(first, lo, lo + f, half, lo + f - 1, firstSearched, uint8_t(1 - r));
                else partition(second, lo + f, hi, k - half, hi - 1, secondSearched, uint8_t(1 - r));
            });
            s.sizes.insert(s.sizes.end(), first.sizes.begin(), first.sizes.end());
            s.sizes.insert(s.sizes.end(), second.sizes.begin(), second.sizes.end());
            return;
        }
        partition(s, lo, lo + f, half, lo + f - 1, firstSearched, uint8_t(1 - r));
        partition(s, lo + f, hi, k - half, hi - 1, secondSearched, uint8_t(1 - r));
    }

    // Calls body(b, e) on blocks [b, e) covering [lo, hi): in parallel for a large range, whose
    // passes would otherwise leave all but one thread idle at the top of the tree.
    template <class Body>
    static void blocks(uint32_t lo, uint32_t hi, const Body& body) {
        if (hi - lo < kParallelNode) {
            body(lo, hi);
            return;
        }
        parallelFor(lo, hi, kParallelNode / 4,
                    [&](const tbb::blocked_range<size_t>& r) { body(uint32_t(r.begin()), uint32_t(r.end())); });
    }

    static constexpr uint32_t kOpen = kNone - 1, kVisited = kNone - 2, kFirst = kNone - 3;
    static constexpr uint32_t kEscape = kNone;  // slot 0 of a row kept in overflow_

    const Mesh& mesh_;
    HierarchyOptions opt_;
    Hierarchy& out_;
    std::mt19937_64 rng_;
    Scratch root_;  // the root's, and every subtree's split on this thread
    // Connectivity only, shared by parallel subtrees. By position: rows_ (rows, 3 each: a range's
    // in one of the two, its halves' in the other; the second is the incidence array), mark_
    // (labels during a bisection, then old -> new position). By triangle id, only when some row
    // overflows: posOf_. rows_ and mark_ start unwritten (cullide/unwritten.h; zeroing the
    // arrays of n or 3n entries was 12% of a 1M build).
    Pages<uint32_t> rows_[2], mark_;
    Pages<uint32_t> queue_;  // the root's scratch, sliced for parallel subtrees
    std::vector<uint32_t> overflow_, posOf_;
};

}  // namespace

Hierarchy buildHierarchy(const Mesh& mesh, const HierarchyOptions& options) {
    if (options.leafSize < 1) throw InputError("hierarchy options", "leaf size must be at least 1");
    if (options.branching < 2) throw InputError("hierarchy options", "branching must be at least 2");
    Hierarchy h;
    Builder(mesh, options, h).build();
    return h;
}

bool operator==(const HierarchyOptions& a, const HierarchyOptions& b) {
    return a.kind == b.kind && a.leafSize == b.leafSize && a.branching == b.branching && a.seed == b.seed;
}

void HierarchyCache::resize(size_t objects) {
    entries_.resize(objects);
}

const Hierarchy& HierarchyCache::get(size_t object, const Mesh& mesh, const HierarchyOptions& options) {
    CULLIDE_CHECK(object < entries_.size(), "HierarchyCache::get on an object beyond resize()");
    Entry& e = entries_[object];
    e.reused = e.valid && e.options == options && e.vertexCount == mesh.positions.size() &&
        std::equal(e.triangles.begin(), e.triangles.end(), mesh.triangles.begin(), mesh.triangles.end());
    if (!e.reused) {
        e.valid = false;  // a throwing build leaves no stale entry
        e.hierarchy = buildHierarchy(mesh, options);
        e.triangles = mesh.triangles;
        e.vertexCount = mesh.positions.size();
        e.options = options;
        e.valid = true;
    }
    return e.hierarchy;
}

}  // namespace cullide
