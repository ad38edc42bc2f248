// The 0.1.0 reference build's connectivity hierarchy build (hierarchy_v010.h): its code as it was, less
// the random kind, the option parsing and Hierarchy::depth (today's types are the same).
#include "hierarchy_v010.h"

#include "cullide/error.h"

#include <algorithm>
#include <limits>
#include <span>
#include <vector>

namespace cullide::v010 {

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Face adjacency through shared edges (by vertex index), as compressed rows, neighbours in
// increasing triangle order. Triangles on a non-manifold edge are all adjacent to each other;
// degenerate edges (a == b) connect nothing. Built from the vertex -> triangle incidence (linear
// time, no sort): the triangles sharing edge (a, b) are among those incident to a.
struct Adjacency {
    std::vector<uint32_t> start, next;

    explicit Adjacency(const Mesh& mesh) {
        const size_t n = mesh.triangles.size(), nv = mesh.positions.size();
        std::vector<uint32_t> vstart(nv + 1, 0), incident;
        for (const Triangle& tri : mesh.triangles)
            for (uint32_t v : tri) ++vstart[v + 1];
        for (size_t v = 0; v < nv; ++v) vstart[v + 1] += vstart[v];
        incident.resize(vstart[nv]);
        std::vector<uint32_t> fill(vstart.begin(), vstart.end() - 1);
        for (uint32_t t = 0; t < n; ++t)
            for (uint32_t v : mesh.triangles[t]) incident[fill[v]++] = t;  // increasing t per vertex

        start.assign(n + 1, 0);
        next.reserve(3 * n);
        std::vector<uint32_t> row;
        for (uint32_t t = 0; t < n; ++t) {
            const Triangle& tri = mesh.triangles[t];
            row.clear();
            for (int e = 0; e < 3; ++e) {
                const uint32_t a = tri[e], b = tri[(e + 1) % 3];
                if (a == b) continue;
                for (uint32_t k = vstart[a]; k < vstart[a + 1]; ++k) {
                    const uint32_t u = incident[k];
                    if (u == t) continue;
                    const Triangle& other = mesh.triangles[u];
                    if (other[0] == b || other[1] == b || other[2] == b) row.push_back(u);
                }
            }
            std::sort(row.begin(), row.end());
            row.erase(std::unique(row.begin(), row.end()), row.end());
            next.insert(next.end(), row.begin(), row.end());
            start[t + 1] = uint32_t(next.size());
        }
    }
};

class Builder {
public:
    Builder(const Mesh& mesh, const HierarchyOptions& options, Hierarchy& out) : mesh_(mesh), opt_(options), out_(out) {
        adjacency_.emplace_back(mesh);
        label_.assign(mesh.triangles.size(), kNone);
    }

    void build() {
        const uint32_t n = uint32_t(mesh_.triangles.size());
        out_.order.resize(n);
        for (uint32_t t = 0; t < n; ++t) out_.order[t] = t;
        out_.nodes.clear();
        out_.nodes.push_back({0, n, 0, 0, 0});
        split(0);
    }

private:
    void split(uint32_t nodeIndex) {
        const HierarchyNode node = out_.nodes[nodeIndex];
        if (node.count <= opt_.leafSize) return;
        const uint32_t k = std::min<uint32_t>(opt_.branching, node.count);
        std::span<uint32_t> set(out_.order.data() + node.first, node.count);
        std::vector<uint32_t> sizes;
        partition(set, k, sizes);

        const uint32_t firstChild = uint32_t(out_.nodes.size());
        out_.nodes[nodeIndex].firstChild = firstChild;
        out_.nodes[nodeIndex].childCount = uint32_t(sizes.size());
        uint32_t first = node.first;
        for (uint32_t size : sizes) {
            CULLIDE_CHECK(size > 0 && size < node.count, "a child is smaller than its parent and not empty");
            out_.nodes.push_back({first, size, 0, 0, node.depth + 1});
            first += size;
        }
        for (uint32_t i = 0; i < sizes.size(); ++i) split(firstChild + i);
    }

    std::span<const uint32_t> neighbours(uint32_t t) const {
        const Adjacency& adj = adjacency_.front();
        return {adj.next.data() + adj.start[t], adj.start[t + 1] - adj.start[t]};
    }

    // Reorders `set` into k consecutive parts (appending their sizes to `sizes`), each a compact
    // patch connected through shared edges where the mesh allows: recursive graph-growing
    // bisection. The first part of a bisection is a prefix of the breadth-first order from a
    // pseudo-peripheral triangle (a prefix of a breadth-first order is connected), sized in
    // proportion to its share of the k parts; the second part is the rest, whose stray pieces
    // (cut off from its largest piece, so bordered by the first part) move to the first part.
    // Sizes are therefore near-equal, not exact.
    // `hint`: a triangle of `set` on its periphery, when the caller knows one (kNone otherwise).
    void partition(std::span<uint32_t> set, uint32_t k, std::vector<uint32_t>& sizes, uint32_t hint = kNone) {
        if (k < 2 || set.size() < 2) {
            sizes.push_back(uint32_t(set.size()));
            return;
        }
        const uint32_t half = k / 2;
        const size_t target = std::max<size_t>(1, set.size() * half / k);

        for (uint32_t t : set) label_[t] = kOpen;
        const uint32_t seed = hint != kNone ? hint : farthest(set[0]);
        // Breadth-first order over the set from the seed; when a component is exhausted, go on
        // from the first unvisited triangle of the set (in set order).
        std::vector<uint32_t> bfs;
        bfs.reserve(set.size());
        size_t scan = 0;
        uint32_t start = seed;
        while (bfs.size() < set.size()) {
            label_[start] = kVisited;
            bfs.push_back(start);
            for (size_t head = bfs.size() - 1; head < bfs.size(); ++head)
                for (uint32_t u : neighbours(bfs[head]))
                    if (label_[u] == kOpen) label_[u] = kVisited, bfs.push_back(u);
            while (scan < set.size() && label_[set[scan]] != kOpen) ++scan;
            if (scan < set.size()) start = set[scan];
        }

        // Label the first part kFirst, then find the pieces of the rest.
        for (size_t i = 0; i < bfs.size(); ++i) label_[bfs[i]] = i < target ? kFirst : kOpen;
        std::vector<std::vector<uint32_t>> pieces;
        for (size_t i = target; i < bfs.size(); ++i) {
            if (label_[bfs[i]] != kOpen) continue;
            std::vector<uint32_t>& piece = pieces.emplace_back(1, bfs[i]);
            label_[bfs[i]] = kVisited;
            for (size_t head = 0; head < piece.size(); ++head)
                for (uint32_t u : neighbours(piece[head]))
                    if (label_[u] == kOpen) label_[u] = kVisited, piece.push_back(u);
        }
        size_t largest = 0;
        for (size_t p = 1; p < pieces.size(); ++p)
            if (pieces[p].size() > pieces[largest].size()) largest = p;
        std::vector<uint32_t> first(bfs.begin(), bfs.begin() + target), second;
        for (size_t p = 0; p < pieces.size(); ++p) {
            bool touchesFirst = false;
            for (uint32_t t : pieces[p])
                for (uint32_t u : neighbours(t)) touchesFirst = touchesFirst || label_[u] == kFirst;
            std::vector<uint32_t>& to = (p != largest && touchesFirst) ? first : second;
            to.insert(to.end(), pieces[p].begin(), pieces[p].end());
        }
        for (uint32_t t : set) label_[t] = kNone;
        std::copy(second.begin(), second.end(), std::copy(first.begin(), first.end(), set.begin()));
        // Peripheral starts for the halves, for free: the first part is a ball around the seed
        // whose last-reached triangle lies on its rim; the second part's first triangle borders
        // the first part. (The second part is a breadth-first order too, so its rim is its end.)
        const uint32_t firstHint = first.back(), secondHint = second.back();
        partition(set.subspan(0, first.size()), half, sizes, firstHint);
        partition(set.subspan(first.size()), k - half, sizes, secondHint);
    }

    // The triangle labelled kOpen farthest in hops from `from` over kOpen triangles (ties: the
    // last reached in breadth-first order). Leaves the labels as they were.
    uint32_t farthest(uint32_t from) {
        std::vector<uint32_t>& queue = scratch_;
        queue.clear();
        queue.push_back(from);
        label_[from] = kVisited;
        for (size_t head = 0; head < queue.size(); ++head)
            for (uint32_t u : neighbours(queue[head]))
                if (label_[u] == kOpen) label_[u] = kVisited, queue.push_back(u);
        for (uint32_t t : queue) label_[t] = kOpen;
        return queue.back();
    }

    static constexpr uint32_t kOpen = kNone - 1, kVisited = kNone - 2, kFirst = kNone - 3;

    const Mesh& mesh_;
    HierarchyOptions opt_;
    Hierarchy& out_;
    std::vector<Adjacency> adjacency_;
    std::vector<uint32_t> label_, scratch_;
};

}  // namespace

Hierarchy buildConnectivityHierarchy(const Mesh& mesh, const HierarchyOptions& options) {
    Hierarchy h;
    Builder(mesh, options, h).build();
    return h;
}

bool sameHierarchy(const Hierarchy& a, const Hierarchy& b) {
    return a.order == b.order &&
        std::equal(a.nodes.begin(), a.nodes.end(), b.nodes.begin(), b.nodes.end(),
                   [](const HierarchyNode& x, const HierarchyNode& y) {
                       return x.first == y.first && x.count == y.count && x.firstChild == y.firstChild &&
                           x.childCount == y.childCount && x.depth == y.depth;
                   });
}

}  // namespace cullide::v010
