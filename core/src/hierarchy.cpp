// Per-frame hierarchies of sub-objects for Cullide.
//
// References: the seed paper (../shared/papers/000_7db8250a290ddd48.txt), Section 6.1 (random vs
// connectivity-based hierarchies); CULLIDE (Govindaraju et al. 2003), Section 4 (sub-objects).
// The connectivity split is multi-source region growing on the face-adjacency graph, seeded by
// farthest-point sampling in graph distance (the same idea as graph-growing partitioning in
// METIS' initial bisection).
#include "cullide/hierarchy.h"

#include "cullide/error.h"

#include <algorithm>
#include <deque>
#include <limits>
#include <random>

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

// Face adjacency through shared edges (by vertex index), as compressed rows. Triangles on a
// non-manifold edge are all adjacent to each other; degenerate edges (a == b) connect nothing.
struct Adjacency {
    std::vector<uint32_t> start, next;

    Adjacency(const Mesh& mesh) {
        const size_t n = mesh.triangles.size();
        struct Edge {
            uint32_t a, b, t;
        };
        std::vector<Edge> edges;
        edges.reserve(3 * n);
        for (uint32_t t = 0; t < n; ++t) {
            const Triangle& tri = mesh.triangles[t];
            for (int e = 0; e < 3; ++e) {
                uint32_t a = tri[e], b = tri[(e + 1) % 3];
                if (a == b) continue;
                if (a > b) std::swap(a, b);
                edges.push_back({a, b, t});
            }
        }
        std::sort(edges.begin(), edges.end(),
                  [](const Edge& x, const Edge& y) { return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.t < y.t; });
        std::vector<std::pair<uint32_t, uint32_t>> pairs;
        for (size_t i = 0; i < edges.size();) {
            size_t j = i;
            while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) ++j;
            for (size_t p = i; p < j; ++p)
                for (size_t q = i; q < j; ++q)
                    if (edges[p].t != edges[q].t) pairs.push_back({edges[p].t, edges[q].t});
            i = j;
        }
        std::sort(pairs.begin(), pairs.end());
        pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
        start.assign(n + 1, 0);
        for (const auto& p : pairs) ++start[p.first + 1];
        for (size_t t = 0; t < n; ++t) start[t + 1] += start[t];
        next.resize(pairs.size());
        for (size_t i = 0; i < pairs.size(); ++i) next[i] = pairs[i].second;  // pairs sorted by first
    }
};

class Builder {
public:
    Builder(const Mesh& mesh, const HierarchyOptions& options, Hierarchy& out)
        : mesh_(mesh), opt_(options), out_(out), rng_(options.seed) {
        const size_t n = mesh.triangles.size();
        if (opt_.kind == HierarchyKind::Connectivity) {
            adjacency_.emplace_back(mesh);
            centroid_.resize(n);
            for (size_t t = 0; t < n; ++t) {
                const Triangle& tri = mesh.triangles[t];
                centroid_[t] = (mesh.positions[tri[0]].cast<double>() + mesh.positions[tri[1]].cast<double>() +
                                mesh.positions[tri[2]].cast<double>()) / 3.0;
            }
            label_.assign(n, kNone);
            dist_.assign(n, kNone);
        }
    }

    void build() {
        const uint32_t n = uint32_t(mesh_.triangles.size());
        out_.order.resize(n);
        for (uint32_t t = 0; t < n; ++t) out_.order[t] = t;
        if (opt_.kind == HierarchyKind::Random) {
            // Fisher-Yates with our own bounded draws (std's distributions are implementation-defined).
            for (uint32_t i = n; i > 1; --i) std::swap(out_.order[i - 1], out_.order[uniform(i)]);
        }
        out_.nodes.clear();
        out_.nodes.push_back({0, n, 0, 0, 0});
        split(0);
    }

private:
    uint32_t uniform(uint32_t bound) {  // in [0, bound), by rejection: unbiased, portable
        const uint64_t limit = std::numeric_limits<uint64_t>::max() - std::numeric_limits<uint64_t>::max() % bound;
        uint64_t x;
        do x = rng_(); while (x >= limit);
        return uint32_t(x % bound);
    }

    void split(uint32_t nodeIndex) {
        const HierarchyNode node = out_.nodes[nodeIndex];
        if (node.count <= opt_.leafSize) return;
        const uint32_t k = std::min<uint32_t>(opt_.branching, node.count);
        std::vector<uint32_t> sizes(k);
        for (uint32_t i = 0; i < k; ++i) sizes[i] = node.count / k + (i < node.count % k ? 1 : 0);
        if (opt_.kind == HierarchyKind::Connectivity) partition(node, sizes);

        const uint32_t firstChild = uint32_t(out_.nodes.size());
        out_.nodes[nodeIndex].firstChild = firstChild;
        out_.nodes[nodeIndex].childCount = k;
        uint32_t first = node.first;
        for (uint32_t i = 0; i < k; ++i) {
            out_.nodes.push_back({first, sizes[i], 0, 0, node.depth + 1});
            first += sizes[i];
        }
        for (uint32_t i = 0; i < k; ++i) split(firstChild + i);
    }

    // Reorders order[node.first, +count) into k connected, compact regions of the given sizes.
    void partition(const HierarchyNode& node, const std::vector<uint32_t>& sizes) {
        const Adjacency& adj = adjacency_.front();
        const uint32_t k = uint32_t(sizes.size());
        std::span<uint32_t> set(out_.order.data() + node.first, node.count);
        const uint32_t open = kNone - 1;  // label of "in this set, not yet claimed"
        for (uint32_t t : set) label_[t] = open;

        auto neighbours = [&](uint32_t t) {
            return std::span<const uint32_t>(adj.next.data() + adj.start[t], adj.start[t + 1] - adj.start[t]);
        };

        // Seeds: farthest-point sampling in hops. The first seed is the triangle farthest from
        // set[0] (a pseudo-peripheral triangle); each next one is the farthest from all seeds so
        // far, an unreachable triangle (another component) counting as infinitely far.
        std::vector<uint32_t> seeds;
        std::deque<uint32_t> queue;
        auto farthestFrom = [&](const std::vector<uint32_t>& sources) {
            for (uint32_t t : set) dist_[t] = kNone;
            queue.clear();
            for (uint32_t s : sources) dist_[s] = 0, queue.push_back(s);
            while (!queue.empty()) {
                const uint32_t t = queue.front();
                queue.pop_front();
                for (uint32_t u : neighbours(t))
                    if (label_[u] == open && dist_[u] == kNone) dist_[u] = dist_[t] + 1, queue.push_back(u);
            }
            uint32_t best = set[0];
            for (uint32_t t : set)
                if (dist_[t] > dist_[best] || (dist_[t] == dist_[best] && t < best && dist_[t] != kNone)) best = t;
            return best;
        };
        seeds.push_back(farthestFrom({set[0]}));
        while (seeds.size() < k) seeds.push_back(farthestFrom(seeds));

        // Grow all regions at once, one triangle per region in turn, each up to its size.
        std::vector<std::vector<uint32_t>> regions(k);
        std::vector<std::deque<uint32_t>> fronts(k);
        std::vector<Vec3d> sum(k, Vec3d::Zero());
        auto claim = [&](uint32_t r, uint32_t t) {
            label_[t] = r;
            regions[r].push_back(t);
            sum[r] += centroid_[t];
            for (uint32_t u : neighbours(t))
                if (label_[u] == open) fronts[r].push_back(u);
        };
        for (uint32_t r = 0; r < k; ++r) claim(r, seeds[r]);
        for (bool grew = true; grew;) {
            grew = false;
            for (uint32_t r = 0; r < k; ++r) {
                if (regions[r].size() >= sizes[r]) continue;
                while (!fronts[r].empty() && label_[fronts[r].front()] != open) fronts[r].pop_front();
                if (fronts[r].empty()) continue;
                const uint32_t t = fronts[r].front();
                fronts[r].pop_front();
                claim(r, t);
                grew = true;
            }
        }

        // What no region reached (other components, or pockets closed off by full regions):
        // walk each leftover piece breadth-first and hand it to the region with room whose
        // centroid is nearest, switching region when that one is full.
        for (uint32_t s : set) {
            if (label_[s] != open) continue;
            queue.clear();
            queue.push_back(s);
            std::vector<uint32_t> piece;
            label_[s] = open - 1;  // queued
            while (!queue.empty()) {
                const uint32_t t = queue.front();
                queue.pop_front();
                piece.push_back(t);
                for (uint32_t u : neighbours(t))
                    if (label_[u] == open) label_[u] = open - 1, queue.push_back(u);
            }
            uint32_t r = kNone;
            for (uint32_t t : piece) {
                if (r == kNone || regions[r].size() >= sizes[r]) {
                    r = kNone;
                    double best = std::numeric_limits<double>::infinity();
                    for (uint32_t c = 0; c < k; ++c) {
                        if (regions[c].size() >= sizes[c]) continue;
                        const double d = (sum[c] / double(regions[c].size()) - centroid_[t]).squaredNorm();
                        if (d < best) best = d, r = c;
                    }
                }
                CULLIDE_CHECK(r != kNone, "region sizes add up to the set size");
                label_[t] = r;
                regions[r].push_back(t);
                sum[r] += centroid_[t];
            }
        }

        uint32_t* dst = set.data();
        for (uint32_t r = 0; r < k; ++r) {
            CULLIDE_CHECK(regions[r].size() == sizes[r], "every region filled to its size");
            dst = std::copy(regions[r].begin(), regions[r].end(), dst);
        }
        for (uint32_t t : set) label_[t] = kNone;
    }

    const Mesh& mesh_;
    HierarchyOptions opt_;
    Hierarchy& out_;
    std::mt19937_64 rng_;
    std::vector<Adjacency> adjacency_;  // empty for Random
    std::vector<Vec3d> centroid_;
    std::vector<uint32_t> label_, dist_;
};

}  // namespace

Hierarchy buildHierarchy(const Mesh& mesh, const HierarchyOptions& options) {
    if (options.leafSize < 1) throw InputError("hierarchy options", "leaf size must be at least 1");
    if (options.branching < 2) throw InputError("hierarchy options", "branching must be at least 2");
    Hierarchy h;
    Builder(mesh, options, h).build();
    return h;
}

}  // namespace cullide
