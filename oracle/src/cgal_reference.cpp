// CGAL's self_intersections as a peer (see cgal_reference.h). Compiled with -frounding-math.
#include "cullide/oracle/cgal_reference.h"

#include "cullide/error.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/version_macros.h>

#include <algorithm>
#include <iterator>

namespace cullide::oracle {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Face = SurfaceMesh::Face_index;
}  // namespace

struct CgalSelfIntersections::Impl {
    SurfaceMesh mesh;
};

CgalSelfIntersections::CgalSelfIntersections(const Mesh& mesh, const std::string& source) : impl_(new Impl) {
    SurfaceMesh& sm = impl_->mesh;
    sm.reserve(SurfaceMesh::size_type(mesh.positions.size()), SurfaceMesh::size_type(3 * mesh.triangles.size()),
               SurfaceMesh::size_type(mesh.triangles.size()));
    for (const Vec3f& p : mesh.positions) sm.add_vertex(Kernel::Point_3(double(p.x()), double(p.y()), double(p.z())));
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Triangle& tri = mesh.triangles[t];
        for (uint32_t v : tri)
            if (v >= mesh.positions.size())
                throw InputError(source, "triangle " + std::to_string(t) + " has a vertex index out of range");
        const Face f = sm.add_face(SurfaceMesh::Vertex_index(tri[0]), SurfaceMesh::Vertex_index(tri[1]),
                                   SurfaceMesh::Vertex_index(tri[2]));
        if (f == SurfaceMesh::null_face())
            throw InputError(source,
                             "triangle " + std::to_string(t) +
                                 " cannot be added to a CGAL Surface_mesh (non-manifold, inconsistently "
                                 "oriented or repeated indices)");
    }
}

CgalSelfIntersections::~CgalSelfIntersections() = default;

std::vector<FacePair> CgalSelfIntersections::run(bool parallel) const {
    std::vector<std::pair<Face, Face>> faces;
    if (parallel) {
#if defined(CGAL_LINKED_WITH_TBB)
        CGAL::Polygon_mesh_processing::self_intersections<CGAL::Parallel_tag>(impl_->mesh, std::back_inserter(faces));
#else
        CGAL::Polygon_mesh_processing::self_intersections<CGAL::Sequential_tag>(impl_->mesh, std::back_inserter(faces));
#endif
    } else {
        CGAL::Polygon_mesh_processing::self_intersections<CGAL::Sequential_tag>(impl_->mesh, std::back_inserter(faces));
    }
    std::vector<FacePair> out;
    out.reserve(faces.size());
    for (const auto& [f, g] : faces) out.push_back(std::minmax(uint32_t(f.idx()), uint32_t(g.idx())));
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<FacePair> selfPairsOf(const Truth& truth, uint32_t object) {
    std::vector<FacePair> out;
    for (const IntersectingPair& p : truth.pairs)
        if (p.objectA == object && p.objectB == object) out.push_back({p.triangleA, p.triangleB});
    for (const TriangleRef& d : truth.degenerate)
        if (d.object == object) out.push_back({d.triangle, d.triangle});
    std::sort(out.begin(), out.end());
    return out;
}

const char* cgalVersion() {
    return CGAL_VERSION_STR;
}

}  // namespace cullide::oracle
