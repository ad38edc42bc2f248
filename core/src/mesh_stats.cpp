// Mesh statistics (see mesh_stats.h).
//
// Degeneracy is decided exactly: the float coordinates are converted to double (exact) and handed
// to the exact predicate `collinear` (cullide/predicates.h: float filters, then exact arithmetic
// when they cannot decide). Everything else here is integer work, made deterministic by sorting
// instead of iterating hash tables.
#include "cullide/mesh_stats.h"

#include "cullide/error.h"
#include "cullide/predicates.h"

#include <algorithm>
#include <bit>
#include <numeric>

namespace cullide {
namespace {

// Union-find with path halving and union by index (the smaller root wins): deterministic.
struct DisjointSets {
    std::vector<uint32_t> parent;
    explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    }
    void unite(uint32_t a, uint32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a < b) parent[b] = a;
        else parent[a] = b;
    }
};

}  // namespace

bool isDegenerate(const Mesh& mesh, size_t triangle) {
    CULLIDE_CHECK(triangle < mesh.triangles.size(), "isDegenerate: triangle index out of range");
    const Triangle& t = mesh.triangles[triangle];
    for (uint32_t v : t) CULLIDE_CHECK(v < mesh.positions.size(), "isDegenerate: vertex index out of range");
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
    // collinear() is also true when two of the points coincide.
    return collinear(mesh.positions[t[0]].cast<double>(), mesh.positions[t[1]].cast<double>(),
                     mesh.positions[t[2]].cast<double>());
}

MeshStats computeStats(const Mesh& mesh) {
    MeshStats s;
    const size_t nv = mesh.positions.size();
    s.vertices = nv;
    s.triangles = mesh.triangles.size();
    for (const Triangle& t : mesh.triangles)
        for (uint32_t v : t) CULLIDE_CHECK(v < nv, "computeStats: vertex index out of range (validate the mesh first)");

    // Referenced vertices, bounds, components.
    std::vector<bool> referenced(nv, false);
    DisjointSets sets(nv);
    for (const Triangle& t : mesh.triangles) {
        for (uint32_t v : t) referenced[v] = true;
        sets.unite(t[0], t[1]);
        sets.unite(t[1], t[2]);
    }
    s.bounds = referencedBounds(mesh);
    for (size_t v = 0; v < nv; ++v) {
        if (!referenced[v]) ++s.unreferencedVertices;
        else if (sets.find(static_cast<uint32_t>(v)) == v) ++s.components;  // one root per component
    }

    for (size_t i = 0; i < mesh.triangles.size(); ++i)
        if (isDegenerate(mesh, i)) ++s.degenerateTriangles;

    // Duplicate vertices: sort (position bits, index); every vertex but the first of a run of equal
    // bits is a duplicate of an earlier one.
    {
        using Key = std::array<uint32_t, 3>;
        std::vector<std::pair<Key, uint32_t>> keys(nv);
        for (size_t v = 0; v < nv; ++v) {
            const Vec3f& p = mesh.positions[v];
            keys[v] = {
                Key{std::bit_cast<uint32_t>(p.x()), std::bit_cast<uint32_t>(p.y()), std::bit_cast<uint32_t>(p.z())},
                static_cast<uint32_t>(v)};
        }
        std::sort(keys.begin(), keys.end());
        for (size_t i = 1; i < keys.size(); ++i)
            if (keys[i].first == keys[i - 1].first) ++s.duplicateVertices;
    }

    // Duplicate triangles: same index set as an earlier triangle (any order, any orientation).
    {
        std::vector<Triangle> sorted(mesh.triangles);
        for (Triangle& t : sorted) std::sort(t.begin(), t.end());
        std::sort(sorted.begin(), sorted.end());
        for (size_t i = 1; i < sorted.size(); ++i)
            if (sorted[i] == sorted[i - 1]) ++s.duplicateTriangles;
    }
    return s;
}

}  // namespace cullide
