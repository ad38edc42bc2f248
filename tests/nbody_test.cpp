// Tests for core/src/nbody.cpp (makeNBody): reproducibility, the box, the intersections every
// frame has (counted by the exact oracle), and the requests it refuses. Small sizes: a few ms each.
#include "cullide/nbody.h"

#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/oracle.h"

#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <string>
#include <vector>

namespace cullide {
namespace {

// The meshes the command line passes: the bundled bunny and cow.
const std::vector<Mesh>& sources() {
    static const std::vector<Mesh> m = {loadMesh(CULLIDE_DATA_DIR "/meshes/bunny.off"),
                                        loadMesh(CULLIDE_DATA_DIR "/meshes/cow.off")};
    return m;
}

NBodyRequest request(size_t count, size_t perBody, size_t frames, uint64_t seed = 1) {
    NBodyRequest r;
    r.count = count;
    r.triangles = count * perBody;
    r.frames = frames;
    r.seed = seed;
    return r;
}

template <typename T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

bool sameBits(const Transform& a, const Transform& b) {
    return std::memcmp(a.matrix().data(), b.matrix().data(), sizeof(float) * 16) == 0;
}

// Every mesh and every pose, bit for bit.
bool sameBits(const Animation& a, const Animation& b) {
    if (a.scene.objects.size() != b.scene.objects.size() || a.frames.size() != b.frames.size()) return false;
    for (size_t i = 0; i < a.scene.objects.size(); ++i) {
        const Object &x = a.scene.objects[i], &y = b.scene.objects[i];
        if (x.name != y.name || !sameBits(x.mesh.positions, y.mesh.positions) ||
            !sameBits(x.mesh.triangles, y.mesh.triangles) || !sameBits(x.transform, y.transform))
            return false;
    }
    for (size_t f = 0; f < a.frames.size(); ++f)
        for (size_t i = 0; i < a.scene.objects.size(); ++i)
            if (!sameBits(*a.frames[f].poses[i].transform, *b.frames[f].poses[i].transform)) return false;
    return true;
}

// Trap: a draw that depends on something other than the request (an uninitialised field, the
// order of a hash container, a std distribution), or a seed that is ignored.
TEST(NBody, SameRequestSameBytesOtherSeedOtherBytes) {
    const Animation a = makeNBody(sources(), request(8, 64, 5));
    EXPECT_TRUE(sameBits(a, makeNBody(sources(), request(8, 64, 5))));
    EXPECT_FALSE(sameBits(a, makeNBody(sources(), request(8, 64, 5, 2))));
    ASSERT_EQ(a.scene.objects.size(), 8u);
    EXPECT_EQ(a.scene.objects[0].name, "body_000");
    EXPECT_EQ(a.scene.objects[7].name, "body_007");
    EXPECT_NO_THROW(validateAnimation(a, "nbody"));
}

// Trap: the frame count changing the motion (it only samples it): the first and last frames are
// times 0 and T for every frame count, and the base scene is frame 0.
TEST(NBody, FramesSampleOneMotion) {
    const Animation three = makeNBody(sources(), request(6, 64, 3)), five = makeNBody(sources(), request(6, 64, 5));
    const Animation one = makeNBody(sources(), request(6, 64, 1));
    for (size_t i = 0; i < 6; ++i) {
        EXPECT_TRUE(sameBits(*three.frames[0].poses[i].transform, *five.frames[0].poses[i].transform));
        EXPECT_TRUE(sameBits(*three.frames[1].poses[i].transform, *five.frames[2].poses[i].transform));
        EXPECT_TRUE(sameBits(*three.frames[2].poses[i].transform, *five.frames[4].poses[i].transform));
        EXPECT_TRUE(sameBits(*one.frames[0].poses[i].transform, *five.frames[0].poses[i].transform));
        EXPECT_TRUE(sameBits(five.scene.objects[i].transform, *five.frames[0].poses[i].transform));
    }
}

// Trap: a body that leaves the box at a wall (a bounce computed on the centre alone, or a radius
// that misses the float rounding of the pose), and a box that bodies never reach (no bounces).
TEST(NBody, BodiesStayInTheBox) {
    const Animation a = makeNBody(sources(), request(12, 100, 40));
    const float h = kNBodyHalfSize;
    float nearest = h;  // the smallest gap between a vertex and a wall, over all frames
    size_t total = 0;
    for (size_t f = 0; f < a.frameCount(); ++f) {
        const Scene s = a.sceneAt(f);
        for (size_t i = 0; i < s.objects.size(); ++i)
            for (const Vec3f& p : s.worldMesh(i).positions) {
                ASSERT_LE(p.cwiseAbs().maxCoeff(), h) << "frame " << f << " body " << i;
                nearest = std::min(nearest, h - p.cwiseAbs().maxCoeff());
            }
        total = s.triangleCount();
    }
    EXPECT_LT(nearest, 0.05f * h);  // bodies do reach the walls (0.024 here)
    EXPECT_NEAR(double(total), 1200.0, 0.1 * 1200.0);
}

// Trap: a box so large (or bodies so small) that frames go by without contacts, which is the
// scene's purpose. 12 bodies of 150 triangles, 8 frames, seed 1: 220 to 520 intersecting triangle
// pairs between bodies per frame (all crossing), 6 to 14 of the 66 pairs of bodies in contact;
// seeds 2 to 5: at least 116 per frame. (The cow bodies' self pairs, 147 here, are the bundled
// cow's own: it intersects itself.)
TEST(NBody, EveryFrameHasIntersections) {
    const Animation a = makeNBody(sources(), request(12, 150, 8));
    for (size_t f = 0; f < a.frameCount(); ++f) {
        const oracle::Truth t = oracle::findIntersections(a.sceneAt(f));
        size_t between = 0;
        for (const oracle::IntersectingPair& p : t.pairs) between += p.selfPair() ? 0 : 1;
        EXPECT_GE(between, 100u) << "frame " << f;
    }
}

// Trap: a request out of range turned into a huge allocation, an empty scene or a division by
// zero instead of an error that names the field (or the mesh) at fault.
TEST(NBody, BadRequestsRefusedByName) {
    auto cause = [](const std::function<void()>& make, const std::string& source) -> std::string {
        try {
            make();
        } catch (const InputError& e) {
            EXPECT_EQ(e.source(), source);
            return e.what();
        }
        return "(accepted)";
    };
    auto make = [](NBodyRequest r) { return [r] { makeNBody(sources(), r, "meshes"); }; };
    NBodyRequest r = request(4, 64, 2);
    r.count = 0;
    EXPECT_NE(cause(make(r), "nbody").find("count 0"), std::string::npos);
    r.count = kMaxNBodyCount + 1;
    EXPECT_NE(cause(make(r), "nbody").find("count"), std::string::npos);
    r = request(4, 64, 2);
    r.triangles = kMaxNBodyTriangles + 1;
    EXPECT_NE(cause(make(r), "nbody").find("triangles"), std::string::npos);
    r.triangles = 4 * kMinNBodyTrianglesPerBody - 1;
    EXPECT_NE(cause(make(r), "nbody").find("triangles"), std::string::npos);
    r = request(4, 64, 0);
    EXPECT_NE(cause(make(r), "nbody").find("frames 0"), std::string::npos);
    r.frames = kMaxNBodyFrames + 1;
    EXPECT_NE(cause(make(r), "nbody").find("frames"), std::string::npos);

    const NBodyRequest fine = request(4, 64, 2);
    Mesh point;
    point.positions = {Vec3f(1, 2, 3), Vec3f(1, 2, 3), Vec3f(1, 2, 3), Vec3f(9, 9, 9)};  // the last unreferenced
    point.triangles = {{0, 1, 2}};
    const std::vector<Mesh> withPoint = {sources()[0], point};
    EXPECT_NE(cause([&] { makeNBody(withPoint, fine, "a.off"); }, "a.off").find("zero extent"), std::string::npos);
    Mesh none;
    none.positions = {Vec3f(0, 0, 0)};
    EXPECT_NE(cause([&] { makeNBody(std::vector<Mesh>{none}, fine, "b.off"); }, "b.off").find("zero triangles"),
              std::string::npos);
    EXPECT_NE(cause([&] { makeNBody({}, fine, "c.off"); }, "c.off").find("no source meshes"), std::string::npos);
}

}  // namespace
}  // namespace cullide

