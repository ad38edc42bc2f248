// The peers (peers/): each adapter on small fixtures with a known answer, against the oracle.
// What each peer reports where it disagrees with the oracle is pinned here and explained in
// docs/peers.md.
#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/oracle.h"
#include "cullide/peers/peer.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <string>
#include <vector>

namespace cullide::peers {
namespace {

using test::box;
using Pairs = std::vector<TrianglePair>;

TrianglePair pair(uint32_t oa, uint32_t ta, uint32_t ob, uint32_t tb) {
    return TrianglePair::make({oa, ta}, {ob, tb});
}

// The oracle's pairs (all, or the crossing ones only), sorted.
Pairs truth(const Scene& scene, bool crossingOnly = false) {
    Pairs out;
    for (const oracle::IntersectingPair& p : oracle::findIntersections(scene).pairs)
        if (!crossingOnly || p.cls == oracle::PairClass::Crossing) out.push_back(TrianglePair::make(p.a(), p.b()));
    return out;
}

Pairs minus(const Pairs& a, const Pairs& b) {
    Pairs out;
    std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
    return out;
}

Pairs pairsOf(const std::string& name, const Scene& scene, const PeerOptions& options = {}) {
    return makePeer(name, options)->collide(scene).pairs;
}

Scene twoObjects(Mesh a, Mesh b, const Transform& tb = Transform::Identity()) {
    return test::sceneOf({{std::move(a), Transform::Identity()}, {std::move(b), tb}});
}

// A unit box and a rotated box whose corner passes through it: 12 crossing pairs, none touching.
Scene crossingBoxes() {
    Transform t = Transform::Identity();
    t.translate(Vec3f(0.9f, 0.8f, 0.7f));
    t.rotate(Eigen::AngleAxisf(0.5f, Vec3f(0.3f, 0.5f, 0.8f).normalized()));
    return twoObjects(box({0, 0, 0}, {1, 1, 1}), box({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}), t);
}

Mesh triangle(Vec3f a, Vec3f b, Vec3f c) {
    return Mesh{{a, b, c}, {{0, 1, 2}}};
}

// Trap: a study that names a peer this build does not have, or lists them in another order than
// the charts: the names, their order and the refusal are fixed.
TEST(Peers, NamesAndUnknownNameRefused) {
    EXPECT_EQ(peerNames(), (std::vector<std::string>{"fcl", "embree", "bullet", "cgal"}));
    for (const std::string& name : peerNames()) {
        EXPECT_TRUE(isPeer(name));
        EXPECT_EQ(makePeer(name)->info().name, name);
        EXPECT_FALSE(makePeer(name)->info().library.empty());
    }
    EXPECT_FALSE(isPeer("ode"));
    try {
        makePeer("ode");
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), "peer: unknown peer 'ode' (fcl, embree, bullet, cgal)");
    }
    EXPECT_THROW(makePeer("bullet", {-1.0}), InputError);
    EXPECT_FALSE(makePeer("fcl")->info().selfPairs);
    EXPECT_FALSE(makePeer("bullet")->info().selfPairs);
    EXPECT_TRUE(makePeer("embree")->info().selfPairs);
    EXPECT_TRUE(makePeer("cgal")->info().selfPairs);
}

// Trap: an adapter that reads the wrong triangle ids back from its library (FCL's contact ids in
// the order of the objects the manager hands over, Embree's geometry ids): the crossing pairs
// between two boxes are the oracle's exactly. Bullet over-reports: GImpact's clip test treats a
// triangle as the face of a solid, so a triangle behind the other's plane within its edges
// counts as penetrating, whatever the distance (six pairs here, 0.15 to 0.46 apart).
TEST(Peers, CrossingBoxesGiveTheOraclesPairs) {
    const Scene scene = crossingBoxes();
    const Pairs crossing = truth(scene, true);
    ASSERT_EQ(crossing.size(), 12u);
    ASSERT_EQ(truth(scene), crossing);
    EXPECT_EQ(pairsOf("fcl", scene), crossing);
    EXPECT_EQ(pairsOf("embree", scene), crossing);
    EXPECT_EQ(pairsOf("cgal", scene), crossing);
    const Pairs bullet = pairsOf("bullet", scene);
    EXPECT_TRUE(minus(crossing, bullet).empty());
    EXPECT_EQ(minus(bullet, crossing),
              (Pairs{pair(0, 6, 1, 8), pair(0, 7, 1, 8), pair(0, 7, 1, 9), pair(0, 10, 1, 0), pair(0, 11, 1, 0),
                     pair(0, 11, 1, 1)}));
}

// Trap: touching pairs, where float tests and exact ones part: two unit cubes with a face in
// common (62 touching pairs). FCL, Bullet and CGAL report them all; Embree's tutorial test misses
// the six coplanar pairs whose edges lie on each other (its 2D test counts a point on a line as
// one side, so edges on one line never cross).
TEST(Peers, TouchingCubes) {
    const Scene scene = twoObjects(box({0, 0, 0}, {1, 1, 1}), box({1, 0, 0}, {2, 1, 1}));
    const Pairs all = truth(scene);
    ASSERT_EQ(all.size(), 62u);
    ASSERT_TRUE(truth(scene, true).empty());
    EXPECT_EQ(pairsOf("fcl", scene), all);
    EXPECT_EQ(pairsOf("bullet", scene), all);
    EXPECT_EQ(pairsOf("cgal", scene), all);
    const Pairs embree = pairsOf("embree", scene);
    EXPECT_TRUE(minus(embree, all).empty());
    EXPECT_EQ(minus(all, embree),
              (Pairs{pair(0, 0, 1, 0), pair(0, 1, 1, 1), pair(0, 2, 1, 3), pair(0, 4, 1, 4), pair(0, 5, 1, 5),
                     pair(0, 7, 1, 6)}));
}

// Trap: coplanar triangles (the case a plane-based test handles apart): two overlapping triangles
// in z = 0 are one touching pair, and every peer reports it.
TEST(Peers, CoplanarOverlap) {
    const Scene scene = twoObjects(triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}),
                                   triangle({0.2f, 0.2f, 0}, {1.2f, 0.2f, 0}, {0.2f, 1.2f, 0}));
    ASSERT_EQ(truth(scene), Pairs{pair(0, 0, 1, 0)});
    for (const std::string& name : peerNames()) EXPECT_EQ(pairsOf(name, scene), Pairs{pair(0, 0, 1, 0)}) << name;
}

// Trap: a tolerance where there should be none. Triangles 1e-9 apart (parallel, or a corner above
// the other) do not intersect and no peer says so: their float boxes do not meet. Bullet with a
// margin counts the pair closer than it.
TEST(Peers, GapOf1e9) {
    const Mesh floor = triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    const Scene parallel = twoObjects(floor, triangle({0.2f, 0.2f, 1e-9f}, {1.2f, 0.2f, 1e-9f}, {0.2f, 1.2f, 1e-9f}));
    const Scene corner = twoObjects(floor, triangle({0.2f, 0.2f, 1e-9f}, {0.3f, 0.2f, 1}, {0.2f, 0.3f, 1}));
    for (const Scene* scene : {&parallel, &corner}) {
        ASSERT_TRUE(truth(*scene).empty());
        for (const std::string& name : peerNames()) EXPECT_TRUE(pairsOf(name, *scene).empty()) << name;
    }
    EXPECT_EQ(pairsOf("bullet", corner, {1e-6}), Pairs{pair(0, 0, 1, 0)});
}

// Trap: pairs within one object. Triangle 1 shares vertex 0 with triangle 0 and passes through
// its opposite edge: a crossing self pair under CGAL's sharing rules. CGAL reports it; Embree's
// test skips every two triangles that share a vertex; FCL and Bullet test no pairs within an
// object (selfPairs false).
TEST(Peers, SharedVertexWithinOneObject) {
    Mesh m{
        {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.4f, 0.4f, -0.5f}, {0.4f, 0.4f, 0.5f}, {-1, -1, 0.3f}, {-1, -0.5f, 0.3f}},
        {{0, 1, 2}, {0, 3, 4}, {0, 5, 6}}};
    const Scene scene = test::sceneOf({{m, Transform::Identity()}});
    ASSERT_EQ(truth(scene, true), Pairs{pair(0, 0, 0, 1)});
    EXPECT_EQ(pairsOf("cgal", scene), Pairs{pair(0, 0, 0, 1)});
    for (const char* name : {"fcl", "embree", "bullet"}) EXPECT_TRUE(pairsOf(name, scene).empty()) << name;
}

// Trap: a stale BVH. After the first frame a peer refits (new model positions), or only moves an
// object (a new rigid transform), or refits world positions (a non-uniform scale, which FCL's and
// Bullet's transforms cannot hold); each frame's pairs must be those a fresh peer finds on it.
TEST(Peers, LaterFramesRefitOrMove) {
    std::vector<Scene> frames(4, crossingBoxes());
    for (Vec3f& p : frames[1].objects[1].mesh.positions) p += Vec3f(0.1f, -0.35f, 0.2f);  // deformed
    frames[2].objects[1].transform.pretranslate(Vec3f(-0.2f, 0.1f, -0.4f));  // moved
    frames[3].objects[1].transform.scale(Vec3f(1.6f, 0.7f, 1.1f));  // stretched
    for (size_t f = 1; f < frames.size(); ++f) ASSERT_NE(truth(frames[f]), truth(frames[f - 1])) << f;
    for (const std::string& name : peerNames()) {
        const std::unique_ptr<Peer> peer = makePeer(name);
        for (size_t f = 0; f < frames.size(); ++f) {
            const PeerFrame frame = peer->collide(frames[f]);
            EXPECT_EQ(frame.built, f == 0) << name << " frame " << f;
            EXPECT_EQ(frame.pairs, pairsOf(name, frames[f])) << name << " frame " << f;
            if (name != "bullet") {
                EXPECT_EQ(frame.pairs, truth(frames[f], true)) << name << " frame " << f;
            }
        }
        const PeerFrame again = peer->collide(test::sceneOf({{box({0, 0, 0}, {1, 1, 1}), Transform::Identity()}}));
        EXPECT_TRUE(again.built) << name << ": other objects build again";
    }
}

// Trap: geometry a library cannot take. CGAL's self_intersections needs a polygon mesh: a third
// triangle on an edge is refused, naming the object; the peer then builds again on a good frame.
// Every peer refuses an index out of range rather than reading past the positions.
TEST(Peers, UnusableGeometryRefused) {
    Mesh fin{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}};
    Scene bad = test::sceneOf({{fin, Transform::Identity()}});
    bad.objects[0].name = "fin";
    const std::unique_ptr<Peer> cgal = makePeer("cgal");
    try {
        cgal->collide(bad);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(e.source(), "scene");
        EXPECT_NE(std::string(e.what()).find("object 'fin': triangle 2 cannot be added to a CGAL Surface_mesh"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_EQ(cgal->collide(crossingBoxes()).pairs, truth(crossingBoxes()));
    Scene outOfRange = crossingBoxes();
    outOfRange.objects[1].mesh.triangles[3][1] = 99;
    for (const std::string& name : peerNames()) EXPECT_THROW(makePeer(name)->collide(outOfRange), InputError) << name;
}

// Trap: pairs that depend on the thread count (per-thread lists merged in the order threads
// finish). Embree and CGAL run on TBB: one thread and two give the same pairs on a bundled mesh
// against a turned copy of itself.
TEST(Peers, ThreadsDoNotChangeThePairs) {
    const Mesh bunny = loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/bunny.off");
    const Scene scene =
        test::sceneOf({{bunny, Transform::Identity()}, {bunny, test::rotation(0.3, 0.2, 0.1, Vec3f(0.3f, 0.1f, 0))}});
    for (const char* name : {"embree", "cgal"}) {
        Pairs one, two;
        tbb::task_arena(1).execute([&] { one = pairsOf(name, scene); });
        tbb::task_arena(2).execute([&] { two = pairsOf(name, scene); });
        EXPECT_FALSE(one.empty()) << name;
        EXPECT_EQ(one, two) << name;
    }
}

}  // namespace
}  // namespace cullide::peers
