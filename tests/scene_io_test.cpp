// Tests for scene_io: the JSON scene format (docs/scene-format.md), its errors, and writeScene.
#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "cullide/positions_file.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene_io.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
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
    EXPECT_EQ(files, 1u + 3u + 1u);  // the scene, three meshes, the deforming object's positions file
    ASSERT_EQ(b.positionsFiles.size(), 1u);
    EXPECT_EQ(b.positionsFiles[0].object, 0u);
    EXPECT_EQ(std::filesystem::path(b.positionsFiles[0].path).filename(), "s_0_polys.pos");
}

// A copy of tests/data/good/scene.json and the meshes it names in `d`, to be changed by a test.
void copyGoodScene(const TempDir& d) {
    for (const char* f : {"scene.json", "polys.off", "polys_moved.off", "cube_binary.stl", "polys_ascii.ply"})
        std::filesystem::copy_file(testData((std::string("good/") + f).c_str()), d / f);
}

// The message of the InputError `f` throws, or "" when it throws none.
std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

// Trap: frame positions read lazily (loadScene keeps one frame in memory, not all) but trusted
// without a check when used: a per-frame mesh file changed after loading (fewer vertices,
// non-finite, gone) must give an InputError naming that file at sceneAt, and the frames without it
// still work.
TEST(SceneIo, FramePositionsAreCheckedWhenUsed) {
    TempDir d;
    copyGoodScene(d);
    const Animation a = loadScene(d / "scene.json");
    ASSERT_EQ(a.frameCount(), 3u);
    const std::string frameFile = a.frames[1].poses[0].positionsFile;
    ASSERT_EQ(std::filesystem::path(frameFile).filename(), "polys_moved.off");
    EXPECT_FALSE(a.frames[1].poses[0].positions.has_value());  // not held in memory
    const Scene before = a.sceneAt(1);
    auto expectNamed = [&](const std::string& bytes, const std::string& what) {
        test::writeBytes(frameFile, bytes);
        EXPECT_NE(errorOf([&] { a.sceneAt(1); }).find("polys_moved.off"), std::string::npos) << what;
        EXPECT_EQ(a.sceneAt(0).objects.size(), 3u) << what;  // frame 0 reads no file
    };
    expectNamed("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "fewer vertices");
    std::string nan = "OFF\n" + std::to_string(before.objects[0].mesh.vertexCount()) + " 1 0\n";
    for (size_t v = 0; v < before.objects[0].mesh.vertexCount(); ++v) nan += v == 1 ? "nan 0 0\n" : "0 0 0\n";
    expectNamed(nan + "3 0 1 2\n", "a NaN vertex");
    std::filesystem::remove(frameFile);
    EXPECT_NE(errorOf([&] { a.sceneAt(1); }).find("polys_moved.off"), std::string::npos);
}

// Trap: a positions file's frames trusted because its header was checked at load: a NaN written
// into frame 1 later must be refused when frame 1 is used, naming the file and the frame, while
// frames 0 and 2 still load; a file cut short or gone is named at the next frame used.
TEST(SceneIo, PositionsFileFramesAreCheckedWhenUsed) {
    TempDir d;
    writeScene(loadScene(testData("good/scene.json")), d / "s.json");
    const Animation a = loadScene(d / "s.json");
    ASSERT_EQ(a.positionsFiles.size(), 1u);
    const std::string file = a.positionsFiles[0].path;
    std::string bytes = slurp(file);
    const size_t vertices = a.scene.objects[0].mesh.vertexCount();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(bytes.data() + 32 + vertices * 12 + 12 + 4, &nan, 4);  // frame 1, vertex 1, y
    test::writeBytes(file, bytes);
    EXPECT_EQ(errorOf([&] { a.sceneAt(1); }), file + ": frame 1: vertex 1 is not finite (NaN or Inf)");
    EXPECT_EQ(a.sceneAt(0).objects[0].mesh, a.scene.objects[0].mesh);
    EXPECT_EQ(a.sceneAt(2).objects[0].mesh.positions, loadMesh(testData("good/polys_moved.off")).positions);
    std::filesystem::resize_file(file, bytes.size() - 1);
    EXPECT_NE(errorOf([&] { a.sceneAt(0); }).find(file + ": truncated"), std::string::npos);
    std::filesystem::remove(file);
    EXPECT_NE(errorOf([&] { a.sceneAt(2); }).find(file + ": cannot open: no such file"), std::string::npos);
}

// A scene of objects "a" and "b" (both polys.off, 7 vertices) in `d`, with `animation` as its
// animation's JSON text.
std::string positionsScene(const TempDir& d, const std::string& animation) {
    std::filesystem::copy_file(testData("good/polys.off"), d / "polys.off",
                               std::filesystem::copy_options::skip_existing);
    const std::string path = (d / "s.json").string();
    test::writeBytes(path, R"({"objects": [{"name": "a", "mesh": "polys.off"}, {"name": "b", "mesh": "polys.off"}],
                              "animation": )" + animation + "}");
    return path;
}

// `frames` frames of `vertices` positions as a positions file at `path` (vertex v of frame f at
// (v, f, 0)).
void writeFrames(const std::filesystem::path& path, uint32_t vertices, uint64_t frames) {
    std::vector<Vec3f> p(vertices);
    writePositionsFile(path, vertices, frames, [&](uint64_t f) {
        for (uint32_t v = 0; v < vertices; ++v) p[v] = Vec3f(float(v), float(f), 0);
        return std::span<const Vec3f>(p);
    });
}

// Trap: a positions file that does not fit its scene accepted, or refused without saying which
// file and why (a mesh or another format given as positions, a file cut short or with bytes
// after it, another object's vertex count, frame counts that disagree with the frames or with
// another file, an unknown object, positions given twice for one frame, a FIFO that would block
// the load): each refused at load, naming the scene, the key, the file and the cause.
TEST(SceneIo, PositionsFilesThatDoNotFitAreRefusedAtLoad) {
    TempDir d;
    writeFrames(d / "two.pos", 7, 2);
    writeFrames(d / "three.pos", 7, 3);
    writeFrames(d / "six_vertices.pos", 6, 2);
    std::string cut = slurp(d / "two.pos");
    test::writeBytes(d / "cut.pos", cut.substr(0, cut.size() - 12));
    test::writeBytes(d / "long.pos", cut + "x");
    ASSERT_EQ(::mkfifo((d / "fifo.pos").c_str(), 0600), 0);
    struct Case {
        std::string animation, cause;
    };
    const std::string frames3 = R"("frames": [{}, {}, {}])";
    for (const Case& c : std::vector<Case>{
             {R"({"positions": {"a": "polys.off"}})", "animation.positions.a: " + (d / "polys.off").string() +
                                                         ": wrong magic 'OFF\\x0a# a ': not a cullide positions file"},
             {R"({"positions": {"a": "cut.pos"}})", "cut.pos: truncated: 188 bytes, but the header's 2 frame(s) of 7 "
                                                    "vertices need 200"},
             {R"({"positions": {"a": "long.pos"}})", "long.pos: size mismatch: 201 bytes"},
             {R"({"positions": {"a": "six_vertices.pos"}})",
              "animation.positions.a: 'six_vertices.pos' has 6 vertices per frame, but object 'a' has 7 (wrong vertex "
              "count)"},
             {R"({"positions": {"a": "two.pos"}, )" + frames3 + "}",
              "animation.positions: the positions files have 2 frames, but animation.frames has 3 (wrong frame count)"},
             {R"({"positions": {"a": "two.pos", "b": "three.pos"}})",
              "animation.positions.b: 'three.pos' has 3 frames, but 'two.pos' has 2 (wrong frame count)"},
             {R"({"positions": {"zz": "two.pos"}})", "animation.positions.zz: unknown object 'zz'"},
             {R"({"positions": {"a": "fifo.pos"}})", "fifo.pos: cannot read: not a regular file (a FIFO)"},
             {R"({"positions": {}})", "'animation': missing key 'frames'"},
             {R"({"positions": {"a": "two.pos"}, "frames": [{}, {"objects": {"a": {"positions": "polys.off"}}}]})",
              "frame 1, object 'a': positions given both by the frame and by the object's positions file"}}) {
        const std::string scene = positionsScene(d, c.animation);
        const std::string what = errorOf([&] { (void)loadScene(scene); });
        EXPECT_EQ(what.rfind(scene + ": ", 0), 0u) << what;
        EXPECT_NE(what.find(c.cause), std::string::npos) << c.animation << "\n" << what;
    }
}

// Trap: the frame count of a scene whose frames are left out not taken from its positions files,
// or a frame's transform for an object with a positions file dropped: frame f is the file's frame
// f under the frame's transform (or the object's).
TEST(SceneIo, PositionsFilesGiveTheFrames) {
    TempDir d;
    writeFrames(d / "a.pos", 7, 3);
    const Animation still = loadScene(positionsScene(d, R"({"positions": {"a": "a.pos"}})"));
    ASSERT_EQ(still.frameCount(), 3u);
    for (size_t f = 0; f < 3; ++f) {
        const Scene s = still.sceneAt(f);
        EXPECT_EQ(s.objects[0].mesh.positions[4], Vec3f(4, float(f), 0)) << f;
        EXPECT_EQ(s.objects[1].mesh, still.scene.objects[1].mesh);
    }
    const Animation moved = loadScene(
        positionsScene(d, R"({"positions": {"a": "a.pos"}, "frames": [{}, {"objects": {"a": {"transform": {"translate": [0, 0, 5]}}}}, {}]})"));
    const Scene s1 = moved.sceneAt(1);
    EXPECT_EQ(applyTransform(s1.objects[0].transform, s1.objects[0].mesh.positions[4]), Vec3f(4, 1, 5));
}

// Trap: an animation built in code whose positions files cannot be what it says (for an object
// it does not have, two for one object, frames from a file in a still scene, an object given
// positions by a frame and by its file): refused by validateAnimation, so writeScene and the
// Python module refuse it too, instead of sceneAt choosing one.
TEST(SceneIo, PositionsFileRefsAreChecked) {
    Animation a;
    a.scene = test::sceneOf({{test::box({0, 0, 0}, {1, 1, 1}), Transform::Identity()}});
    a.positionsFiles = {{0, "a.pos"}};
    EXPECT_EQ(errorOf([&] { validateAnimation(a, "s"); }),
              "s: object 'o0' has a positions file, but the animation has no frames");
    a.frames.resize(2);
    EXPECT_EQ(errorOf([&] { validateAnimation(a, "s"); }), "");
    a.positionsFiles.push_back({0, "b.pos"});
    EXPECT_EQ(errorOf([&] { validateAnimation(a, "s"); }), "s: object 'o0' has two positions files");
    a.positionsFiles = {{1, "a.pos"}};
    EXPECT_EQ(errorOf([&] { validateAnimation(a, "s"); }),
              "s: a positions file (a.pos) is for object 1, but the scene has 1 objects");
    a.positionsFiles = {{0, "a.pos"}};
    a.frames[1].poses.resize(1);
    a.frames[1].poses[0].positions = a.scene.objects[0].mesh.positions;
    EXPECT_EQ(errorOf([&] { validateAnimation(a, "s"); }),
              "s: frame 1, object 'o0': positions given both by the frame and by the object's positions file");
}

// Trap: writeScene writing a file per frame again, storing frames that leave an object's
// positions as something else than the base positions, or giving other bytes for the same
// animation: one positions file per deforming object with every frame, frames kept only for their
// transforms (left out when none has one), and the written scene loads back bit for bit.
TEST(SceneIo, WriteSceneWritesOnePositionsFilePerDeformingObject) {
    Animation a;
    a.scene = test::sceneOf({{test::box({0, 0, 0}, {1, 1, 1}), Transform::Identity()},
                             {test::box({2, 0, 0}, {3, 1, 1}), Transform::Identity()}});
    a.frames.resize(3);
    a.frames[1].poses.resize(2);
    std::vector<Vec3f> bent = a.scene.objects[0].mesh.positions;
    bent[5] += Vec3f(0.25f, -0.0f, 1e-7f);
    a.frames[1].poses[0].positions = bent;
    TempDir d1, d2;
    writeScene(a, d1 / "s.json");
    const std::string json = slurp(d1 / "s.json");
    EXPECT_NE(json.find(R"("positions": {)" "\n" R"(      "o0": "s_0_o0.pos")"), std::string::npos) << json;
    EXPECT_EQ(json.find("frames"), std::string::npos) << json;  // no frame gives a transform
    EXPECT_EQ(slurp(d1 / "s_0_o0.pos").size(), 32u + 3 * 8 * 12);
    a.frames[2].poses.resize(2);
    a.frames[2].poses[1].transform = test::rotation(0, 0, 0, Vec3f(0, 0, 1));
    writeScene(a, d1 / "s.json");
    writeScene(a, d2 / "s.json");
    size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(d1.path())) {
        ++files;
        EXPECT_EQ(slurp(e.path()), slurp(d2 / e.path().filename().string())) << e.path();
    }
    EXPECT_EQ(files, 1u + 2u + 1u);  // the scene, two meshes, one positions file
    const Animation b = loadScene(d1 / "s.json");
    ASSERT_EQ(b.frameCount(), 3u);
    for (size_t f = 0; f < 3; ++f)
        for (size_t i = 0; i < 2; ++i) {
            const Scene sa = a.sceneAt(f), sb = b.sceneAt(f);
            EXPECT_EQ(sa.objects[i].mesh, sb.objects[i].mesh) << f << " " << i;
            EXPECT_EQ(sa.objects[i].transform.matrix(), sb.objects[i].transform.matrix()) << f << " " << i;
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

// Trap: a scene file that cannot be written (here a folder is in its place) after its meshes and
// positions files were: the files left behind without the scene that names them. A mesh that was
// there before stays.
TEST(SceneIo, FailedSceneWriteRemovesTheFilesItWrote) {
    Animation a = loadScene(testData("good/polys.off"));
    a.scene.objects.push_back(a.scene.objects[0]);
    a.scene.objects[0].name = "first", a.scene.objects[1].name = "second";
    a.frames.resize(2);
    a.frames[1].poses.resize(2);
    a.frames[1].poses[0].positions = a.scene.objects[0].mesh.positions;
    TempDir d;
    std::filesystem::create_directory(d / "s.json");
    std::ofstream(d / "s_1_second.off") << "not ours to remove\n";
    EXPECT_THROW(writeScene(a, d / "s.json"), InputError);
    EXPECT_FALSE(std::filesystem::exists(d / "s_0_first.off"));
    EXPECT_FALSE(std::filesystem::exists(d / "s_0_first.pos"));
    EXPECT_TRUE(std::filesystem::exists(d / "s_1_second.off"));
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(d.path()), std::filesystem::directory_iterator()), 2);
}

}  // namespace
}  // namespace cullide
