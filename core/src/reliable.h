// The pieces of the reliable reducePCS that are not image-space: which units (hierarchy leaves)
// share vertices, a distance-2 colouring of that graph, and the exact check of the pairs the
// image-space test leaves out (pairs inside a unit, pairs between units that share a vertex).
// Private to core/; the argument is in docs/reliable.md.
#pragma once

#include "cullide/cullide.h"

#include <cstdint>
#include <span>
#include <vector>

namespace cullide::detail {

// Unit adjacency in CSR form: units u and v (u != v) are adjacent when a triangle of u and a
// triangle of v share a vertex index. Lists are sorted.
struct UnitGraph {
    std::vector<uint32_t> start;  // size units + 1
    std::vector<uint32_t> adj;
    std::span<const uint32_t> neighbours(uint32_t u) const {
        return {adj.data() + start[u], adj.data() + start[u + 1]};
    }
};

// `units` are ranges of `triangles` (indices into one shared vertex array, so triangles of
// different objects never share an index).
UnitGraph unitAdjacency(std::span<const Triangle> triangles, std::span<const TriangleRange> units);

// A colouring in which any two units at distance 1 or 2 differ: greedy in unit order (smallest
// free colour), deterministic. Then every unit has at most one neighbour of each colour.
std::vector<uint32_t> distanceTwoColouring(const UnitGraph& g);

// Whether two triangles may intersect under the oracle's rules (cullide/oracle/oracle.h), decided
// exactly by the oracle's own rules (faceContact, cullide/predicates.h): false only when the
// oracle would report no intersecting pair. Sharing is by vertex index: 3 shared: true; 2 shared:
// coplanar with the opposite corners strictly on one side of the edge; 1 shared: either meets the
// other's opposite edge; 0 shared: the plain test. A degenerate (collinear) triangle is in no
// pair: false.
bool mayIntersect(std::span<const Vec3f> positions, const Triangle& a, const Triangle& b);

// Per unit: whether some pair inside the unit, or between it and an adjacent unit, may intersect
// (mayIntersect). Parallel, deterministic.
std::vector<uint8_t> exactHits(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                               std::span<const TriangleRange> units, const UnitGraph& g);

}  // namespace cullide::detail
