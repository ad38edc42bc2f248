// Hierarchies of sub-objects, built per frame with no preprocessing (the seed paper, Section 6.1:
// "a hierarchy built on mesh connectivity ... improved performance significantly" over a random
// one). The hierarchy changes how fast Cullide prunes, never what it may prune.
//
// Conventions
//   - A hierarchy covers one object's triangles. Building it permutes them so that every node
//     is a contiguous range [first, first + count) of `order` (order[k] = the object's triangle
//     id at position k); a backend can then draw any node as one index range.
//   - Node 0 is the root (the whole object). Children of a node are contiguous in `nodes`
//     (firstChild .. firstChild + childCount - 1); a leaf has childCount == 0.
//   - A node is split while it holds more than `leafSize` triangles, into up to `branching`
//     children of near-equal size (exactly equal, to one triangle, for Random; for Connectivity
//     a few triangles may move between siblings to keep patches connected).
//   - Deterministic: same mesh and options, same hierarchy, for any thread count (no unordered
//     iteration; a large node's subtrees are built in parallel but laid out as one thread would;
//     a seeded std::mt19937_64 with our own integer draws).
#pragma once

#include "cullide/mesh.h"

#include <cstdint>
#include <string>
#include <vector>

namespace cullide {

enum class HierarchyKind : uint8_t {
    // Compact patches connected through shared edges: each split is a recursive bisection by
    // breadth-first growth over the face-adjacency graph from a pseudo-peripheral triangle (the
    // first part is a prefix of that order, hence connected). Components the growth cannot
    // reach are visited afterwards, in order, so a soup still splits into equal parts.
    Connectivity,
    // The paper's poor baseline: a seeded random permutation cut into equal ranges.
    Random,
};

const char* toString(HierarchyKind kind);
HierarchyKind parseHierarchyKind(const std::string& text);  // "connectivity" | "random"; InputError

struct HierarchyOptions {
    HierarchyKind kind = HierarchyKind::Connectivity;
    uint32_t leafSize = 16;  // a node with at most this many triangles is a leaf (>= 1)
    uint32_t branching = 4;  // children per split (>= 2)
    uint64_t seed = 1;  // used by Random
};

struct HierarchyNode {
    uint32_t first = 0, count = 0;  // range in Hierarchy::order
    uint32_t firstChild = 0, childCount = 0;  // range in Hierarchy::nodes
    uint32_t depth = 0;  // root: 0
    bool isLeaf() const { return childCount == 0; }
};

struct Hierarchy {
    std::vector<uint32_t> order;  // permutation of the object's triangle ids
    std::vector<HierarchyNode> nodes;
    uint32_t depth() const;  // deepest node's depth
};

bool operator==(const HierarchyOptions& a, const HierarchyOptions& b);

// Builds the hierarchy of `mesh` (any triangle soup; an empty mesh gives a single empty root).
// Throws InputError("hierarchy options", ...) on leafSize < 1 or branching < 2.
Hierarchy buildHierarchy(const Mesh& mesh, const HierarchyOptions& options);

// Each object's hierarchy kept from one frame to the next. A hierarchy is a function of the
// object's triangles (vertex indices), its vertex count and the options, never of its positions
// (Connectivity grows over edges shared by vertex index, Random draws from the triangle count and
// seed), so a deforming object whose triangles are unchanged gets the same hierarchy, bit for
// bit, and Cullide the same PCS, without the build the paper pays every frame. The test is exact:
// the kept triangles are compared in full (12 bytes per triangle kept beside the hierarchy).
// get() on distinct objects may run concurrently after resize(); one cache serves one run at a
// time.
class HierarchyCache {
public:
    // Makes room for `objects` objects (keeping what the first ones hold).
    void resize(size_t objects);
    // The hierarchy of object `object` (< the size given to resize) for `mesh`: the kept one when
    // the mesh's triangles, vertex count and `options` equal the last call's for that object, else
    // a new build, kept for next time.
    const Hierarchy& get(size_t object, const Mesh& mesh, const HierarchyOptions& options);
    // Whether the last get() for `object` reused the kept hierarchy.
    bool reused(size_t object) const { return entries_[object].reused; }

private:
    struct Entry {
        std::vector<Triangle> triangles;
        size_t vertexCount = 0;
        HierarchyOptions options;
        Hierarchy hierarchy;
        bool valid = false, reused = false;
    };
    std::vector<Entry> entries_;
};

}  // namespace cullide
