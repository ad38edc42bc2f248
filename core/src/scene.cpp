#include "cullide/scene.h"

#include "cullide/error.h"
#include "cullide/mesh_io.h"

#include <cmath>
#include <limits>

namespace cullide {

Vec3f applyTransform(const Transform& t, const Vec3f& p) {
    const auto& m = t.matrix();
    Vec3f r;
    for (int row = 0; row < 3; ++row)
        r[row] = ((m(row, 0) * p.x() + m(row, 1) * p.y()) + m(row, 2) * p.z()) + m(row, 3);
    return r;
}

size_t Scene::triangleCount() const {
    size_t n = 0;
    for (const Object& o : objects) n += o.mesh.triangleCount();
    return n;
}

size_t Scene::vertexCount() const {
    size_t n = 0;
    for (const Object& o : objects) n += o.mesh.vertexCount();
    return n;
}

Mesh Scene::worldMesh(size_t i) const {
    const Object& o = objects.at(i);
    Mesh m;
    m.triangles = o.mesh.triangles;
    m.positions.reserve(o.mesh.positions.size());
    for (const Vec3f& p : o.mesh.positions) m.positions.push_back(applyTransform(o.transform, p));
    return m;
}

FlatScene flatten(const Scene& scene) {
    const uint64_t vertices = scene.vertexCount(), triangles = scene.triangleCount();
    if (vertices > std::numeric_limits<uint32_t>::max() || triangles > std::numeric_limits<uint32_t>::max())
        throw InputError("scene", "more than 2^32 vertices or triangles");
    FlatScene f;
    f.mesh.positions.reserve(vertices);
    f.mesh.triangles.reserve(triangles);
    f.firstTriangle.reserve(scene.objects.size() + 1);
    for (const Object& o : scene.objects) {
        const uint32_t base = uint32_t(f.mesh.positions.size());
        f.firstTriangle.push_back(uint32_t(f.mesh.triangles.size()));
        for (const Vec3f& p : o.mesh.positions) f.mesh.positions.push_back(applyTransform(o.transform, p));
        for (const Triangle& t : o.mesh.triangles) f.mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    f.firstTriangle.push_back(uint32_t(f.mesh.triangles.size()));
    return f;
}

void checkPosePositions(std::span<const Vec3f> positions, const Object& object, const std::string& source,
                        const std::string& where) {
    if (positions.size() != object.mesh.positions.size())
        throw InputError(source, where + ", object '" + object.name + "': " + std::to_string(positions.size()) +
                                     " positions, but the mesh has " + std::to_string(object.mesh.positions.size()) +
                                     " vertices");
    for (size_t v = 0; v < positions.size(); ++v)
        if (!positions[v].allFinite())
            throw InputError(source, where + ", object '" + object.name + "': vertex " + std::to_string(v) +
                                         " is not finite (NaN or Inf)");
}

Scene Animation::sceneAt(size_t f) const {
    CULLIDE_CHECK(f < frameCount(), "frame index out of range");
    Scene s = scene;
    if (frames.empty()) return s;
    const Frame& fr = frames[f];
    for (size_t i = 0; i < fr.poses.size() && i < s.objects.size(); ++i) {
        if (fr.poses[i].transform) s.objects[i].transform = *fr.poses[i].transform;
        if (fr.poses[i].positions) {
            s.objects[i].mesh.positions = *fr.poses[i].positions;
        } else if (!fr.poses[i].positionsFile.empty()) {
            const std::string& file = fr.poses[i].positionsFile;
            std::vector<Vec3f> positions = loadMesh(file).positions;
            checkPosePositions(positions, s.objects[i], file, "frame " + std::to_string(f));
            s.objects[i].mesh.positions = std::move(positions);
        }
    }
    return s;
}

static bool finite(const Transform& t) {
    return t.matrix().allFinite();
}

void validateAnimation(const Animation& a, const std::string& source) {
    for (size_t i = 0; i < a.scene.objects.size(); ++i) {
        if (!finite(a.scene.objects[i].transform))
            throw InputError(source, "object '" + a.scene.objects[i].name + "' has a non-finite transform");
    }
    for (size_t f = 0; f < a.frames.size(); ++f) {
        const Frame& fr = a.frames[f];
        const std::string where = "frame " + std::to_string(f);
        if (!fr.poses.empty() && fr.poses.size() != a.scene.objects.size())
            throw InputError(source,
                             where + " has " + std::to_string(fr.poses.size()) + " object poses, but the scene has " +
                                 std::to_string(a.scene.objects.size()) + " objects");
        for (size_t i = 0; i < fr.poses.size(); ++i) {
            const ObjectPose& p = fr.poses[i];
            const Object& o = a.scene.objects[i];
            if (p.transform && !finite(*p.transform))
                throw InputError(source, where + ", object '" + o.name + "': non-finite transform");
            if (p.positions) checkPosePositions(*p.positions, o, source, where);
        }
    }
}

}  // namespace cullide
