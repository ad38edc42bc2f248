// Where cullide's bundled files are: the resource root holds data/ (meshes/, scenes/) and tools/
// (plot.py, trace/replay_reference.py), laid out as in the source tree.
//
// Conventions (the first that applies):
//   1. setResourceDir(dir) was called (the Python module does, from its own location);
//   2. the environment variable CULLIDE_RESOURCE_DIR is set;
//   3. <executable's folder>/../share/cullide exists (/proc/self/exe): there, where
//      `cmake --install` puts them; an installed command never reads the source tree, even when
//      that still exists;
//   4. the executable lies inside the build tree it was built in: the source tree (a build-tree
//      `cullide` and the tests use the checkout's data);
//   5. otherwise <executable's folder>/../share/cullide all the same (errors then name files there).
#pragma once

#include <filesystem>
#include <vector>

namespace cullide {

std::filesystem::path resourceDir();
// resourceDir() / "data": bunny.off, cow.off, bunny75k.off in meshes/; scenes/.
std::filesystem::path dataDir();
// The source meshes of the N-body scene when none is given (make-scene nbody, the study's
// nbody:N): dataDir() / "meshes" / bunny.off and cow.off.
std::vector<std::filesystem::path> nbodyMeshPaths();
// Overrides the resource root for this process (empty: back to the rules above). Not thread-safe
// against concurrent resourceDir() calls: call it once at start-up.
void setResourceDir(const std::filesystem::path& dir);
// Where the build tree's executables find the resources (rule 3): the source tree's path, fixed
// at build time. Exposed so that a Python module in the build tree can choose it.
std::filesystem::path sourceResourceDir();

}  // namespace cullide
