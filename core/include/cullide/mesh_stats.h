// What `cullide info` reports about a mesh: sizes, bounds and the things that matter for
// image-space culling (degenerate triangles, components, duplicated vertices).
#pragma once

#include "cullide/mesh.h"

#include <cstddef>

namespace cullide {

struct MeshStats {
    size_t vertices = 0;
    size_t triangles = 0;
    size_t unreferencedVertices = 0;
    Bounds bounds;  // of the referenced vertices
    // Degenerate triangles, decided exactly (no epsilon): repeated index, two corners at the same
    // point, or three collinear corners (the exact predicate `collinear` of cullide/predicates.h).
    size_t degenerateTriangles = 0;
    // Connected components of triangles that share a vertex index (soups whose vertices are
    // duplicated fall apart into many components: that is what their indices say).
    size_t components = 0;
    // Vertices whose position is bit-identical to an earlier vertex's.
    size_t duplicateVertices = 0;
    // Triangles whose three indices (as a set) equal an earlier triangle's.
    size_t duplicateTriangles = 0;
};

MeshStats computeStats(const Mesh& mesh);

// True when the triangle's corners are collinear or coincide (exact), or it repeats an index.
bool isDegenerate(const Mesh& mesh, size_t triangle);

}  // namespace cullide
