// The connectivity hierarchy's builder (hierarchy.h): the arrays it shares between threads, its
// per-thread scratch, and the searches every step of the build runs (inline: they are the build's
// inner loops). Private to core/. Its files: hierarchy_tree.cpp (the tree: build, split),
// hierarchy_adjacency.cpp (the face adjacency and the renumbering of scattered meshes),
// hierarchy_bisection.cpp (partition: recursive graph-growing bisection).
#pragma once

#include "cullide/hierarchy.h"
#include "cullide/parallel.h"
#include "cullide/unwritten.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace cullide::detail::hierarchy {

inline constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Builds the hierarchy over flat arrays sized once per build (no allocation per node).
//
// Connectivity works on a list of the triangles, out_.order: a node, and every part of its
// recursive bisection, is a segment of it, and a bisection reorders its segment (the hierarchy's
// order is then the list). Neither triangles nor their face adjacency (their rows) move: a
// search keeps to its part by labels (no triangle outside it is kOpen or carries its bisection's
// first-part label), and where parts are split in parallel (nodes of kParallelNode triangles and
// more) the rows on the cut between a bisection's halves lose their neighbours across it, so
// that no search reads another thread's labels. So a bisection writes only the cut rows, and its
// cost is its searches (moving each bisection's triangles and rebuilding its halves' rows cost a
// third of each level's cycles).
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
// first write (on a virtual machine ~17 us per 4 KiB page, 4 ms per MiB): subtrees' own scratch
// (40 MB in 4 KiB-page arrays for 1M triangles) was about a fifth of a 1M build. The memory is the same: a parent's scratch was freed before its
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
inline constexpr uint32_t kParallelNode = 1 << 16;

// A bisection of a segment in progress: what partition's steps hand each other (partition()).
struct Bisection {
    uint32_t* list;  // the segment: out_.order[at, at + n)
    uint32_t* pieces;  // the pieces of its second part: pieces_[at, at + n)
    uint32_t n, target;  // the segment's size; the first part's size before stray pieces join it
    uint32_t first;  // the first part's label
    uint32_t size = 0, firstComponent = 0;  // the search from the seed: Scratch::queue[0, size)
    uint32_t levels[3] = {0, 0, 0};  // the first part's last levels' starts (Part::rim)
    bool whole = false;  // the search ran over the whole segment (not only to the first part)
    size_t pieceCount = 0;  // the pieces of the rest (Scratch::pieceStart)
    uint32_t f = 0, kept = 0;  // the first part's size, stray pieces included; the pieces left
};

class Builder {
public:
    Builder(const Mesh& mesh, const HierarchyOptions& options, Hierarchy& out)
        : mesh_(mesh), opt_(options), out_(out), rng_(options.seed) {}

    void build();

private:
    uint32_t uniform(uint32_t bound) {  // in [0, bound), by rejection: unbiased, portable
        const uint64_t limit = std::numeric_limits<uint64_t>::max() - std::numeric_limits<uint64_t>::max() % bound;
        uint64_t x;
        do x = rng_();
        while (x >= limit);
        return uint32_t(x % bound);
    }

    // The face adjacency (hierarchy_adjacency.cpp).
    void buildAdjacency();
    bool scattered() const;
    void compact();

    // The tree (hierarchy_tree.cpp).
    void split(std::vector<HierarchyNode>& nodes, uint32_t i, Scratch& s, Part part);

    // The bisections (hierarchy_bisection.cpp).
    void partition(Scratch& s, uint32_t at, uint32_t n, uint32_t k, uint32_t hint, Part self, bool isolate);
    void labelOpen(const uint32_t* list, uint32_t n);
    uint32_t peripheralSeed(Scratch& s, const uint32_t* list, uint32_t n, const Part& self);
    void searchFromSeed(Scratch& s, Bisection& b, uint32_t seed);
    void wholeSearch(Scratch& s, Bisection& b, uint32_t seed);
    uint32_t findPieces(Scratch& s, const uint32_t* bfs, uint32_t size, uint32_t target, uint32_t first,
                        uint32_t* pieces);
    void joinStrayPieces(Scratch& s, Bisection& b);
    void cutAtFirstPart(const Scratch& s, const Bisection& b);
    void writeOrder(const Scratch& s, const Bisection& b);
    void cutBetweenHalves(const Bisection& bisection);
    static std::pair<Part, Part> halves(const Bisection& b);
    void partitionHalves(Scratch& s, uint32_t at, const Bisection& b, uint32_t k, Part one, Part two, bool isolate);

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

}  // namespace cullide::detail::hierarchy
