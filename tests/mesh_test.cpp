// Tests for the mesh and scene model (mesh.cpp, scene.cpp): validation and the fixed-order
// transform evaluation every backend relies on.
#include "cullide/error.h"
#include "cullide/mesh.h"
#include "cullide/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace cullide {
namespace {

Mesh triangle() {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    return m;
}

std::string messageOf(const Mesh& m) {
    try {
        validateMesh(m, "src.off");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

// Trap: validation that forgets a class, or whose message does not say which vertex/triangle.
TEST(MeshValidate, NamesTheFirstProblemAndTheSource) {
    EXPECT_EQ(messageOf(triangle()), "");
    EXPECT_EQ(messageOf(Mesh{}), "src.off: empty mesh: no vertices");
    Mesh noTriangles = triangle();
    noTriangles.triangles.clear();
    EXPECT_EQ(messageOf(noTriangles), "src.off: mesh has zero triangles");
    Mesh nan = triangle();
    nan.positions[2].y() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(messageOf(nan).find("vertex 2 has a non-finite"), std::string::npos);
    Mesh inf = triangle();
    inf.positions[1].z() = -std::numeric_limits<float>::infinity();
    EXPECT_NE(messageOf(inf).find("vertex 1 has a non-finite"), std::string::npos);
    Mesh oor = triangle();
    oor.triangles.push_back({0, 1, 3});
    EXPECT_NE(messageOf(oor).find("triangle 1 refers to vertex 3"), std::string::npos);
}

// Trap: "cleaning" input. Degenerate triangles and unreferenced vertices are legal and pass.
TEST(MeshValidate, DegenerateAndUnreferencedPass) {
    Mesh m = triangle();
    m.triangles.push_back({0, 0, 1});
    m.positions.push_back({5, 5, 5});
    EXPECT_NO_THROW(validateMesh(m, "x"));
    const Bounds b = referencedBounds(m);
    EXPECT_EQ(b.hi, Vec3f(1, 1, 0));  // (5,5,5) is unreferenced
}

// Trap: Eigen's `transform * p` may fuse or reorder operations; applyTransform must be the
// documented ((m0 x + m1 y) + m2 z) + t in float, bit for bit, which worldMesh uses.
TEST(MeshScene, ApplyTransformHasOneFixedEvaluationOrder) {
    Transform t = Transform::Identity();
    t.matrix() << 0.1f, 0.2f, 0.3f, 1e8f, 0.7f, -0.3f, 1e-3f, -1e8f, 3, 1e7f, -1e7f, 0.5f, 0, 0, 0, 1;
    const Vec3f p(1.1f, 2.2f, 3.3f);
    const Vec3f r = applyTransform(t, p);
    for (int row = 0; row < 3; ++row) {
        volatile float a = t.matrix()(row, 0) * p.x();
        volatile float b = t.matrix()(row, 1) * p.y();
        volatile float c = t.matrix()(row, 2) * p.z();
        volatile float s = a + b;
        s = s + c;
        s = s + t.matrix()(row, 3);
        EXPECT_EQ(r[row], s) << "row " << row;
    }
    Scene scene;
    scene.objects.push_back({"a", triangle(), t});
    const Mesh w = scene.worldMesh(0);
    EXPECT_EQ(w.triangles, triangle().triangles);
    for (size_t i = 0; i < 3; ++i) EXPECT_EQ(w.positions[i], applyTransform(t, triangle().positions[i]));
    EXPECT_EQ(scene.triangleCount(), 1u);
    EXPECT_EQ(scene.vertexCount(), 3u);
}

// Trap: frames that leak into each other, or a pose that replaces more than it says.
TEST(MeshAnimation, SceneAtAppliesOnlyWhatTheFrameGives) {
    Animation a;
    a.scene.objects.push_back({"a", triangle(), Transform::Identity()});
    a.scene.objects.push_back({"b", triangle(), Transform(Eigen::Translation3f(0, 0, 1))});
    EXPECT_EQ(a.frameCount(), 1u);
    EXPECT_EQ(a.sceneAt(0).objects[1].transform.matrix(), a.scene.objects[1].transform.matrix());

    Frame moveA;
    moveA.poses.resize(2);
    moveA.poses[0].transform = Transform(Eigen::Translation3f(5, 0, 0));
    Frame deformB;
    deformB.poses.resize(2);
    deformB.poses[1].positions = std::vector<Vec3f>{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
    a.frames = {moveA, deformB, Frame{}};
    EXPECT_EQ(a.frameCount(), 3u);
    const Scene s0 = a.sceneAt(0), s1 = a.sceneAt(1), s2 = a.sceneAt(2);
    EXPECT_EQ(s0.objects[0].transform.translation(), Vec3f(5, 0, 0));
    EXPECT_EQ(s0.objects[1].mesh.positions, triangle().positions);
    EXPECT_EQ(s1.objects[0].transform.translation(), Vec3f(0, 0, 0));  // frame 0's move does not leak
    EXPECT_EQ(s1.objects[1].mesh.positions[1], Vec3f(2, 0, 0));
    EXPECT_EQ(s1.objects[1].transform.translation(), Vec3f(0, 0, 1));  // positions only: transform kept
    EXPECT_EQ(s2.objects[1].mesh.positions, triangle().positions);
    EXPECT_NO_THROW(validateAnimation(a, "anim.json"));
}

// Trap: a frame that does not fit the scene being accepted and then read out of bounds.
TEST(MeshAnimation, ValidateRefusesFramesThatDoNotFit) {
    Animation a;
    a.scene.objects.push_back({"a", triangle(), Transform::Identity()});
    Frame wrongPoses;
    wrongPoses.poses.resize(2);
    a.frames = {wrongPoses};
    EXPECT_THROW(validateAnimation(a, "s"), InputError);
    Frame wrongCount;
    wrongCount.poses.resize(1);
    wrongCount.poses[0].positions = std::vector<Vec3f>{{0, 0, 0}};
    a.frames = {wrongCount};
    try {
        validateAnimation(a, "s.json");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("1 positions, but the mesh has 3"), std::string::npos) << e.what();
    }
    Frame nanTransform;
    nanTransform.poses.resize(1);
    Transform t = Transform::Identity();
    t.matrix()(0, 3) = std::numeric_limits<float>::quiet_NaN();
    nanTransform.poses[0].transform = t;
    a.frames = {nanTransform};
    EXPECT_THROW(validateAnimation(a, "s"), InputError);
    a.frames.clear();
    a.scene.objects[0].transform = t;
    EXPECT_THROW(validateAnimation(a, "s"), InputError);
}

}  // namespace
}  // namespace cullide
