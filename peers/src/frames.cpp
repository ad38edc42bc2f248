#include "frames.h"

#include "cullide/error.h"

#include <algorithm>
#include <cmath>

namespace cullide::peers::detail {
namespace {

// What every library needs of an object it is given (a crash or a silent wrong answer otherwise):
// indices in range, at least one triangle, finite world coordinates within kMaxWorldCoordinate.
void checkObject(const Object& o) {
    try {
        validateMesh(o.mesh, "mesh");
    } catch (const InputError& e) {
        throw InputError("scene",
                         "object '" + o.name + "': " + std::string(e.what()).substr(std::string("mesh: ").size()));
    }
    checkWorldPositions(o.mesh.positions, o.transform, o.name, "scene", "");
}

}  // namespace

FrameChanges FrameTracker::next(const Scene& scene) {
    const size_t n = scene.objects.size();
    FrameChanges changes;
    changes.positions.assign(n, 1);
    changes.transform.assign(n, 1);
    bool same = started_ && triangles_.size() == n;
    for (size_t i = 0; same && i < n; ++i)
        same = scene.objects[i].mesh.triangles == triangles_[i] &&
            scene.objects[i].mesh.positions.size() == positions_[i].size();
    changes.build = !same;
    if (changes.build) {
        triangles_.resize(n);
        positions_.resize(n);
        transforms_.resize(n);
    }
    for (size_t i = 0; i < n; ++i) {
        const Object& o = scene.objects[i];
        if (!changes.build) {
            changes.positions[i] = o.mesh.positions != positions_[i];
            changes.transform[i] = !o.transform.matrix().cwiseEqual(transforms_[i].matrix()).all();
        }
        if (changes.positions[i] || changes.transform[i]) checkObject(o);
        if (changes.build) triangles_[i] = o.mesh.triangles;
        if (changes.positions[i]) positions_[i] = o.mesh.positions;
        transforms_[i] = o.transform;
    }
    started_ = true;
    return changes;
}

RigidPlacement rigidPlacement(const Transform& transform) {
    const Eigen::Matrix3d linear = transform.linear().cast<double>();
    const Eigen::Vector3d translation = transform.translation().cast<double>();
    RigidPlacement p;
    const double scale = linear.col(0).norm();
    // A rotation times a uniform scale, to float's precision: L^T L = s^2 I, det > 0.
    const double residual =
        (linear.transpose() * linear - scale * scale * Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (scale > 0 && residual <= 1e-6 * scale * scale && linear.determinant() > 0) {
        p.scale = float(scale);
        p.rotation = linear / scale;
        p.translation = translation;
    } else {
        p.rigid = false;
    }
    return p;
}

std::vector<Vec3f> bvhPositions(const Object& object, const RigidPlacement& placement) {
    std::vector<Vec3f> out(object.mesh.positions);
    if (!placement.rigid) {
        for (Vec3f& p : out) p = applyTransform(object.transform, p);  // as Scene::worldMesh
        return out;
    }
    if (placement.scale != 1)
        for (Vec3f& p : out) p *= placement.scale;
    return out;
}

bool needsRefit(const RigidPlacement& before, const RigidPlacement& now, bool positionsChanged, bool transformChanged) {
    if (positionsChanged || before.rigid != now.rigid) return true;
    if (!now.rigid) return transformChanged;
    return before.scale != now.scale;
}

void sortPairs(std::vector<TrianglePair>& pairs) {
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

}  // namespace cullide::peers::detail
