// HierarchyCache: each object's hierarchy kept from one frame to the next (hierarchy.h).
#include "cullide/hierarchy.h"

#include "cullide/error.h"

#include <algorithm>

namespace cullide {

void HierarchyCache::resize(size_t objects) {
    entries_.resize(objects);
}

const Hierarchy& HierarchyCache::get(size_t object, const Mesh& mesh, const HierarchyOptions& options) {
    CULLIDE_CHECK(object < entries_.size(), "HierarchyCache::get on an object beyond resize()");
    Entry& e = entries_[object];
    e.reused = e.valid && e.options == options && e.vertexCount == mesh.positions.size() &&
        std::equal(e.triangles.begin(), e.triangles.end(), mesh.triangles.begin(), mesh.triangles.end());
    if (!e.reused) {
        e.valid = false;  // a throwing build leaves no stale entry
        e.hierarchy = buildHierarchy(mesh, options);
        e.triangles = mesh.triangles;
        e.vertexCount = mesh.positions.size();
        e.options = options;
        e.valid = true;
    }
    return e.hierarchy;
}

}  // namespace cullide
