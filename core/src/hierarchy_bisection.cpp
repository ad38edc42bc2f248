// The connectivity hierarchy's bisections (Builder::partition, hierarchy_builder.h): recursive
// graph-growing bisection of a segment of the list into a node's parts, as named steps.
#include "hierarchy_builder.h"

#include <algorithm>

namespace cullide::detail::hierarchy {

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
// The steps: a peripheral seed (peripheralSeed, unless `hint` is one), the search from it and
// the pieces of the rest (searchFromSeed), the stray pieces that join the first part
// (joinStrayPieces), the rows cut between the halves where they are split in parallel
// (cutAtFirstPart, cutBetweenHalves), the new order (writeOrder), and the halves' own
// partitions (partitionHalves).
void Builder::partition(Scratch& s, uint32_t at, uint32_t n, uint32_t k, uint32_t hint, Part self, bool isolate) {
    if (k < 2 || n < 2) {
        self.size = n;
        s.sizes.push_back(self);
        return;
    }
    const uint32_t half = k / 2;
    Bisection b;
    b.list = out_.order.data() + at;
    b.pieces = pieces_.data() + at;
    b.n = n;
    b.target = uint32_t(std::max<size_t>(1, size_t(n) * half / k));
    b.first = kFirst - s.labels++;
    labelOpen(b.list, n);
    const uint32_t seed = hint != kNone ? hint : peripheralSeed(s, b.list, n, self);
    searchFromSeed(s, b, seed);
    joinStrayPieces(s, b);

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
    const bool rowsNeeded = isolate && (needsRows(b.f, half) || needsRows(n - b.f, k - half));
    if (rowsNeeded && !b.whole) cutAtFirstPart(s, b);
    writeOrder(s, b);
    if (rowsNeeded && b.whole) cutBetweenHalves(b);
    const auto [one, two] = halves(b);
    partitionHalves(s, at, b, k, one, two, isolate);
}

// Labels the segment list[0, n) kOpen.
void Builder::labelOpen(const uint32_t* list, uint32_t n) {
    blocks(0, n, [&](uint32_t b, uint32_t e) {
        for (uint32_t j = b; j < e; ++j) mark_[list[j]] = kOpen;
    });
}

// The triangle farthest in hops from the segment's first one (ties: the last reached), for a
// segment labelled kOpen; leaves it labelled kOpen again. `self`: what is known of the segment's
// order (Part).
uint32_t Builder::peripheralSeed(Scratch& s, const uint32_t* list, uint32_t n, const Part& self) {
    uint32_t seed;
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
        // triangles in all reach 0.25M this way, and the build takes 6-9% less time.)
        const uint32_t* rim = self.rim;
        for (uint32_t j = rim[0]; j < rim[2]; ++j) mark_[list[j]] = kVisited;
        std::copy(list + rim[1], list + rim[2], queue);
        seed = queue[grow(queue, 0, rim[2] - rim[1]) - 1];
    } else {
        queue[0] = list[0];
        mark_[queue[0]] = kVisited;
        seed = queue[grow(queue, 0, 1) - 1];
    }
    labelOpen(list, n);
    return seed;
}

// The search from the seed stops once the first part is expanded: the queue then holds
// every neighbour of the first part, in the order the whole search would put them. Each
// piece of the rest inside the seed's component is reached from the first part, so its
// first triangle in the whole search is among those: the pieces, and their order, are the
// whole search's. When they do not cover the rest (other components; rare: the halves
// of a connected mesh are connected), the whole search runs after all. (This halves the
// search from the seed: a third of a bisection's searches.)
void Builder::searchFromSeed(Scratch& s, Bisection& b, uint32_t seed) {
    const uint32_t n = b.n, target = b.target;
    uint32_t* bfs = s.queue;
    uint32_t size = 0, firstComponent = 0, pieceEnd = 0;
    mark_[seed] = kVisited;
    bfs[size++] = seed;
    uint32_t levels[3] = {0, 0, 0};  // the first part's last levels' starts (Part::rim)
    size = grow<true>(bfs, 0, size, target, levels);
    bool whole = size <= target;  // the seed's component ends within the first part
    if (!whole) {
        firstComponent = size;  // at most its size; only target <= firstComponent is read
        pieceEnd = findPieces(s, bfs, size, target, b.first, b.pieces);
        whole = pieceEnd != n - target;
    }
    b.size = size, b.firstComponent = firstComponent, b.whole = whole;
    std::copy(levels, levels + 3, b.levels);
    if (whole) wholeSearch(s, b, seed);
}

// The whole search over the segment: when a component is exhausted, go on from the first unvisited
// triangle in the segment's order. Then the pieces of the rest, as searchFromSeed finds them.
void Builder::wholeSearch(Scratch& s, Bisection& b, uint32_t seed) {
    const uint32_t n = b.n;
    const uint32_t* const list = b.list;
    uint32_t* bfs = s.queue;
    labelOpen(list, n);
    uint32_t size = 0, firstComponent = 0;
    uint32_t scan = 0, start = seed;
    while (size < n) {
        mark_[start] = kVisited;
        bfs[size++] = start;
        size = grow(bfs, size - 1, size);
        if (firstComponent == 0) firstComponent = size;
        while (scan < n && mark_[list[scan]] != kOpen) ++scan;
        if (scan < n) start = list[scan];
    }
    findPieces(s, bfs, size, b.target, b.first, b.pieces);
    b.size = size, b.firstComponent = firstComponent;
}

// Labels bfs[0, size) as the first part (the first `target`, label `first`) and the rest kOpen,
// then finds the pieces of the rest, one after another in `pieces`, started in the order of bfs
// (their starts in s.pieceStart, and the end of the last after them). Returns that end.
uint32_t Builder::findPieces(Scratch& s, const uint32_t* bfs, uint32_t size, uint32_t target, uint32_t first,
                             uint32_t* pieces) {
    for (uint32_t i = 0; i < size; ++i) mark_[bfs[i]] = i < target ? first : kOpen;
    uint32_t pieceEnd = 0;
    s.pieceStart.clear();
    for (uint32_t i = target; i < size; ++i) {
        if (mark_[bfs[i]] != kOpen) continue;
        s.pieceStart.push_back(pieceEnd);
        mark_[bfs[i]] = kVisited;
        pieces[pieceEnd++] = bfs[i];
        pieceEnd = grow(pieces, pieceEnd - 1, pieceEnd);
    }
    s.pieceStart.push_back(pieceEnd);
    return pieceEnd;
}

// The stray pieces that touch the first part join it (all but the largest piece): s.moved, the
// first part's size b.f and the pieces kept in the second part b.kept.
void Builder::joinStrayPieces(Scratch& s, Bisection& b) {
    const uint32_t target = b.target, first = b.first;
    const uint32_t* const pieces = b.pieces;
    const size_t pieceCount = s.pieceStart.size() - 1;
    auto pieceSize = [&](size_t p) { return s.pieceStart[p + 1] - s.pieceStart[p]; };
    size_t largest = 0;
    for (size_t p = 1; p < pieceCount; ++p)
        if (pieceSize(p) > pieceSize(largest)) largest = p;

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
    b.pieceCount = pieceCount, b.f = f, b.kept = kept;
}

// The rows cut between the halves after the search from the seed alone: the edges from the kept
// pieces to the first part (its prefix and the moved pieces, labelled `first` here).
void Builder::cutAtFirstPart(const Scratch& s, const Bisection& b) {
    const uint32_t target = b.target, first = b.first, size = b.size;
    const uint32_t* const pieces = b.pieces;
    const uint32_t* const bfs = s.queue;
    const size_t pieceCount = b.pieceCount;
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

// The new order, into the list: the first part (the seed's search's prefix, then the moved
// pieces), then the second.
void Builder::writeOrder(const Scratch& s, const Bisection& b) {
    const uint32_t target = b.target, f = b.f;
    uint32_t* const list = b.list;
    const uint32_t* const pieces = b.pieces;
    const uint32_t* const bfs = s.queue;
    const size_t pieceCount = b.pieceCount;
    std::copy(bfs, bfs + target, list);
    for (size_t p = 0, e = target; p < pieceCount; ++p)
        if (s.moved[p]) e = std::copy(pieces + s.pieceStart[p], pieces + s.pieceStart[p + 1], list + e) - list;
    for (size_t p = 0, e = f; p < pieceCount; ++p)
        if (!s.moved[p]) e = std::copy(pieces + s.pieceStart[p], pieces + s.pieceStart[p + 1], list + e) - list;
}

// The rows cut between the halves after the whole search: every row of the segment keeps only
// the neighbours labelled as itself, once the halves are labelled.
void Builder::cutBetweenHalves(const Bisection& bisection) {
    const uint32_t n = bisection.n, first = bisection.first, f = bisection.f;
    const uint32_t* const list = bisection.list;
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
std::pair<Part, Part> Builder::halves(const Bisection& b) {
    const uint32_t n = b.n, target = b.target, firstComponent = b.firstComponent, f = b.f, kept = b.kept;
    const bool whole = b.whole;
    const uint32_t* const levels = b.levels;
    const bool firstSearched = target <= firstComponent && f == target, secondSearched = kept == 1;
    Part one{f, firstSearched}, two{n - f, secondSearched};
    if (!whole && !firstSearched) {  // the seed's search's prefix and the moved pieces
        // Levels before the first start at 0, so they clamp themselves; a ball of one level
        // (the seed) ends at 1.
        one.ball = true;
        one.rim[0] = levels[0], one.rim[1] = levels[1], one.rim[2] = std::max(levels[2], 1u);
    }
    return {one, two};
}

// Two large halves that are both bisected again are partitioned in parallel (at the top
// of the tree there are fewer nodes than threads), each in a slice of the scratch (as
// split() slices it for children) and with a stack of its own, the second's parts pushed
// after the first's: the same parts in the same order.
void Builder::partitionHalves(Scratch& s, uint32_t at, const Bisection& b, uint32_t k, Part one, Part two,
                              bool isolate) {
    const uint32_t n = b.n, f = b.f, half = k / 2;
    const uint32_t* const list = b.list;
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

}  // namespace cullide::detail::hierarchy
