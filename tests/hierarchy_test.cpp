// Hierarchies: structure invariants, connectivity, determinism, soups; the connectivity build
// against the 0.1.0 reference build of the same algorithm (hierarchy_v010.h).
#include "cullide/hierarchy.h"

#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "hierarchy_v010.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <string>

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

// Expects the default hierarchy of `m` built on every thread to equal the one built on one.
void expectSameWithOneThread(const Mesh& m) {
    const HierarchyOptions o;
    const Hierarchy all = buildHierarchy(m, o);
    tbb::task_arena one(1);
    const Hierarchy single = one.execute([&] { return buildHierarchy(m, o); });
    EXPECT_EQ(all.order, single.order);
    ASSERT_EQ(all.nodes.size(), single.nodes.size());
    for (size_t i = 0; i < all.nodes.size(); ++i)
        EXPECT_TRUE(all.nodes[i].firstChild == single.nodes[i].firstChild &&
                    all.nodes[i].first == single.nodes[i].first)
            << "node " << i;
}

// Expects buildHierarchy's connectivity hierarchy to equal the reference's (the build as first
// written, as of the 0.1.0 reference build: hierarchy_v010.h) for every leaf size and branching given.
void expectSameAsReference(const Mesh& m, std::initializer_list<uint32_t> leafSizes,
                           std::initializer_list<uint32_t> branchings, const std::string& what) {
    for (uint32_t leaf : leafSizes)
        for (uint32_t branching : branchings) {
            const HierarchyOptions o{HierarchyKind::Connectivity, leaf, branching, 1};
            const Hierarchy want = v010::buildConnectivityHierarchy(m, o);
            const Hierarchy got = buildHierarchy(m, o);
            SCOPED_TRACE(what + " leaf " + std::to_string(leaf) + " branching " + std::to_string(branching));
            ASSERT_EQ(got.order, want.order);
            ASSERT_EQ(got.nodes.size(), want.nodes.size());
            for (size_t i = 0; i < want.nodes.size(); ++i) {
                const HierarchyNode &a = got.nodes[i], &b = want.nodes[i];
                ASSERT_TRUE(a.first == b.first && a.count == b.count && a.firstChild == b.firstChild &&
                            a.childCount == b.childCount && a.depth == b.depth)
                    << "node " << i;
            }
        }
}

// A random mesh over a small vertex pool: edges shared by many triangles (rows beyond three
// neighbours), several components, isolated triangles and degenerate ones (a repeated index, in
// each of the three edges: a row takes the triangles across (a, b) and (c, a) from a's list, and a
// degenerate edge there would take all of them).
Mesh randomMesh(uint32_t seed, uint32_t triangles, uint32_t vertices) {
    std::mt19937_64 rng(seed);
    Mesh m;
    for (uint32_t v = 0; v < vertices; ++v) m.positions.push_back(Vec3f(float(v), 0.f, 0.f));
    for (uint32_t t = 0; t < triangles; ++t) {
        const uint32_t a = uint32_t(rng() % vertices);
        uint32_t b = uint32_t((a + 1 + rng() % 5) % vertices), c = uint32_t((a + 1 + rng() % 7) % vertices);
        if (rng() % 13 == 0) b = a;
        else if (rng() % 13 == 0) c = a;
        m.triangles.push_back({a, b, c});
    }
    return m;
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

// The cache across frames. Traps: reusing a hierarchy after the triangles, the vertex count or
// an option changed (a stale permutation of the wrong triangles); rebuilding when only positions
// moved (the reuse would never happen); a reused hierarchy that differs from a fresh build.
TEST(Hierarchy, CacheReusesOnlyForUnchangedTriangles) {
    Mesh m = grid(12);
    HierarchyOptions o;
    HierarchyCache cache;
    cache.resize(2);
    const Hierarchy first = cache.get(0, m, o);
    EXPECT_FALSE(cache.reused(0));
    for (Vec3f& p : m.positions) p = Vec3f(p.x() * 2.0f, p.y() + 0.25f * p.x() * p.x(), p.z() + 1.0f);  // deformed
    const Hierarchy& moved = cache.get(0, m, o);
    EXPECT_TRUE(cache.reused(0));
    EXPECT_EQ(moved.order, buildHierarchy(m, o).order);
    EXPECT_EQ(moved.order, first.order);

    Mesh flipped = m;
    std::swap(flipped.triangles[5][1], flipped.triangles[5][2]);  // same count, other triangles
    EXPECT_EQ(cache.get(0, flipped, o).order, buildHierarchy(flipped, o).order);
    EXPECT_FALSE(cache.reused(0));
    EXPECT_TRUE((cache.get(0, flipped, o), cache.reused(0)));

    HierarchyOptions leaf4 = o;
    leaf4.leafSize = 4;
    EXPECT_EQ(cache.get(0, flipped, leaf4).nodes.size(), buildHierarchy(flipped, leaf4).nodes.size());
    EXPECT_FALSE(cache.reused(0));

    Mesh extraVertex = flipped;
    extraVertex.positions.push_back(Vec3f(9, 9, 9));
    cache.get(0, extraVertex, leaf4);
    EXPECT_FALSE(cache.reused(0));

    // Objects are kept apart: object 1's first call builds, whatever object 0 holds.
    cache.get(1, extraVertex, leaf4);
    EXPECT_FALSE(cache.reused(1));
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

// Random non-manifold meshes, every option corner: the rows keep the original order (by triangle
// id) and reach beyond a part, whose searches stay inside by labels: stray pieces that move, and
// the whole search over several components, must leave no triangle outside the part being split
// open or labelled with its bisection's first-part label (one label shared by all bisections
// fails here); a row with more than three neighbours goes through the overflow table; leaf 1 and
// branching 64 push the bisection to single triangles and to parts smaller than their share.
// A node cut from a ball and its stray pieces resumes its seed's search at the ball's last levels:
// a rim without level D - 2 labelled fails here and below (one started a level late crashes).
TEST(Hierarchy, ConnectivityMatchesReferenceOnRandomMeshes) {
    expectSameAsReference(randomMesh(1, 3000, 900), {1, 16, 1000}, {2, 3, 4, 64}, "pool 900");
    expectSameAsReference(randomMesh(2, 2000, 60), {1, 16}, {2, 4, 64}, "pool 60 (dense fans)");
    expectSameAsReference(randomMesh(3, 2000, 5000), {1, 16}, {2, 4}, "pool 5000 (mostly isolated)");
}

// Several grids whose triangles are shuffled: components are restarted in the node's order (not
// by triangle id), and a node's order differs from its ids everywhere, so a build that confused
// the two, or that restarted components by id, would differ.
TEST(Hierarchy, ConnectivityMatchesReferenceOnShuffledComponents) {
    Mesh m;
    for (int copy = 0; copy < 3; ++copy) {
        const Mesh g = grid(12 + 5 * copy);
        const uint32_t base = uint32_t(m.positions.size());
        m.positions.insert(m.positions.end(), g.positions.begin(), g.positions.end());
        for (const Triangle& t : g.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    std::mt19937_64 rng(5);
    std::shuffle(m.triangles.begin(), m.triangles.end(), rng);
    expectSameAsReference(m, {1, 16, 1000}, {2, 3, 4, 64}, "shuffled grids");
}

// A shuffled grid large enough for the build to renumber it first (most of its neighbours' ids
// more than 4096 apart): the renumbering by a search from triangle 0 must keep every order
// by triangle id (rows, restarts), start the root's bisection from that search's last triangle,
// and map the positions back to triangles at the end. Traps: another seed, a list left in
// positions, an unshuffled mesh that is renumbered anyway (harmless here, only slower).
TEST(Hierarchy, ConnectivityMatchesReferenceOnRenumberedMesh) {
    Mesh m = grid(100);  // 20,000 triangles
    std::mt19937_64 rng(6);
    std::shuffle(m.triangles.begin(), m.triangles.end(), rng);
    expectSameAsReference(m, {1, 16}, {2, 4}, "shuffled grid 100");
}

// A fan of 40 triangles on one edge inside a grid, plus duplicated faces: the fan's rows hold 39+
// neighbours (overflow rows) and stay in the hierarchy's searches through every split.
TEST(Hierarchy, ConnectivityMatchesReferenceWithNonManifoldFan) {
    Mesh m = grid(10);
    const uint32_t a = 5 * 11 + 5, b = a + 1;
    for (int i = 0; i < 40; ++i) {
        m.positions.push_back(Vec3f(5.5f, 5.f, float(i + 1)));
        m.triangles.push_back({a, b, uint32_t(m.positions.size() - 1)});
    }
    for (int i = 0; i < 20; ++i) m.triangles.push_back(m.triangles[size_t(7 * i)]);  // duplicated faces
    expectSameAsReference(m, {1, 16, 1000}, {2, 4, 64}, "fan");
}

// The bundled meshes, as the prunes of data/scenes/ see them (leaf 16, branching 4, and the
// corners): the meshes whose PCS the hierarchy must not change.
TEST(Hierarchy, ConnectivityMatchesReferenceOnBundledMeshes) {
    for (const char* name : {"bunny.off", "cow.off"})
        expectSameAsReference(loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/" + name), {1, 16, 1000}, {2, 4, 64},
                              name);
}

// Nodes of 2^16 triangles and more split their children in parallel, each subtree in a list of its
// own, appended afterwards. Traps: subtrees sharing scratch (a race TSan sees, or wrong orders),
// appended with the wrong index shift or out of child order, or a row (slots or overflow, on a
// non-manifold edge) still reaching into another subtree: each cut edge must be cut on both
// sides, or a subtree's search reads and writes back the labels of a subtree running beside it
// (a race TSan sees; one thread, splitting the subtrees in order, cannot tell). The result must
// equal the one-thread reference and be the same under one worker thread as under all.
TEST(Hierarchy, ParallelSubtreesMatchReference) {
    const Mesh pool = randomMesh(4, 100000, 30000);
    const Mesh sheet = grid(200);  // 80k triangles, one component
    for (const Mesh* m : {&pool, &sheet}) {
        ASSERT_GE(m->triangles.size(), size_t(1) << 16);
        expectSameAsReference(*m, {16}, {2, 4}, m == &pool ? "pool 30000" : "grid 200");
        expectSameWithOneThread(*m);
    }
}

// Parallel subtrees work in slices of their parent's scratch, with slack between siblings (a
// search writes one past its range). Traps: the slack running out (branching 128 on 80k
// triangles leaves none: the children must allocate scratch of their own, not slice without
// slack), and slices of slices (320k triangles: subtrees of subtrees run in parallel, and halves
// of a partition too) overlapping a sibling's, which would make the build differ from one thread
// (or race under TSan).
TEST(Hierarchy, ParallelSubtreesInSlicesOfScratch) {
    expectSameAsReference(grid(200), {16}, {128}, "grid 200, no slack to slice");
    expectSameWithOneThread(grid(400));  // 320k triangles
}
