#include "cullide/mesh.h"

#include "cullide/error.h"

#include <cmath>

namespace cullide {

Bounds referencedBounds(const Mesh& mesh) {
    Bounds b;
    for (const Triangle& t : mesh.triangles)
        for (uint32_t v : t) b.add(mesh.positions[v]);
    return b;
}

void validateMesh(const Mesh& mesh, const std::string& source) {
    if (mesh.positions.empty()) throw InputError(source, "empty mesh: no vertices");
    if (mesh.triangles.empty()) throw InputError(source, "mesh has zero triangles");
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const Vec3f& p = mesh.positions[i];
        if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
            throw InputError(source, "vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or Inf)");
    }
    const size_t n = mesh.positions.size();
    for (size_t i = 0; i < mesh.triangles.size(); ++i)
        for (uint32_t v : mesh.triangles[i])
            if (v >= n)
                throw InputError(source,
                                 "triangle " + std::to_string(i) + " refers to vertex " + std::to_string(v) +
                                     ", but the mesh has only " + std::to_string(n) + " vertices");
}

}  // namespace cullide
