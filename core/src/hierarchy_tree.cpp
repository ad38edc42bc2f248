// Per-frame hierarchies of sub-objects for Cullide: the tree (buildHierarchy, Builder::build and
// Builder::split) and the hierarchy's words.
//
// References: the seed paper (docs/paper.md#section-6-1), Section 6.1 (random vs
// connectivity-based hierarchies); CULLIDE (Govindaraju et al. 2003), Section 4 (sub-objects).
// The connectivity split is recursive graph-growing bisection on the face-adjacency graph (the
// breadth-first "graph growing" of METIS' initial partitioning, Karypis and Kumar 1998), from a
// pseudo-peripheral start (the farthest triangle in hops from an arbitrary one):
// hierarchy_bisection.cpp.
#include "cullide/hierarchy.h"

#include "hierarchy_builder.h"

#include "cullide/error.h"

#include <algorithm>

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

namespace detail::hierarchy {

void Builder::build() {
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
void Builder::split(std::vector<HierarchyNode>& nodes, uint32_t i, Scratch& s, Part part) {
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

}  // namespace detail::hierarchy

Hierarchy buildHierarchy(const Mesh& mesh, const HierarchyOptions& options) {
    if (options.leafSize < 1) throw InputError("hierarchy options", "leaf size must be at least 1");
    if (options.branching < 2) throw InputError("hierarchy options", "branching must be at least 2");
    Hierarchy h;
    detail::hierarchy::Builder(mesh, options, h).build();
    return h;
}

bool operator==(const HierarchyOptions& a, const HierarchyOptions& b) {
    return a.kind == b.kind && a.leafSize == b.leafSize && a.branching == b.branching && a.seed == b.seed;
}

}  // namespace cullide
