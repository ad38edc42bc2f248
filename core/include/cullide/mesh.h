// Mesh: a triangle soup as a plain value type.
//
// Conventions
//   - Positions are float (what the rasterizers and the oracle both consume; float -> double is
//     exact, so the oracle decides on exactly the coordinates the culler used).
//   - Triangles are three uint32_t vertex indices, in the order the file gave them. Face order
//     is preserved by every loader and generator: triangle i of a file is triangle i here
//     (polygons are fan-triangulated in place, so an n-gon yields n-2 consecutive triangles).
//   - Nothing assumes a manifold, closed, oriented or connected mesh. Degenerate triangles
//     (repeated indices, coincident or collinear corners) are legal and are reported, not removed:
//     they are exactly the triangles an image-space method cannot see.
//   - Unreferenced and duplicated vertices are kept as they are.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace cullide {

using Vec3f = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;
using Triangle = std::array<uint32_t, 3>;

struct Mesh {
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;

    size_t vertexCount() const { return positions.size(); }
    size_t triangleCount() const { return triangles.size(); }
    bool empty() const { return triangles.empty(); }

    friend bool operator==(const Mesh& a, const Mesh& b) {
        return a.positions == b.positions && a.triangles == b.triangles;
    }
};

// Axis-aligned box; empty() when no point was added.
struct Bounds {
    Vec3f lo = Vec3f::Constant(std::numeric_limits<float>::infinity());
    Vec3f hi = Vec3f::Constant(-std::numeric_limits<float>::infinity());

    void add(const Vec3f& p) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    void add(const Bounds& b) {
        lo = lo.cwiseMin(b.lo);
        hi = hi.cwiseMax(b.hi);
    }
    bool empty() const { return !(lo.x() <= hi.x()); }
    Vec3f extent() const { return empty() ? Vec3f::Zero() : Vec3f(hi - lo); }
};

// Bounds of the vertices referenced by `mesh`'s triangles (unreferenced vertices do not count).
Bounds referencedBounds(const Mesh& mesh);

// Checks what every consumer relies on, and throws InputError(source, cause) naming the first
// problem: no triangles, a non-finite coordinate (NaN/Inf, with its vertex index), or a triangle
// index out of range (with the triangle number). Degenerate triangles pass.
void validateMesh(const Mesh& mesh, const std::string& source);

}  // namespace cullide
