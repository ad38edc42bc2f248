#include "cullide/scene.h"

#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "cullide/positions_file.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string_view>
#include <unordered_set>

namespace cullide {

namespace {

// "frame 3, object 'cow'", or "object 'cow'" where `where` is empty.
std::string objectWhere(const std::string& where, const std::string& name) {
    return (where.empty() ? std::string() : where + ", ") + "object '" + name + "'";
}

// Whether a world coordinate is one a scene may have (false for NaN and Inf).
bool withinLimits(const Vec3f& w) {
    return std::abs(w.x()) <= kMaxWorldCoordinate && std::abs(w.y()) <= kMaxWorldCoordinate &&
        std::abs(w.z()) <= kMaxWorldCoordinate;
}

// Why vertex v's world position `world` (of model position `model`) is refused.
[[noreturn]] void refuseWorldPosition(const Vec3f& model, const Vec3f& world, size_t v, const std::string& name,
                                      const std::string& source, const std::string& where) {
    const std::string at = objectWhere(where, name) + ": ";
    const std::string vertex = "vertex " + std::to_string(v);
    if (!model.allFinite()) throw InputError(source, at + vertex + " is not finite (NaN or Inf)");
    if (!world.allFinite())
        throw InputError(source,
                         at + "world coordinates overflow (the transform times " + vertex + " is not finite in float)");
    float far = 0;
    for (int k = 0; k < 3; ++k)
        if (std::abs(world[k]) > std::abs(far)) far = world[k];
    char text[32];
    std::snprintf(text, sizeof text, "%g", double(far));
    throw InputError(source,
                     at + vertex + "'s world coordinate " + text +
                         " lies beyond 2^60 in magnitude, the limit of the exact predicates (docs/oracle.md)");
}

// Refuses the worst world position, if one is refused: the first that is not finite (an overflow
// says more than a large coordinate), else the first beyond the limit. world(v): vertex v's.
template <typename World>
void checkEach(std::span<const Vec3f> model, const World& world, const std::string& name, const std::string& source,
               const std::string& where) {
    size_t far = model.size();
    for (size_t v = 0; v < model.size(); ++v) {
        const Vec3f w = world(v);
        if (withinLimits(w)) continue;
        if (!w.allFinite() || !model[v].allFinite()) refuseWorldPosition(model[v], w, v, name, source, where);
        if (far == model.size()) far = v;
    }
    if (far < model.size()) refuseWorldPosition(model[far], world(far), far, name, source, where);
}

// Per axis, the largest magnitude among `positions`; NaN when one is not finite.
Eigen::Vector3d largestMagnitudes(std::span<const Vec3f> positions) {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    bool finite = true;
    for (const Vec3f& p : positions) {
        finite = finite && p.allFinite();
        for (int k = 0; k < 3; ++k) m[k] = std::max(m[k], std::abs(double(p[k])));
    }
    return finite ? m : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
}

// checkWorldPositions with the positions' largestMagnitudes known. The bound |M| m + |t| (in
// double) holds every world coordinate up to float's rounding of applyTransform's five operations
// (a factor below 1 + 2^-21); within half the limit it settles the check without a pass over
// the positions, which a frame that only moves an object then costs nothing.
void checkWorld(std::span<const Vec3f> positions, const Eigen::Vector3d& magnitudes, const Transform& t,
                const std::string& name, const std::string& source, const std::string& where) {
    const auto& m = t.matrix();
    bool bounded = true;
    for (int row = 0; row < 3; ++row) {
        double bound = std::abs(double(m(row, 3)));
        for (int k = 0; k < 3; ++k) bound += std::abs(double(m(row, k))) * magnitudes[k];
        bounded = bounded && bound <= 0.5 * double(kMaxWorldCoordinate);  // false for NaN
    }
    const auto world = [&](size_t v) { return applyTransform(t, positions[v]); };
    if (!bounded) checkEach(positions, world, name, source, where);
}

}  // namespace

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
    const auto world = [&](size_t v) { return m.positions[v]; };
    checkEach(o.mesh.positions, world, o.name, "scene", "");
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
        const auto world = [&](size_t v) { return f.mesh.positions[base + v]; };
        checkEach(o.mesh.positions, world, o.name, "scene", "");
        for (const Triangle& t : o.mesh.triangles) f.mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    f.firstTriangle.push_back(uint32_t(f.mesh.triangles.size()));
    return f;
}

void checkWorldPositions(std::span<const Vec3f> positions, const Transform& transform, const std::string& objectName,
                         const std::string& source, const std::string& where) {
    checkWorld(positions, largestMagnitudes(positions), transform, objectName, source, where);
}

void checkObjectName(const std::string& name, bool taken, const std::string& source, const std::string& where) {
    const std::string at = where.empty() ? std::string() : where + ": ";
    if (name.empty()) throw InputError(source, at + "an object's name is empty");
    if (taken) throw InputError(source, at + "duplicate object name '" + name + "'");
}

void checkSceneObjects(const Scene& scene, const std::string& source) {
    if (scene.objects.empty()) throw InputError(source, "the scene has no objects; it needs at least one");
    std::unordered_set<std::string_view> names;
    names.reserve(scene.objects.size());
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const std::string& name = scene.objects[i].name;
        const bool taken = !names.insert(name).second;
        if (name.empty() || taken) checkObjectName(name, taken, source, "objects[" + std::to_string(i) + "]");
    }
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

const PositionsFileRef* Animation::positionsFileOf(size_t i) const {
    for (const PositionsFileRef& r : positionsFiles)
        if (r.object == i) return &r;
    return nullptr;
}

std::optional<std::vector<Vec3f>> Animation::framePositions(size_t f, size_t i) const {
    CULLIDE_CHECK(f < frameCount() && i < scene.objects.size(), "frame or object index out of range");
    if (frames.empty()) return std::nullopt;
    const Object& o = scene.objects[i];
    const ObjectPose* pose = i < frames[f].poses.size() ? &frames[f].poses[i] : nullptr;
    if (pose && pose->positions) return pose->positions;
    std::vector<Vec3f> positions;
    std::string source;
    if (const PositionsFileRef* ref = positionsFileOf(i)) {
        const PositionsFile file(ref->path);
        file.readFrame(f, positions);
        source = file.source();
    } else if (pose && !pose->positionsFile.empty()) {
        positions = loadMesh(pose->positionsFile).positions;
        source = pose->positionsFile;
    } else {
        return std::nullopt;
    }
    const std::string where = "frame " + std::to_string(f);
    checkPosePositions(positions, o, source, where);
    checkWorldPositions(positions, pose && pose->transform ? *pose->transform : o.transform, o.name, source, where);
    return positions;
}

Scene Animation::sceneAt(size_t f) const {
    CULLIDE_CHECK(f < frameCount(), "frame index out of range");
    Scene s = scene;
    if (frames.empty()) return s;
    const Frame& fr = frames[f];
    for (size_t i = 0; i < fr.poses.size() && i < s.objects.size(); ++i)
        if (fr.poses[i].transform) s.objects[i].transform = *fr.poses[i].transform;
    for (size_t i = 0; i < s.objects.size(); ++i)
        if (std::optional<std::vector<Vec3f>> p = framePositions(f, i)) s.objects[i].mesh.positions = std::move(*p);
    return s;
}

static bool finite(const Transform& t) {
    return t.matrix().allFinite();
}

// The objects that a.positionsFiles gives positions (true at their index), after checking its
// entries against the scene and the frames.
static std::vector<bool> checkPositionsFiles(const Animation& a, const std::string& source) {
    std::vector<bool> tracked(a.scene.objects.size(), false);
    for (const PositionsFileRef& r : a.positionsFiles) {
        if (r.object >= a.scene.objects.size())
            throw InputError(source, "a positions file (" + r.path + ") is for object " + std::to_string(r.object) +
                                         ", but the scene has " + std::to_string(a.scene.objects.size()) + " objects");
        const std::string& name = a.scene.objects[r.object].name;
        if (tracked[r.object]) throw InputError(source, "object '" + name + "' has two positions files");
        if (a.frames.empty())
            throw InputError(source, "object '" + name + "' has a positions file, but the animation has no frames");
        tracked[r.object] = true;
    }
    for (size_t f = 0; f < a.frames.size(); ++f)
        for (size_t i = 0; i < a.frames[f].poses.size() && i < tracked.size(); ++i) {
            const ObjectPose& p = a.frames[f].poses[i];
            if (tracked[i] && (p.positions || !p.positionsFile.empty()))
                throw InputError(source, "frame " + std::to_string(f) + ", object '" + a.scene.objects[i].name +
                                             "': positions given both by the frame and by the object's positions file");
        }
    return tracked;
}

void validateAnimation(const Animation& a, const std::string& source) {
    checkSceneObjects(a.scene, source);
    const std::vector<bool> tracked = checkPositionsFiles(a, source);
    std::vector<Eigen::Vector3d> magnitudes;  // per object, of its base positions
    magnitudes.reserve(a.scene.objects.size());
    for (size_t i = 0; i < a.scene.objects.size(); ++i) {
        const Object& o = a.scene.objects[i];
        if (!finite(o.transform)) throw InputError(source, "object '" + o.name + "' has a non-finite transform");
        magnitudes.push_back(largestMagnitudes(o.mesh.positions));
        checkWorld(o.mesh.positions, magnitudes.back(), o.transform, o.name, source, "");
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
            const Transform& t = p.transform ? *p.transform : o.transform;
            if (p.positions) checkWorldPositions(*p.positions, t, o.name, source, where);
            else if (p.transform && p.positionsFile.empty() && !tracked[i])
                checkWorld(o.mesh.positions, magnitudes[i], t, o.name, source, where);
        }
    }
}

}  // namespace cullide
