// The oracle against CGAL's self_intersections (oracle/src/cgal_reference.cpp), pair for pair:
// the bundled meshes, the paper's generated scenes, and the subdivided cow.
#include "cullide/oracle/oracle.h"

#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/cgal_reference.h"

#include "oracle_test_util.h"

#include <gtest/gtest.h>

#include <string>

namespace cullide::oracle {
namespace {

// Pair for pair against CGAL's self_intersections.
// Both broad phases must give it.
void expectSameAsCgal(const Mesh& mesh, const std::string& what, size_t expectedCount = 0) {
    const std::vector<FacePair> cgal = CgalSelfIntersections(mesh, what).run();
    for (BroadPhase b : {BroadPhase::Grid, BroadPhase::Embree}) {
        OracleOptions o;
        o.broadPhase = b;
        EXPECT_EQ(selfPairsOf(findIntersections(sceneOf({mesh}), o), 0), cgal) << what << " (" << toString(b) << ")";
    }
    if (expectedCount) {
        EXPECT_EQ(cgal.size(), expectedCount) << what;
    }
}

// The bundled cow self-intersects: CGAL finds 101 pairs.
TEST(OracleCgal, CowSameAsCgal) {
    expectSameAsCgal(bundled("cow.off"), "cow", 101);
}
TEST(OracleCgal, BunnySameAsCgal) {
    expectSameAsCgal(bundled("bunny.off"), "bunny");
}

// The paper's generated scenes at a few thousand triangles (the deformation makes the crossings).
TEST(OracleCgal, GeneratedScenesSameAsCgal) {
    SceneRequest req;
    req.triangles = 4000;
    const Mesh bunny = makeDeformedBunny(bundled("bunny.off"), req).scene.objects[0].mesh;
    expectSameAsCgal(bunny, "deformed bunny");
    const Mesh cows = makeTwoCows(bundled("cow.off"), req).scene.objects[0].mesh;
    expectSameAsCgal(cows, "two cows");
}

// The cow subdivided once: rounded midpoints make most neighbours nearly (not exactly)
// coplanar, the case the exact integer paths decide.
TEST(OracleCgal, SubdividedCowSameAsCgal) {
    expectSameAsCgal(subdivide(bundled("cow.off")), "subdivided cow");
}

}  // namespace
}  // namespace cullide::oracle
