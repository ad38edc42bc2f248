// CGAL 5.5 as its Polygon Mesh Processing documentation recommends: within an object,
// Polygon_mesh_processing::self_intersections on a Surface_mesh (CGAL decides which faces share
// vertices from the mesh's connectivity); between objects, box_intersection_d on the triangles'
// boxes and the exact do_intersect (Epick) on each pair of boxes that meet, as self_intersections
// itself does inside one mesh. Parallel_tag (TBB) when the caller's arena has more than one
// thread. CGAL keeps no structure between calls: a later frame only moves the meshes' points.
// Compiled with -frounding-math (CGAL's interval filters).
#include "cullide/error.h"
#include "frames.h"
#include "peer_makers.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/version_macros.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/task_arena.h>

#include <iterator>
#include <memory>
#include <string>

namespace cullide::peers::detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Face = SurfaceMesh::Face_index;
using VertexIndex = SurfaceMesh::Vertex_index;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, uint32_t>;  // info: the triangle

Point toPoint(const Vec3f& p) {
    return Point(double(p.x()), double(p.y()), double(p.z()));
}

// Vertex i of the Surface_mesh is the object's vertex i, face f its triangle f. A triangle that
// add_face refuses makes the object one self_intersections cannot take.
SurfaceMesh surfaceMesh(const Object& object, const std::vector<Vec3f>& world) {
    SurfaceMesh sm;
    const Mesh& mesh = object.mesh;
    sm.reserve(SurfaceMesh::size_type(world.size()), SurfaceMesh::size_type(3 * mesh.triangles.size()),
               SurfaceMesh::size_type(mesh.triangles.size()));
    for (const Vec3f& p : world) sm.add_vertex(toPoint(p));
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Triangle& tri = mesh.triangles[t];
        if (sm.add_face(VertexIndex(tri[0]), VertexIndex(tri[1]), VertexIndex(tri[2])) == SurfaceMesh::null_face())
            throw InputError("scene",
                             "object '" + object.name + "': triangle " + std::to_string(t) +
                                 " cannot be added to a CGAL Surface_mesh (a non-manifold edge or vertex, an "
                                 "inconsistent orientation or a repeated index): CGAL's self_intersections "
                                 "needs a valid polygon mesh");
    }
    return sm;
}

struct CgalObject {
    SurfaceMesh mesh;  // world points
    std::vector<Box> boxes;  // the non-degenerate triangles' boxes, this frame
    CGAL::Bbox_3 bounds;
};

Kernel::Triangle_3 triangleOf(const CgalObject& o, uint32_t t) {
    const auto h = o.mesh.halfedge(Face(t));
    return {o.mesh.point(o.mesh.source(h)), o.mesh.point(o.mesh.target(h)),
            o.mesh.point(o.mesh.target(o.mesh.next(h)))};
}

void boxesOf(CgalObject& o) {
    o.boxes.clear();
    o.bounds = CGAL::Bbox_3();
    for (Face f : o.mesh.faces()) {
        const Kernel::Triangle_3 t = triangleOf(o, uint32_t(f.idx()));
        if (t.is_degenerate()) continue;  // in no pair (do_intersect requires a proper triangle)
        o.boxes.emplace_back(t.bbox(), uint32_t(f.idx()));
        o.bounds += t.bbox();
    }
}

template <typename Tag>
void selfPairs(const CgalObject& o, uint32_t object, std::vector<TrianglePair>& out) {
    std::vector<std::pair<Face, Face>> faces;
    CGAL::Polygon_mesh_processing::self_intersections<Tag>(o.mesh, std::back_inserter(faces));
    for (const auto& [f, g] : faces)
        if (f != g)  // a degenerate face comes as (f, f): no pair
            out.push_back(TrianglePair::make({object, uint32_t(f.idx())}, {object, uint32_t(g.idx())}));
}

template <typename Tag>
void pairsBetween(const CgalObject& a, uint32_t ia, const CgalObject& b, uint32_t ib, std::vector<TrianglePair>& out) {
    if (!CGAL::do_overlap(a.bounds, b.bounds)) return;
    std::vector<Box> boxesA = a.boxes, boxesB = b.boxes;  // box_intersection_d reorders its ranges
    tbb::enumerable_thread_specific<std::vector<TrianglePair>> found;
    const auto test = [&](const Box& x, const Box& y) {
        if (CGAL::do_intersect(triangleOf(a, x.info()), triangleOf(b, y.info())))
            found.local().push_back(TrianglePair::make({ia, x.info()}, {ib, y.info()}));
    };
    CGAL::box_intersection_d<Tag>(boxesA.begin(), boxesA.end(), boxesB.begin(), boxesB.end(), test);
    for (const std::vector<TrianglePair>& local : found) out.insert(out.end(), local.begin(), local.end());
}

template <typename Tag>
std::vector<TrianglePair> query(const std::vector<CgalObject>& objects) {
    std::vector<TrianglePair> pairs;
    for (size_t i = 0; i < objects.size(); ++i) selfPairs<Tag>(objects[i], uint32_t(i), pairs);
    for (size_t i = 0; i < objects.size(); ++i)
        for (size_t j = i + 1; j < objects.size(); ++j)
            pairsBetween<Tag>(objects[i], uint32_t(i), objects[j], uint32_t(j), pairs);
    sortPairs(pairs);
    return pairs;
}

std::vector<Vec3f> worldPositions(const Object& source) {
    std::vector<Vec3f> out(source.mesh.positions.size());
    for (size_t v = 0; v < out.size(); ++v) out[v] = applyTransform(source.transform, source.mesh.positions[v]);
    return out;
}

class CgalPeer final : public Peer {
public:
    CgalPeer() {
        info_.name = "cgal";
        info_.library = "CGAL " CGAL_VERSION_STR;
        info_.selfPairs = true;
        info_.usage =
            "Polygon_mesh_processing::self_intersections per object; box_intersection_d + exact do_intersect "
            "(Epick) between objects; Parallel_tag (TBB) with more than one thread";
    }
    const PeerInfo& info() const override { return info_; }

    PeerFrame collide(const Scene& scene) override {
        return timedFrame(
            tracker_, scene, [&](const FrameChanges& c) { update(scene, c); },
            [&] {
                return tbb::this_task_arena::max_concurrency() > 1 ? query<CGAL::Parallel_tag>(objects_)
                                                                   : query<CGAL::Sequential_tag>(objects_);
            });
    }

private:
    // A new frame's world points into the meshes (new meshes on a build), and the boxes.
    void update(const Scene& scene, const FrameChanges& changes) {
        if (changes.build) objects_.clear();
        objects_.resize(scene.objects.size());
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            if (!changes.build && !changes.positions[i] && !changes.transform[i]) continue;
            const std::vector<Vec3f> world = worldPositions(scene.objects[i]);
            CgalObject& o = objects_[i];
            if (changes.build) o.mesh = surfaceMesh(scene.objects[i], world);
            else
                for (size_t v = 0; v < world.size(); ++v) o.mesh.point(VertexIndex(uint32_t(v))) = toPoint(world[v]);
            boxesOf(o);
        }
    }

    PeerInfo info_;
    FrameTracker tracker_;
    std::vector<CgalObject> objects_;
};

}  // namespace

std::unique_ptr<Peer> makeCgalPeer(const PeerOptions&) {
    return std::make_unique<CgalPeer>();
}

}  // namespace cullide::peers::detail
