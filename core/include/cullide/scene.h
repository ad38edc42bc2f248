// Scene model: named objects (each a mesh) and animations of them.
//
// Conventions
//   - An Object's mesh is in its own (model) space; `transform` places it in the world. A
//     transform is an affine map (rotation, uniform or non-uniform scale, translation) kept in
//     float, like the positions it is applied to.
//   - Scene::worldMesh(i) applies object i's transform in float, in one fixed order of operations,
//     so every backend and the oracle see bit-identical world coordinates.
//   - An Animation is a base scene plus frames. A frame may give, per object, a rigid/affine
//     transform (moving objects) and/or a full set of vertex positions in model space (deforming
//     objects); anything a frame leaves out stays as in the base scene. A deforming object's
//     positions may instead come from a positions file (positions_file.h) holding every frame of
//     it. Topology (the triangle list) never changes between frames.
#pragma once

#include "cullide/mesh.h"

#include <Eigen/Geometry>

#include <compare>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace cullide {

using Transform = Eigen::Affine3f;

// p' = T p, evaluated as M.col(0)*x + M.col(1)*y + M.col(2)*z + t in float, in that order.
Vec3f applyTransform(const Transform& t, const Vec3f& p);

// A triangle of a scene: the object's index in the scene, the triangle's index in its mesh (a PCS
// entry, an oracle's degenerate triangle, one side of an intersecting pair).
struct TriangleRef {
    uint32_t object = 0, triangle = 0;
    friend auto operator<=>(const TriangleRef&, const TriangleRef&) = default;
};

// An unordered pair of triangles of a scene, held as a < b (make() orders them): what a collision
// detector reports (a peer, a pair list given to `cullide audit`). A pair within one object has
// a.object == b.object.
struct TrianglePair {
    TriangleRef a, b;
    static TrianglePair make(TriangleRef x, TriangleRef y) { return x < y ? TrianglePair{x, y} : TrianglePair{y, x}; }
    bool selfPair() const { return a.object == b.object; }
    friend auto operator<=>(const TrianglePair&, const TrianglePair&) = default;
};

struct Object {
    std::string name;
    Mesh mesh;
    Transform transform = Transform::Identity();
};

struct Scene {
    std::vector<Object> objects;

    size_t triangleCount() const;
    size_t vertexCount() const;
    // Object i's mesh with its transform applied (same triangles, world positions). Throws
    // InputError("scene", ...) when a world coordinate is beyond kMaxWorldCoordinate or not finite
    // (a scene built in code; loaded scenes were checked with their file's name).
    Mesh worldMesh(size_t i) const;
};

// The whole scene as one geometry, as a backend draws it: every object's world mesh
// (Scene::worldMesh), in object order, its vertex indices offset past the objects before it.
struct FlatScene {
    Mesh mesh;
    // Object i's triangles are [firstTriangle[i], firstTriangle[i + 1]) in mesh.triangles (one
    // entry per object, plus the total).
    std::vector<uint32_t> firstTriangle;

    uint32_t triangle(uint32_t object, uint32_t t) const { return firstTriangle[object] + t; }
};
// Throws InputError("scene", ...) when the scene has more than 2^32 vertices or triangles, or a
// world coordinate that Scene::worldMesh refuses.
FlatScene flatten(const Scene& scene);

// What one frame of an animation changes for one object.
struct ObjectPose {
    std::optional<Transform> transform;  // replaces the object's transform
    std::optional<std::vector<Vec3f>> positions;  // replaces its model-space positions (same count)
    // Or, when `positions` is empty, the mesh file whose positions replace them, read (and checked
    // again) each time the frame is used: a scene file's animation keeps one frame in memory, not
    // all of them (loadScene reads and checks every such frame once, then drops its positions).
    std::string positionsFile;
};

struct Frame {
    std::vector<ObjectPose> poses;  // empty, or one per object of the base scene
};

// An object whose model-space positions in every frame come from a positions file
// (positions_file.h): frame f of the animation takes frame f of the file, read (and checked) each
// time the frame is used; the file has one frame per frame of the animation. No frame gives
// that object positions of its own (a frame may still give it a transform).
struct PositionsFileRef {
    size_t object = 0;  // index in the base scene
    std::string path;
};

struct Animation {
    Scene scene;  // the base scene (frame-independent data: names, triangles)
    std::vector<Frame> frames;  // may be empty: a still scene
    std::vector<PositionsFileRef> positionsFiles;  // at most one per object (loadScene: in object order)

    size_t frameCount() const { return frames.empty() ? 1 : frames.size(); }
    // The scene as it is at frame f (f < frameCount()). Throws InputError(file, ...) when a
    // pose's positionsFile or a positions file no longer reads as it did (gone, changed vertex
    // count, non-finite, world coordinates checkWorldPositions refuses), naming the frame.
    Scene sceneAt(size_t f) const;
    // Object i's model-space positions at frame f when that frame changes them (nullopt when they
    // are the base mesh's): a pose's positions, its positionsFile's, or the object's positions
    // file's frame f, checked as sceneAt checks them.
    std::optional<std::vector<Vec3f>> framePositions(size_t f, size_t i) const;
    // The object's entry in positionsFiles, or nullptr.
    const PositionsFileRef* positionsFileOf(size_t i) const;
};

// The largest magnitude a world coordinate may have. The exact predicates decide on coordinates up
// to 2^60 (docs/oracle.md), so every scene is held to it where its world geometry is made: a
// transform that overflows float (Inf, NaN) or goes beyond it is refused when the scene is loaded
// or built, not when the oracle meets it.
inline constexpr float kMaxWorldCoordinate = 0x1p60f;

// Throws InputError(source, where + "object 'name': ...") unless every one of `positions` under
// `transform` (applyTransform, in float) has finite coordinates of magnitude at most
// kMaxWorldCoordinate. `where` ("frame 3") may be empty.
void checkWorldPositions(std::span<const Vec3f> positions, const Transform& transform, const std::string& objectName,
                         const std::string& source, const std::string& where);

// Throws InputError(source, where + ": ...") when `name` cannot name a new object of a scene: it is
// empty, or `taken` (an earlier object has it). Frames and results name objects, so a name is a
// key; scene files and the Python API refuse the same names. `where` may be empty.
void checkObjectName(const std::string& name, bool taken, const std::string& source, const std::string& where);
// Throws InputError(source, ...) when the scene has no objects, or an object's name fails
// checkObjectName.
void checkSceneObjects(const Scene& scene, const std::string& source);

// Throws InputError(source, ...) when the animation is not one cullide can use: objects as
// checkSceneObjects wants them; a frame that does not fit the base scene (wrong number of poses,
// wrong number of positions, non-finite positions or transforms); a positionsFiles entry for no
// object, a second one for an object, one without frames, or one for an object a frame gives
// positions too; world coordinates, in the base scene or any frame held in memory, that
// checkWorldPositions refuses. (Files are checked where they are read: by the scene loader, and
// again by sceneAt.)
void validateAnimation(const Animation& animation, const std::string& source);
// Throws InputError(source, where + ...) unless `positions` fit `object`'s mesh (same vertex
// count, all finite).
void checkPosePositions(std::span<const Vec3f> positions, const Object& object, const std::string& source,
                        const std::string& where);

}  // namespace cullide
