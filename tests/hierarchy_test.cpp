// Hierarchies: structure invariants, connectivity, determinism, soups.
#include "cullide/hierarchy.h"

#include "cullide/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

using namespace cullide;

namespace {

// An n x n grid of quads in the z = 0 plane, two triangles each, with shared vertices.
Mesh grid(int n) {
    Mesh m;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) m.positions.push_back(Vec3f(float(x), float(y), 0.f));
    auto v = [n](int x, int y) { return uint32_t(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            m.triangles.push_back({v(x, y), v(x + 1, y), v(x + 1, y + 1)});
            m.triangles.push_back({v(x, y), v(x + 1, y + 1), v(x, y + 1)});
        }
    return m;
}

// Checks what every hierarchy must satisfy; returns the leaves.
std::vector<HierarchyNode> checkStructure(const Hierarchy& h, size_t triangles, const HierarchyOptions& o) {
    std::vector<uint32_t> sorted = h.order;
    std::sort(sorted.begin(), sorted.end());
    std::vector<uint32_t> ids(triangles);
    std::iota(ids.begin(), ids.end(), 0u);
    EXPECT_EQ(sorted, ids) << "order must be a permutation of the triangles";
    EXPECT_EQ(h.nodes.at(0).first, 0u);
    EXPECT_EQ(h.nodes.at(0).count, triangles);
    std::vector<HierarchyNode> leaves;
    for (const HierarchyNode& n : h.nodes) {
        if (n.isLeaf()) {
            EXPECT_LE(n.count, o.leafSize);
            leaves.push_back(n);
            continue;
        }
        EXPECT_GT(n.count, o.leafSize) << "a node small enough to be a leaf was split";
        EXPECT_LE(n.childCount, o.branching);
        uint32_t first = n.first, minSize = UINT32_MAX, maxSize = 0;
        for (uint32_t c = 0; c < n.childCount; ++c) {
            const HierarchyNode& ch = h.nodes.at(n.firstChild + c);
            EXPECT_EQ(ch.first, first) << "children must tile their parent's range in order";
            EXPECT_EQ(ch.depth, n.depth + 1);
            first += ch.count;
            minSize = std::min(minSize, ch.count);
            maxSize = std::max(maxSize, ch.count);
        }
        EXPECT_EQ(first, n.first + n.count);
        // Balanced: exactly (to one triangle) for Random; within a few stray triangles moved to
        // keep patches connected for Connectivity.
        if (o.kind == HierarchyKind::Random) EXPECT_LE(maxSize - minSize, 1u) << "siblings are balanced";
        else EXPECT_LE(maxSize, 2 * n.count / n.childCount + 2) << "no child takes much more than its share";
    }
    return leaves;
}

// Whether the triangles of a node are connected through shared edges.
bool connected(const Mesh& m, const Hierarchy& h, const HierarchyNode& n) {
    std::vector<uint32_t> tris(h.order.begin() + n.first, h.order.begin() + n.first + n.count);
    std::vector<int> comp(tris.size(), -1);
    auto shareEdge = [&](uint32_t a, uint32_t b) {
        int shared = 0;
        for (uint32_t u : m.triangles[a])
            for (uint32_t v : m.triangles[b]) shared += u == v;
        return shared >= 2;
    };
    std::vector<size_t> stack{0};
    comp[0] = 0;
    size_t reached = 1;
    while (!stack.empty()) {
        const size_t i = stack.back();
        stack.pop_back();
        for (size_t j = 0; j < tris.size(); ++j)
            if (comp[j] < 0 && shareEdge(tris[i], tris[j])) comp[j] = 0, ++reached, stack.push_back(j);
    }
    return reached == tris.size();
}

double meanLeafDiagonal(const Mesh& m, const Hierarchy& h, const std::vector<HierarchyNode>& leaves) {
    double sum = 0;
    for (const HierarchyNode& n : leaves) {
        Bounds b;
        for (uint32_t k = n.first; k < n.first + n.count; ++k)
            for (uint32_t v : m.triangles[h.order[k]]) b.add(m.positions[v]);
        sum += b.extent().norm();
    }
    return sum / double(leaves.size());
}

}  // namespace

// The connectivity hierarchy of a connected mesh: every leaf is a patch connected through shared
// edges (the whole point of the paper's hierarchy), and patches are compact: on a 64x64 grid the
// mean leaf diagonal is far below a random hierarchy's (which scatters leaves over the mesh).
TEST(Hierarchy, ConnectivityLeavesAreConnectedCompactPatches) {
    const Mesh m = grid(64);
    HierarchyOptions o;
    o.leafSize = 16;
    o.branching = 4;
    const Hierarchy h = buildHierarchy(m, o);
    const auto leaves = checkStructure(h, m.triangles.size(), o);
    size_t connectedLeaves = 0;
    for (const HierarchyNode& n : leaves) connectedLeaves += connected(m, h, n);
    EXPECT_EQ(connectedLeaves, leaves.size()) << "every leaf of a grid is a connected patch";

    o.kind = HierarchyKind::Random;
    const Hierarchy r = buildHierarchy(m, o);
    const auto randomLeaves = checkStructure(r, m.triangles.size(), o);
    const double compact = meanLeafDiagonal(m, h, leaves), scattered = meanLeafDiagonal(m, r, randomLeaves);
    EXPECT_LT(compact * 5, scattered) << "connectivity " << compact << " vs random " << scattered;
}

// Branching 2..7 and leaf sizes 1..40 on an odd-sized mesh: the structure holds everywhere
// (off-by-one in the size split or a child equal to its parent would loop or lose triangles).
// On a grid, every connectivity leaf is connected.
TEST(Hierarchy, StructureForManyShapes) {
    const Mesh m = grid(13);  // 338 triangles
    for (HierarchyKind kind : {HierarchyKind::Connectivity, HierarchyKind::Random})
        for (uint32_t branching : {2u, 3u, 4u, 7u})
            for (uint32_t leaf : {1u, 2u, 16u, 40u, 1000u}) {
                HierarchyOptions o{kind, leaf, branching, 3};
                const Hierarchy h = buildHierarchy(m, o);
                checkStructure(h, m.triangles.size(), o);
            }
}

// A soup: triangles that share no vertex (every triangle its own component), plus degenerate and
// duplicated triangles. Region growing reaches nothing from a seed; the leftover assignment must
// still fill every region to its size.
TEST(Hierarchy, TriangleSoupWithDegenerates) {
    Mesh m;
    std::mt19937_64 rng(42);
    for (int i = 0; i < 300; ++i) {
        const uint32_t base = uint32_t(m.positions.size());
        for (int k = 0; k < 3; ++k)
            m.positions.push_back(Vec3f(float(rng() % 1000), float(rng() % 1000), float(rng() % 1000)));
        m.triangles.push_back({base, base + 1, base + 2});
        if (i % 10 == 0) m.triangles.push_back({base, base, base + 1});  // repeated index
        if (i % 15 == 0) m.triangles.push_back({base, base + 1, base + 2});  // duplicated face
    }
    HierarchyOptions o;
    o.leafSize = 8;
    checkStructure(buildHierarchy(m, o), m.triangles.size(), o);
}

// Same mesh and options: the same hierarchy, bit for bit; the random hierarchy depends on its seed.
TEST(Hierarchy, Deterministic) {
    const Mesh m = grid(20);
    HierarchyOptions o;
    const Hierarchy a = buildHierarchy(m, o), b = buildHierarchy(m, o);
    EXPECT_EQ(a.order, b.order);
    o.kind = HierarchyKind::Random;
    const Hierarchy r1 = buildHierarchy(m, o), r1again = buildHierarchy(m, o);
    o.seed = 2;
    const Hierarchy r2 = buildHierarchy(m, o);
    EXPECT_EQ(r1.order, r1again.order);
    EXPECT_NE(r1.order, r2.order);
}

// Tiny and empty meshes: a single triangle is a leaf root; an empty mesh an empty root.
TEST(Hierarchy, TinyAndEmpty) {
    Mesh one;
    one.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
    one.triangles = {{0, 1, 2}};
    const Hierarchy h = buildHierarchy(one, {});
    ASSERT_EQ(h.nodes.size(), 1u);
    EXPECT_TRUE(h.nodes[0].isLeaf());
    const Hierarchy e = buildHierarchy(Mesh{}, {});
    ASSERT_EQ(e.nodes.size(), 1u);
    EXPECT_EQ(e.nodes[0].count, 0u);
}

// Absurd options are refused with a message, not a hang (branching 1 would never shrink a node).
TEST(Hierarchy, BadOptions) {
    const Mesh m = grid(2);
    EXPECT_THROW(buildHierarchy(m, {HierarchyKind::Connectivity, 0, 4, 1}), InputError);
    EXPECT_THROW(buildHierarchy(m, {HierarchyKind::Connectivity, 16, 1, 1}), InputError);
    EXPECT_THROW(parseHierarchyKind("octree"), InputError);
    EXPECT_EQ(parseHierarchyKind("random"), HierarchyKind::Random);
}
