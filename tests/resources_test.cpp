// Where executables find the bundled data and scripts (core resources.h).
#include "cullide/resources.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

namespace {

using namespace cullide;

// Trap: a build-tree executable (this test) must read the source tree's data/, where the tests'
// meshes are, not a ../share/cullide that does not exist beside it.
TEST(Resources, BuildTreeUsesTheSourceTree) {
    unsetenv("CULLIDE_RESOURCE_DIR");
    EXPECT_EQ(std::filesystem::weakly_canonical(resourceDir()), std::filesystem::weakly_canonical(CULLIDE_SOURCE_DIR));
    EXPECT_TRUE(std::filesystem::exists(dataDir() / "meshes" / "cow.off"));
    EXPECT_TRUE(std::filesystem::exists(resourceDir() / "tools" / "plot.py"));
}

// Trap: the environment and an explicit setResourceDir (the Python module's) take precedence, in
// that order, and clearing the override goes back to the rules.
TEST(Resources, OverridesInOrder) {
    setenv("CULLIDE_RESOURCE_DIR", "/opt/from-env", 1);
    EXPECT_EQ(resourceDir(), std::filesystem::path("/opt/from-env"));
    EXPECT_EQ(dataDir(), std::filesystem::path("/opt/from-env/data"));
    setResourceDir("/opt/explicit");
    EXPECT_EQ(resourceDir(), std::filesystem::path("/opt/explicit"));
    setResourceDir({});
    unsetenv("CULLIDE_RESOURCE_DIR");
    EXPECT_EQ(resourceDir(), sourceResourceDir());
}

}  // namespace
