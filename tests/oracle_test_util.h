// Helpers shared by the oracle's test files (oracle_test.cpp, broad_phase_test.cpp,
// narrow_phase_test.cpp, cgal_reference_test.cpp): scenes of bare meshes, their pairs, the bundled
// meshes.
#pragma once

#include "cullide/mesh_io.h"
#include "cullide/oracle/oracle.h"

#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace cullide::oracle {

inline Scene sceneOf(std::vector<Mesh> meshes) {
    Scene s;
    for (size_t i = 0; i < meshes.size(); ++i)
        s.objects.push_back({std::string("m").append(std::to_string(i)), std::move(meshes[i]), Transform::Identity()});
    return s;
}

inline Mesh meshOf(std::vector<Vec3f> p, std::vector<Triangle> t) {
    return Mesh{std::move(p), std::move(t)};
}

// The pairs of a one-object scene as (a, b, class).
inline std::vector<std::tuple<uint32_t, uint32_t, PairClass>> pairsOf(const Mesh& m, const OracleOptions& o = {}) {
    std::vector<std::tuple<uint32_t, uint32_t, PairClass>> out;
    for (const IntersectingPair& p : findIntersections(sceneOf({m}), o).pairs)
        out.emplace_back(p.triangleA, p.triangleB, p.cls);
    return out;
}

using Pairs = std::vector<std::tuple<uint32_t, uint32_t, PairClass>>;
inline constexpr PairClass X = PairClass::Crossing, T = PairClass::Touching;

inline Mesh bundled(const char* name) {
    return loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/" + name);
}

}  // namespace cullide::oracle
