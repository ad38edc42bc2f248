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
// Connectivity works on a list of the triangles, out_.order: a node, and every part of its
// recursive bisection, is a segment of it, and a bisection reorders its segment (the hierarchy's
// order is then the list). Neither triangles nor their face adjacency (their rows) move: a
// search keeps to its part by labels (no triangle outside it is kOpen or carries its bisection's
// first-part label), and where parts are split in parallel (nodes of kParallelNode triangles and
// more) the rows on the cut between a bisection's halves lose their neighbours across it, so
// that no search reads another thread's labels. So a bisection writes only the cut rows, and its
// cost is its searches. (Until session 22 every bisection moved its triangles and rebuilt its
// halves' rows into a second array, a third of each level's cycles; the build is the same.)
//
// A row is three slots (a triangle has three edges), unused ones holding the triangle itself: a
// triangle is labelled kVisited before its row is read, so it never passes for an open or first
// neighbour; searches run without branches on row lengths. (One shared sentinel would chain
// every search step through its label.) A triangle with more than three neighbours (on a
// non-manifold edge) has slot 0 = kEscape and its neighbours in overflow_ (slots 1, 2: offset
// and count), restricted as the slots are.
// The build's arrays: written before they are read, and mapped with pages of their own, so that
// the scratch a parallel subtree frees goes back to the system (cullide/unwritten.h).
template <typename T>
using Pages = UnwrittenVector<T, true>;

// A part of a node's partition: its size, and what its order tells of the search from its first
// triangle, for the node it may become (see partition()):
// - searched: the order is a breadth-first order of the whole part from its first triangle;
// - ball: the order is a ball, a prefix of a breadth-first search from its first triangle over the
//   segment the part was cut from, followed by stray pieces that touch it. rim: where the ball's
//   last levels start in the order (the levels D - 2, D - 1 and D, the last, clamped at 0; for a
//   ball of one level {0, 0, 1}).
struct Part {
    uint32_t size;
    bool searched;
    bool ball = false;
    uint32_t rim[3] = {};
};

// What one thread's splits write besides the shared arrays, indexed from the start of the segment
// being split: queue (a bisection's breadth-first order, then the segment's new order), and the
// small stacks. (A bisection's pieces go to Builder::pieces_ at the segment's offset.)
//
// The queue is a view: the root's is the build's own (Builder::queue_), and a parallel subtree's
// is a slice of its parent's, not an array of its own. Fresh pages cost a page fault each on
// first write, and on the shared build machine's VM a 4 KiB fault costs ~17 us
// (4 ms per MiB): the subtrees' own scratch (40 MB in 4 KiB-page arrays for 1M triangles) was
// about a fifth of a 1M build. The memory is the same: a parent's scratch was freed before its
// children allocated theirs, as large together.
// For a segment of m triangles, queue holds m + slack entries (a search writes one past its last
// entry, so slack >= 1, and siblings' slices must not overlap there).
struct Scratch {
    uint32_t* queue = nullptr;
    size_t slack = 0;
    std::vector<Part> sizes;
    std::vector<uint32_t> pieceStart;
    std::vector<uint8_t> moved;
    uint32_t labels = 0;  // first-part labels used: the next is Builder::kFirst - labels
    Pages<uint32_t> ownQueue;  // only where the parent's slack ran out

    void allocate(uint32_t n) {  // a queue of its own, for segments of up to n triangles
        ownQueue.resize(size_t(n) + 1);
        queue = ownQueue.data(), slack = 1;
    }
};

// Nodes of at least this many triangles split their children in parallel (a 1M-triangle build
// has 16 such nodes at leaf size 16, branching 4; smaller subtrees are not worth a task).
constexpr uint32_t kParallelNode = 1 << 16;

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
            // Each bisection has a first-part label of its own, counting down from kFirst.
            CULLIDE_CHECK(n < kFirst / 2, "triangle count leaves room for the labels");
            // Slack for a slice per parallel subtree: each level of parallel subtrees divides it
            // by the branching (a 1M build has two such levels); where it runs out, a subtree
            // allocates its own scratch.
            const size_t slack = 1 + n / 1024;
            queue_.resize(n + slack);
            buildAdjacency();
            mark_.resize(n);
            root_.queue = queue_.data(), root_.slack = slack;
        }
        const bool compacted = opt_.kind == HierarchyKind::Connectivity && scattered();
        if (compacted) compact();
        split(out_.nodes, 0, root_, {n, false});
        if (!compacted) return;
        // The list holds positions (compact()): their triangles.
        const uint32_t* triangleAt = pieces_.data() + n;
        blocks(0, n, [&](uint32_t b, uint32_t e) {
            for (uint32_t j = b; j < e; ++j) out_.order[j] = triangleAt[out_.order[j]];
        });
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
    // triangles sharing edge (a, b) are among those incident to a.
    //
    // The incidence is built by the two halves of the triangles at once, each counting and then
    // filling in its own triangles, the second half's after the first's in each vertex's list: the
    // lists are in increasing triangle order, as one pass makes them, whatever the threads. (One
    // pass, serial, was a tenth of a 1M build's wall time on two threads; the halves took 21-23 ->
    // 9-12 ms there.) Their counts live in the root's queue where they fit, and the incidence array
    // becomes the pieces' scratch: both are then written for the first time here, and their page
    // faults are paid once.
    void buildAdjacency() {
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
    bool scattered() const {
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
    void compact() {
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

    // Splits nodes[i] and its descendants, appending them to `nodes` depth first: a node's
    // children are contiguous, followed by the first child's descendants, then the second's, ...
    //
    // A large node's children are split in parallel, each subtree in a list of its own (its root
    // at 0, its descendants after it) with scratch of its own, then appended in child order with
    // their indices shifted: the same nodes, in the same order, as one thread would make. The
    // subtrees' segments are disjoint and their rows restricted to them, so they share the arrays
    // (each writes only its own triangles' entries).
    //
    // `part`: the node as a part of its parent's partition. part.searched: the node's order is a
    // breadth-first order of the whole node from its first triangle, so that search's farthest
    // triangle is known: the last one.
    void split(std::vector<HierarchyNode>& nodes, uint32_t i, Scratch& s, Part part) {
        const HierarchyNode node = nodes[i];
        if (node.count <= opt_.leafSize) return;
        const uint32_t k = std::min<uint32_t>(opt_.branching, node.count);
        // s.sizes is a stack: this node's children stay on it while their subtrees push theirs.
        const size_t base = s.sizes.size();
        if (opt_.kind == HierarchyKind::Connectivity) {
            const uint32_t last = out_.order[node.first + node.count - 1];
            const bool root = node.count == mark_.size();
            partition(s, node.first, node.count, k,
                      part.searched ? last
                          : root    ? rootSeed_
                                    : kNone,
                      part, node.count >= kParallelNode);
        } else {
            for (uint32_t c = 0; c < k; ++c) s.sizes.push_back({node.count / k + (c < node.count % k ? 1 : 0), false});
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
            for (uint32_t c = 0; c < childCount; ++c) split(nodes, firstChild + c, s, s.sizes[base + c]);
            s.sizes.resize(base);
            return;
        }
        // A node this large is the root or a parallel task's own root, so its scratch serves no
        // later sibling: its children work in slices of it. Child c's slice starts c slacks after
        // its segment's offset, and holds its segment and one slack more: disjoint.
        const size_t childSlack = s.slack / childCount;
        std::vector<Part> parts(s.sizes.begin() + std::ptrdiff_t(base), s.sizes.end());
        s.sizes.resize(base);
        std::vector<std::vector<HierarchyNode>> sub(childCount);
        parallelForEach(0, childCount, [&](size_t c) {
            sub[c] = {nodes[firstChild + c]};
            Scratch local;
            local.labels = s.labels;
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

    // Calls f(q) for the neighbours q of triangle p in its part, in increasing order, and for p
    // itself in unused slots (p is labelled kVisited by then).
    template <class F>
    void forNeighbours(uint32_t p, F&& f) const {
        const uint32_t* slot = rows_.data() + 3 * size_t(p);
        if (slot[0] != kEscape) {
            f(slot[0]), f(slot[1]), f(slot[2]);
            return;
        }
        for (uint32_t i = slot[1]; i < slot[1] + slot[2]; ++i) f(overflow_[i]);
    }

    // Breadth-first search over kOpen triangles, labelling them kVisited: the queue holds [head,
    // size); returns its new end. With `stop`, it expands only the triangles before queue index
    // `stop` (the queue then holds all their neighbours). Branch-free: whether a neighbour is open
    // is a coin toss the branch predictor loses, so each neighbour is written at the queue's end
    // and kept only if it was open.
    // The row of the triangle 16 places ahead in the queue is prefetched: near the top of the
    // tree the rows lie beyond the caches, and the search would wait on each (5-10% of a 1M build).
    // A three-slot row reads its three labels before writing any: its entries are distinct but
    // for repeats of the triangle itself (kVisited, left as is), so no write changes a label read
    // after it, and the loads no longer wait on the stores (the compiler cannot know that).
    // kLevels: with a search from one triangle (head 0, size 1) and levels[0, 3) zero, levels are
    // then where the last three levels it expanded start (oldest first; 0 for levels before the
    // first).
    template <bool kLevels = false>
    uint32_t grow(uint32_t* queue, uint32_t head, uint32_t size, uint32_t stop = kNone, uint32_t* levels = nullptr) {
        const uint32_t* rows = rows_.data();
        uint32_t* mark = mark_.data();
        uint32_t levelEnd = size;
        for (; head < size && head < stop; ++head) {
            if constexpr (kLevels) {
                if (head == levelEnd) {
                    levels[0] = levels[1], levels[1] = levels[2], levels[2] = head;
                    levelEnd = size;
                }
            }
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
            forNeighbours(queue[head], [&](uint32_t u) {
                const uint32_t label = mark[u];
                queue[size] = u;
                size += label == kOpen;
                mark[u] = label == kOpen ? kVisited : label;
            });
        }
        return size;
    }

    // Replaces neighbour q in p's row by p itself (p's side of a cut edge).
    void cut(uint32_t p, uint32_t q) {
        uint32_t* slot = rows_.data() + 3 * size_t(p);
        if (slot[0] != kEscape) {
            for (int k = 0; k < 3; ++k) slot[k] = slot[k] == q ? p : slot[k];
            return;
        }
        for (uint32_t i = slot[1]; i < slot[1] + slot[2]; ++i) overflow_[i] = overflow_[i] == q ? p : overflow_[i];
    }

    // Whether a part of a bisection will be bisected again, or become a node that is split: only
    // then does it need its rows.
    bool needsRows(uint32_t count, uint32_t k) const { return count > opt_.leafSize || (k >= 2 && count >= 2); }

    // Reorders the segment out_.order[at, at + n) into k consecutive parts (their sizes pushed on
    // s.sizes), each a compact patch connected through shared edges where the mesh allows:
    // recursive graph-growing bisection. The first part of a bisection is a prefix of the
    // breadth-first order from a pseudo-peripheral triangle (a prefix of a breadth-first order is
    // connected), sized in proportion to its share of the k parts; the second part is the rest,
    // whose stray pieces (cut off from its largest piece, so bordered by the first part) move to
    // the first part. Sizes are therefore near-equal, not exact.
    // `hint`: a triangle on the segment's periphery, when the caller knows one (kNone otherwise).
    // `self`: what is known of the segment's order (pushed with its size when the segment is a
    // part; Part).
    void partition(Scratch& s, uint32_t at, uint32_t n, uint32_t k, uint32_t hint, Part self, bool isolate) {
        if (k < 2 || n < 2) {
            self.size = n;
            s.sizes.push_back(self);
            return;
        }
        const uint32_t half = k / 2;
        const uint32_t target = uint32_t(std::max<size_t>(1, size_t(n) * half / k));
        uint32_t* const list = out_.order.data() + at;
        const uint32_t first = kFirst - s.labels++;
        uint32_t* const pieces = pieces_.data() + at;
        auto labelOpen = [&] {
            blocks(0, n, [&](uint32_t b, uint32_t e) {
                for (uint32_t j = b; j < e; ++j) mark_[list[j]] = kOpen;
            });
        };
        labelOpen();
        uint32_t seed = hint;
        if (seed == kNone) {
            // The triangle farthest in hops from the segment's first one (ties: the last reached).
            uint32_t* queue = s.queue;
            if (self.ball) {
                // A ball B of the search from the first triangle over a larger segment, then stray
                // pieces M that touch it. The search over B + M goes as that search did until it
                // expands a triangle next to M: B's triangles come in the same order, from the
                // same triangles (any other way to them would run through triangles reached after
                // them). And no triangle of B next to M lies before the ball's last level D but
                // one: M was not reached before the ball ended, and neighbours' hops differ by at
                // most one. So the search can resume where the other began to expand level D - 1:
                // its queue then held the levels up to D - 1, and from there on it reads the
                // labels of levels D - 2 and later only. (In the 1M bunny's build every node but
                // the root that needs a seed was cut from a ball: their searches over 2.17M
                // triangles in all now reach 0.25M, and the build takes 6-9% less time.)
                const uint32_t* rim = self.rim;
                for (uint32_t j = rim[0]; j < rim[2]; ++j) mark_[list[j]] = kVisited;
                std::copy(list + rim[1], list + rim[2], queue);
                seed = queue[grow(queue, 0, rim[2] - rim[1]) - 1];
            } else {
                queue[0] = list[0];
                mark_[queue[0]] = kVisited;
                seed = queue[grow(queue, 0, 1) - 1];
            }
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
                pieceEnd = grow(pieces, pieceEnd - 1, pieceEnd);
            }
            s.pieceStart.push_back(pieceEnd);
        };
        // The search from the seed stops once the first part is expanded: the queue then holds
        // every neighbour of the first part, in the order the whole search would put them. Each
        // piece of the rest inside the seed's component is reached from the first part, so its
        // first triangle in the whole search is among those: the pieces, and their order, are the
        // whole search's. When they do not cover the rest (other components; rare: the halves
        // of a connected mesh are connected), the whole search runs after all. (This halves the
        // search from the seed: a third of a bisection's searches.)
        mark_[seed] = kVisited;
        bfs[size++] = seed;
        uint32_t levels[3] = {0, 0, 0};  // the first part's last levels' starts (Part::rim)
        size = grow<true>(bfs, 0, size, target, levels);
        bool whole = size <= target;  // the seed's component ends within the first part
        if (!whole) {
            firstComponent = size;  // at most its size; only target <= firstComponent is read
            findPieces();
            whole = pieceEnd != n - target;
        }
        if (whole) {
            // The whole search over the segment: when a component is exhausted, go on from the
            // first unvisited triangle in the segment's order.
            labelOpen();
            size = 0, firstComponent = 0;
            uint32_t scan = 0, start = seed;
            while (size < n) {
                mark_[start] = kVisited;
                bfs[size++] = start;
                size = grow(bfs, size - 1, size);
                if (firstComponent == 0) firstComponent = size;
                while (scan < n && mark_[list[scan]] != kOpen) ++scan;
                if (scan < n) start = list[scan];
            }
            findPieces();
        }
        const size_t pieceCount = s.pieceStart.size() - 1;
        auto pieceSize = [&](size_t p) { return s.pieceStart[p + 1] - s.pieceStart[p]; };
        size_t largest = 0;
        for (size_t p = 1; p < pieceCount; ++p)
            if (pieceSize(p) > pieceSize(largest)) largest = p;

        // The stray pieces that touch the first part join it.
        s.moved.assign(pieceCount, 0);
        uint32_t f = target, kept = uint32_t(pieceCount);
        for (size_t p = 0; p < pieceCount; ++p) {
            if (p == largest) continue;  // stays in the second part whatever it touches
            bool touchesFirst = false;
            for (uint32_t i = s.pieceStart[p]; i < s.pieceStart[p + 1] && !touchesFirst; ++i)
                forNeighbours(pieces[i], [&](uint32_t u) { touchesFirst |= mark_[u] == first; });
            if (!touchesFirst) continue;
            s.moved[p] = 1;
            --kept;
            f += pieceSize(p);
        }

        // Where the parts of this node's partition are split in parallel (isolate), the rows are
        // cut between the halves, where the halves are bisected again or split: no search of one
        // part then reads another's labels. The cut edges join the seed's search's first `target`
        // triangles (labelled `first`) to the kept pieces (the stray pieces that move touch no
        // other piece: pieces are the components of the rest); a kept piece's triangle on such an
        // edge is a neighbour of the first part, so it is in bfs[target, size). So only those few
        // rows are cut, once the moved pieces are labelled `first` too. After the whole search
        // (several components, rare) bfs holds every triangle, and every row of the segment keeps
        // only the neighbours labelled as itself once the halves are labelled (below).
        // Elsewhere the rows reach beyond a part, and its searches stay inside by labels alone:
        // one thread splits the parts one after another, so no triangle outside the part being
        // split is kOpen, and none is labelled with its bisection's `first`. (Cutting every
        // bisection's rows made the 5k bunny's build 8% slower.)
        const bool rowsNeeded = isolate && (needsRows(f, half) || needsRows(n - f, k - half));
        if (rowsNeeded && !whole) {
            for (size_t p = 0; p < pieceCount; ++p)
                if (s.moved[p])
                    for (uint32_t i = s.pieceStart[p]; i < s.pieceStart[p + 1]; ++i) mark_[pieces[i]] = first;
            for (uint32_t i = target; i < size; ++i) {
                const uint32_t p = bfs[i];
                if (mark_[p] == first) continue;  // in a moved piece
                forNeighbours(p, [&](uint32_t q) {
                    if (mark_[q] != first) return;
                    cut(p, q);
                    cut(q, p);
                });
            }
        }

        // The new order, into the list: the first part (the seed's search's prefix, then the
        // moved pieces), then the second.
        std::copy(bfs, bfs + target, list);
        for (size_t p = 0, e = target; p < pieceCount; ++p)
            if (s.moved[p]) e = std::copy(pieces + s.pieceStart[p], pieces + s.pieceStart[p + 1], list + e) - list;
        for (size_t p = 0, e = f; p < pieceCount; ++p)
            if (!s.moved[p]) e = std::copy(pieces + s.pieceStart[p], pieces + s.pieceStart[p + 1], list + e) - list;
        if (rowsNeeded && whole) {
            blocks(0, n, [&](uint32_t b, uint32_t e) {
                for (uint32_t j = b; j < e; ++j) mark_[list[j]] = j < f ? first : kVisited;
            });
            blocks(0, n, [&](uint32_t b, uint32_t e) {
                for (uint32_t j = b; j < e; ++j) {
                    const uint32_t p = list[j], label = mark_[p];
                    forNeighbours(p, [&](uint32_t q) {
                        if (mark_[q] != label) cut(p, q);
                    });
                }
            });
        }

        // Peripheral starts for the halves, for free: the first part is a ball around the seed
        // whose last-reached triangle lies on its rim; the second part's first triangle borders
        // the first part. (The second part is a breadth-first order too, so its rim is its end.)
        //
        // Which halves are breadth-first orders of themselves from their first triangle, for the
        // nodes they may become (split() then needs no search for a peripheral start): the first
        // part when it is a prefix of the seed's search alone (the searches restricted to a prefix
        // of a breadth-first order find the prefix in the same order: each triangle of it is
        // reached from an earlier one), the second when it is one piece (its own search). A first
        // part that took stray pieces is a ball (Part): a node made of it resumes that search.
        const bool firstSearched = target <= firstComponent && f == target, secondSearched = kept == 1;
        Part one{f, firstSearched}, two{n - f, secondSearched};
        if (!whole && !firstSearched) {  // the seed's search's prefix and the moved pieces
            // Levels before the first start at 0, so they clamp themselves; a ball of one level
            // (the seed) ends at 1.
            one.ball = true;
            one.rim[0] = levels[0], one.rim[1] = levels[1], one.rim[2] = std::max(levels[2], 1u);
        }
        // Two large halves that are both bisected again are partitioned in parallel (at the top
        // of the tree there are fewer nodes than threads), each in a slice of the scratch (as
        // split() slices it for children) and with a stack of its own, the second's parts pushed
        // after the first's: the same parts in the same order.
        const size_t g = s.slack / 2;
        if (n >= kParallelNode && half >= 2 && f >= 2 && n - f >= 2 && g >= 1) {
            Scratch sOne, sTwo;
            sOne.queue = s.queue, sOne.slack = g, sOne.labels = s.labels;
            sTwo.queue = s.queue + f + g, sTwo.slack = g, sTwo.labels = s.labels;
            parallelForEach(0, 2, [&](size_t i) {
                if (i == 0) partition(sOne, at, f, half, list[f - 1], one, isolate);
                else partition(sTwo, at + f, n - f, k - half, list[n - 1], two, isolate);
            });
            s.labels = std::max(sOne.labels, sTwo.labels);  // none used twice in this subtree
            s.sizes.insert(s.sizes.end(), sOne.sizes.begin(), sOne.sizes.end());
            s.sizes.insert(s.sizes.end(), sTwo.sizes.begin(), sTwo.sizes.end());
            return;
        }
        partition(s, at, f, half, list[f - 1], one, isolate);
        partition(s, at + f, n - f, k - half, list[n - 1], two, isolate);
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
    // Connectivity only, shared by parallel subtrees, by triangle (by position once compact()
    // renumbered them): rows_ (3 each), mark_ (labels during a bisection), pieces_ (by the
    // segment's offset). They start unwritten
    // (cullide/unwritten.h; zeroing the arrays of n or 3n entries was 12% of a 1M build).
    Pages<uint32_t> rows_, mark_, pieces_;
    uint32_t rootSeed_ = kNone;  // the root's peripheral start (compact())
    Pages<uint32_t> queue_;  // the root's scratch, sliced for parallel subtrees
    std::vector<uint32_t> overflow_;
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
