// Helpers shared by the test files: where the test data is, and scratch folders.
#pragma once

#include "cullide/scene.h"

#include <filesystem>
#include <initializer_list>
#include <string>
#include <utility>

// 1 in the AddressSanitizer and ThreadSanitizer builds, where the heaviest tests run smaller cases.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define CULLIDE_SANITIZED 1
#else
#define CULLIDE_SANITIZED 0
#endif

namespace cullide::test {

// CULLIDE_TEST_DATA_DIR "/" relative, e.g. testData("good/polys.off").
std::string testData(const char* relative);

// A scene of the given (mesh, transform) objects, named o0, o1, ...
Scene sceneOf(std::initializer_list<std::pair<Mesh, Transform>> objects);

// A closed box [lo, hi] of 12 triangles (two per face).
Mesh box(const Vec3f& lo, const Vec3f& hi);

// Rotation about x, then y, then z (radians), then the translation.
Transform rotation(double ax, double ay, double az, const Vec3f& translation = Vec3f::Zero());

// Fans of triangles around one vertex each (one mesh, fans on a grid 3 apart, all from `seed`):
// 5 to 8 rim triangles whose rim vertices lie within a few ulps of the centre's plane z = 0.5
// (half of them exactly on it; now and then a real fold), and two more triangles from each centre
// across its fan (crossing, touching or apart). Subdivided flat faces with rounded midpoints look
// like this: the float filter cannot decide most neighbours. Non-manifold (the extra triangles):
// not for CGAL's Surface_mesh.
Mesh nearlyCoplanarFans(uint32_t seed, int fans);

// A test-name-safe form of a data file's path ("bad/nan.off" -> "bad_nan_off"), for
// parameterized tests' names.
std::string paramName(const std::string& path);

// A file's bytes ("" when it cannot be read), and writing bytes to a file.
std::string readBytes(const std::filesystem::path& path);
void writeBytes(const std::filesystem::path& path, const std::string& bytes);

// Runs a shell command: its exit status (128 + the signal when killed) and stdout and stderr
// together.
struct CommandRun {
    int status = -1;
    std::string output;
};
CommandRun runCommand(const std::string& command);

// A fresh, empty folder under the system temp folder, removed (with its contents) on destruction.
class TempDir {
public:
    TempDir();
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
    std::filesystem::path path_;
};

}  // namespace cullide::test
