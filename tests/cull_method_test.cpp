// The methods' promises (promisesToKeep), the enums' words and the refusal of bad options.
#include "cullide/cullide.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/options.h"
#include "cullide/parallel.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene_io.h"

#include "cullide_test_util.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <map>
#include <memory>
#include <set>

#include <tbb/task_arena.h>

using namespace cullide;
using cullide::test::box;
using cullide::test::contains;
using cullide::test::crossingTriangles;
using cullide::test::icosphere;
using cullide::test::prune;
using cullide::test::rotation;
using cullide::test::sceneOf;
using cullide::test::selfCrossingRibbon;

// Which false prunes break a method's promise (`prune --check` exits 1 on them): reliable keeps every
// intersecting pair, modified the crossing ones, original those between two objects.
TEST(Cullide, PromisesToKeepFollowTheMethods) {
    for (bool crossing : {false, true})
        for (bool sameObject : {false, true}) {
            EXPECT_TRUE(promisesToKeep(CullMethod::Reliable, crossing, sameObject));
            EXPECT_EQ(promisesToKeep(CullMethod::Modified, crossing, sameObject), crossing);
            EXPECT_EQ(promisesToKeep(CullMethod::Original, crossing, sameObject), !sameObject);
        }
}


TEST(Cullide, BadOptionsRefused) {
    EXPECT_THROW(parseCullMethod("reliable-ish"), InputError);
    EXPECT_THROW(parseDirections(""), InputError);
    EXPECT_THROW(parseDirections("0"), InputError);
    EXPECT_THROW(parseDirections("x,q"), InputError);
    EXPECT_THROW(parseDirections("0 0 0"), InputError);
    EXPECT_THROW(parseDirections("1 nan 0"), InputError);
    EXPECT_EQ(parseDirections("x,-y,+z").size(), 3u);
    EXPECT_EQ(parseDirections("1 0 0;0 1 1").size(), 2u);
    EXPECT_EQ(parseDirections("14").size(), 14u);
    EXPECT_EQ(parseDirections("axes").size(), 6u);
    const Scene s = sceneOf({{box(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Transform::Identity()}});
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.width = 0;
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.directions.clear();
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.hierarchy.branching = 1;
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.autoCoverage = -1;  // adaptive K must be positive
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
    o = {};
    o.autoCoverage = 4;
    o.autoBudget = 499 * 500;  // a budget below the base viewport could go coarser than the base
    EXPECT_THROW(runCullide(s, *backend, o), InputError);
}
