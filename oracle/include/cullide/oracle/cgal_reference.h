// CGAL's Polygon_mesh_processing::self_intersections, the peer the oracle is compared with
// (tests, benchmarks). Only this header's implementation includes CGAL's mesh machinery.
//
// Conventions
//   - The mesh becomes a CGAL::Surface_mesh with vertex i = our vertex i and face f = our
//     triangle f. CGAL decides sharing by that connectivity, so it needs a valid polygon mesh:
//     a triangle that add_face refuses (a non-manifold edge or vertex, an inconsistent
//     orientation, a repeated index) makes the constructor throw InputError(source, ...).
//   - Pairs are (f, g) with f < g, sorted; a degenerate face f is reported as (f, f).
#pragma once

#include "cullide/mesh.h"
#include "cullide/oracle/oracle.h"

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace cullide::oracle {

using FacePair = std::pair<uint32_t, uint32_t>;

class CgalSelfIntersections {
public:
    // Builds the Surface_mesh (world positions as given, float to double).
    CgalSelfIntersections(const Mesh& mesh, const std::string& source);
    ~CgalSelfIntersections();
    CgalSelfIntersections(const CgalSelfIntersections&) = delete;
    CgalSelfIntersections& operator=(const CgalSelfIntersections&) = delete;

    // Runs self_intersections (Sequential_tag, or Parallel_tag under TBB when `parallel`).
    std::vector<FacePair> run(bool parallel = false) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Our answer for one object in CGAL's form: its self pairs (f < g) and its degenerate
// triangles as (f, f), sorted.
std::vector<FacePair> selfPairsOf(const Truth& truth, uint32_t object);

// The CGAL version this build was compiled against ("5.5.1"), for libraryVersions (versions.h).
const char* cgalVersion();

}  // namespace cullide::oracle
