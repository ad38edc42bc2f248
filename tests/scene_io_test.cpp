// Tests for scene_io: the JSON scene format (docs/scene-format.md), its errors, and writeScene.
#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene_io.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <sstream>

namespace cullide {
namespace {

using test::TempDir;
using test::testData;

const auto slurp = test::readBytes;

// Trap: mesh paths resolved against the working folder instead of the scene file's; transforms
// composed in another order than T * R * S; frames applied to the wrong object.
TEST(SceneIo, LoadsObjectsTransformsAndFrames) {
    const Animation a = loadScene(testData("good/scene.json"));
    ASSERT_EQ(a.scene.objects.size(), 3u);
    EXPECT_EQ(a.scene.objects[0].name, "polys");
    EXPECT_EQ(a.scene.objects[1].name, "cube");
    EXPECT_EQ(a.scene.objects[2].name, "matrixed");
    EXPECT_EQ(a.scene.objects[0].mesh, loadMesh(testData("good/polys.off")));
    EXPECT_EQ(a.scene.objects[1].mesh.vertexCount(), 8u);
    // polys: scale 2, then 90 degrees about z, then translate (1,2,3): (1,0,0) -> (2,0,0) -> (0,2,0) -> (1,4,3).
    const Vec3f p = applyTransform(a.scene.objects[0].transform, Vec3f(1, 0, 0));
    EXPECT_NEAR(p.x(), 1, 1e-6);
    EXPECT_NEAR(p.y(), 4, 1e-6);
    EXPECT_NEAR(p.z(), 3, 1e-6);
    EXPECT_EQ(a.scene.objects[2].transform.translation(), Vec3f(5, 0, 0));
    EXPECT_TRUE(a.scene.objects[1].transform.matrix().isIdentity(0));

    ASSERT_EQ(a.frameCount(), 3u);
    EXPECT_TRUE(a.frames[0].poses.empty());
    const Mesh moved = loadMesh(testData("good/polys_moved.off"));
    const Scene f1 = a.sceneAt(1);
    EXPECT_EQ(f1.objects[0].mesh.positions, moved.positions);
    EXPECT_EQ(f1.objects[0].transform.matrix(), a.scene.objects[0].transform.matrix());
    const Scene f2 = a.sceneAt(2);
    EXPECT_EQ(f2.objects[1].transform.translation(), Vec3f(0, 0, 1));
    EXPECT_EQ(applyTransform(f2.objects[0].transform, Vec3f(1, 1, 1)), Vec3f(1, 2, 3));
    EXPECT_EQ(f2.objects[2].transform.matrix(), a.scene.objects[2].transform.matrix());
}

// Trap: a mesh path given where a scene is expected must work (one object named after the file).
TEST(SceneIo, PlainMeshFileIsAOneObjectScene) {
    const Animation a = loadScene(testData("good/polys_binary.ply"));
    ASSERT_EQ(a.scene.objects.size(), 1u);
    EXPECT_EQ(a.scene.objects[0].name, "polys_binary");
    EXPECT_EQ(a.scene.objects[0].mesh, loadMesh(testData("good/polys_binary.ply")));
    EXPECT_EQ(a.frameCount(), 1u);
}

struct BadScene {
    const char* file;
    const char* cause;
};

// Trap: errors that do not name the scene file, that point nowhere (malformed JSON without line
// and column), or input accepted silently (unknown keys, duplicate keys that nlohmann would
// collapse, duplicate names, frames naming unknown objects, wrong position counts, transforms of
// finite numbers whose world coordinates overflow float or pass the oracle's 2^60, in the base
// scene or in one frame).
class SceneIoBad : public ::testing::TestWithParam<BadScene> {};

TEST_P(SceneIoBad, ThrowsInputErrorNamingSceneAndCause) {
    const std::string path = testData(GetParam().file);
    try {
        (void)loadScene(path);
        FAIL() << "loaded " << path;
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
        EXPECT_NE(what.find(GetParam().cause), std::string::npos) << what;
    }
}

INSTANTIATE_TEST_SUITE_P(
    SceneIo, SceneIoBad,
    ::testing::Values(BadScene{"bad/malformed.json", "malformed JSON at line 3, column 47"},
                      BadScene{"bad/missing_key.json", "objects[0]: missing key 'mesh'"},
                      BadScene{"bad/wrong_type.json",
                               "objects[0].transform.scale: expected a number or an array of 3 numbers, got string"},
                      BadScene{"bad/unknown_key.json", "unknown key 'colour'"},
                      BadScene{"bad/duplicate_name.json", "duplicate object name 'a'"},
                      BadScene{"bad/duplicate_key.json", "duplicate key 'name'"},
                      BadScene{"bad/unknown_object_in_frame.json", "unknown object 'b'"},
                      BadScene{"bad/wrong_position_count.json",
                               "has 8 vertices, but object 'a' has 7 (wrong position count)"},
                      BadScene{"bad/missing_mesh.json", "no_such_mesh.off: cannot open: no such file"},
                      BadScene{"bad/nul_in_mesh_path.json",
                               "polys.off\\0.ply: cannot open: the path contains a NUL byte"},
                      BadScene{"bad/nonfinite_transform.json", "is not a finite float"},
                      BadScene{"bad/overflow_transform.json", "object 'cow': world coordinates overflow"},
                      BadScene{"bad/overflow_frame.json", "frame 3, object 'cow': world coordinates overflow"},
                      BadScene{"bad/beyond_2_60.json", "lies beyond 2^60 in magnitude"},
                      BadScene{"bad/does_not_exist.json", "no such file"},
                      BadScene{"bad/unknown_extension.xyz", "unknown scene format"},
                      BadScene{"bad/nan.off", "non-finite"}),
    // Stable, readable names (the default prints the pointers, which change with ASLR and make
    // CTest's discovered names miss the tests).
    [](const auto& param) { return cullide::test::paramName(param.param.file); });

// Trap: a scene built in code (the C++ API, no file) whose transform overflows float: its Inf world
// coordinates must be refused, naming the object, wherever world geometry is made (worldMesh,
// flatten, a prune), not reach a backend as "the view box has a non-finite bound".
TEST(SceneIo, WorldCoordinatesAreCheckedWhereTheyAreMade) {
    Transform huge = Transform::Identity();
    huge.matrix().topLeftCorner<3, 3>() *= 1e38f;
    huge.translation() = Vec3f(3e38f, 0, 0);
    const Scene s = test::sceneOf(
        {{test::box({0, 0, 0}, {1, 1, 1}), Transform::Identity()}, {test::box({0, 0, 0}, {1, 1, 1}), huge}});
    auto refused = [](const std::function<void()>& f, const std::string& words) {
        try {
            f();
            ADD_FAILURE() << "accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    };
    refused([&] { (void)s.worldMesh(1); }, "scene: object 'o1': world coordinates overflow");
    refused([&] { (void)flatten(s); }, "object 'o1': world coordinates overflow");
    refused([&] { (void)runCullide(s, *raster::makeCpuBackend(), CullideOptions{}); }, "object 'o1'");
    Animation a;
    a.scene = s;
    refused([&] { validateAnimation(a, "s.json"); }, "s.json: object 'o1': world coordinates overflow");
    a.scene.objects[1].transform = Transform::Identity();
    a.frames.resize(2);
    a.frames[1].poses.resize(2);
    a.frames[1].poses[0].transform = huge;
    refused([&] { validateAnimation(a, "s.json"); }, "s.json: frame 1, object 'o0': world coordinates overflow");
    EXPECT_NO_THROW(s.worldMesh(0));
}

// Trap: names that frames and results cannot tell apart (empty, or an earlier object's), or a
// scene without objects, accepted from code although a scene file refuses them (one check in core).
TEST(SceneIo, ObjectNamesAreKeys) {
    Scene s = test::sceneOf({{test::box({0, 0, 0}, {1, 1, 1}), Transform::Identity()},
                             {test::box({0, 0, 0}, {1, 1, 1}), Transform::Identity()}});
    EXPECT_NO_THROW(checkSceneObjects(s, "x"));
    s.objects[1].name = "o0";
    EXPECT_THROW(checkSceneObjects(s, "x"), InputError);
    Animation a;
    a.scene = s;
    TempDir d;
    EXPECT_THROW(writeScene(a, d / "s.json"), InputError);
    s.objects[1].name = "";
    EXPECT_THROW(checkSceneObjects(s, "x"), InputError);
    try {
        checkSceneObjects(Scene{}, "x");
        ADD_FAILURE() << "an empty scene";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "x: the scene has no objects; it needs at least one");
    }
}

// Trap: writeScene output that does not load back to the same animation (bit for bit: meshes,
// transforms, per-frame positions), or whose bytes differ between two writes.
TEST(SceneIo, WriteThenLoadRoundTripsAndIsDeterministic) {
    const Animation a = loadScene(testData("good/scene.json"));
    TempDir d1, d2;
    writeScene(a, d1 / "s.json");
    writeScene(a, d2 / "s.json");
    const Animation b = loadScene(d1 / "s.json");
    ASSERT_EQ(b.scene.objects.size(), a.scene.objects.size());
    ASSERT_EQ(b.frameCount(), a.frameCount());
    for (size_t f = 0; f < a.frameCount(); ++f) {
        const Scene sa = a.sceneAt(f), sb = b.sceneAt(f);
        for (size_t i = 0; i < sa.objects.size(); ++i) {
            EXPECT_EQ(sa.objects[i].name, sb.objects[i].name);
            EXPECT_EQ(sa.objects[i].mesh, sb.objects[i].mesh);
            EXPECT_EQ(sa.objects[i].transform.matrix(), sb.objects[i].transform.matrix())
                << "frame " << f << " object " << i;
        }
    }
    size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(d1.path())) {
        ++files;
        EXPECT_EQ(slurp(e.path()), slurp(d2 / e.path().filename().string())) << e.path();
    }
    EXPECT_EQ(files, 1u + 3u + 2u);  // the scene, three meshes, two frame position files
}

// Trap: frame positions read lazily (loadScene keeps one frame in memory, not all) but trusted
// without a check when used: a frame file changed after loading (fewer vertices, non-finite, gone)
// must give an InputError naming that file at sceneAt, and the frames without it still work.
TEST(SceneIo, FramePositionsAreCheckedWhenUsed) {
    TempDir d;
    writeScene(loadScene(testData("good/scene.json")), d / "s.json");
    const Animation a = loadScene(d / "s.json");
    ASSERT_EQ(a.frameCount(), 3u);
    const std::string frameFile = a.frames[1].poses[0].positionsFile;
    ASSERT_FALSE(frameFile.empty());
    EXPECT_FALSE(a.frames[1].poses[0].positions.has_value());  // not held in memory
    const Scene before = a.sceneAt(1);
    auto expectNamed = [&](const std::string& bytes, const std::string& what) {
        test::writeBytes(frameFile, bytes);
        try {
            a.sceneAt(1);
            ADD_FAILURE() << what << ": no error";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(std::filesystem::path(frameFile).filename().string()),
                      std::string::npos)
                << what << ": " << e.what();
        }
        EXPECT_EQ(a.sceneAt(0).objects.size(), 3u) << what;  // frame 0 reads no file
    };
    expectNamed("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "fewer vertices");
    std::string nan = "OFF\n" + std::to_string(before.objects[0].mesh.vertexCount()) + " 1 0\n";
    for (size_t v = 0; v < before.objects[0].mesh.vertexCount(); ++v) nan += v == 1 ? "nan 0 0\n" : "0 0 0\n";
    expectNamed(nan + "3 0 1 2\n", "a NaN vertex");
    std::filesystem::remove(frameFile);
    try {
        a.sceneAt(1);
        ADD_FAILURE() << "a removed frame file gave no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(std::filesystem::path(frameFile).filename().string()), std::string::npos)
            << e.what();
    }
}

// Trap: a failed scene write leaving a file behind, or a message without the path.
TEST(SceneIo, FailedWriteThrowsNamingTheFile) {
    const Animation a = loadScene(testData("good/polys.off"));
    TempDir d;
    const auto target = d / "missing_folder" / "s.json";
    try {
        writeScene(a, target);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("missing_folder"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(target));
}

// Trap: a scene file that cannot be written (here a folder is in its place) after its meshes were:
// the meshes left behind without the scene that names them. A mesh that was there before stays.
TEST(SceneIo, FailedSceneWriteRemovesTheMeshesItWrote) {
    Animation a = loadScene(testData("good/polys.off"));
    a.scene.objects.push_back(a.scene.objects[0]);
    a.scene.objects[0].name = "first", a.scene.objects[1].name = "second";
    TempDir d;
    std::filesystem::create_directory(d / "s.json");
    std::ofstream(d / "s_1_second.off") << "not ours to remove\n";
    EXPECT_THROW(writeScene(a, d / "s.json"), InputError);
    EXPECT_FALSE(std::filesystem::exists(d / "s_0_first.off"));
    EXPECT_TRUE(std::filesystem::exists(d / "s_1_second.off"));
}

}  // namespace
}  // namespace cullide
