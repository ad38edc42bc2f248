// Helpers shared by the test files: where the test data is, and scratch folders.
#pragma once

#include "cullide/scene.h"

#include <filesystem>
#include <initializer_list>
#include <string>
#include <utility>

namespace cullide::test {

// CULLIDE_TEST_DATA_DIR "/" relative, e.g. testData("good/polys.off").
std::string testData(const char* relative);

// A scene of the given (mesh, transform) objects, named o0, o1, ...
Scene sceneOf(std::initializer_list<std::pair<Mesh, Transform>> objects);

// A closed box [lo, hi] of 12 triangles (two per face).
Mesh box(const Vec3f& lo, const Vec3f& hi);

// Rotation about x, then y, then z (radians), then the translation.
Transform rotation(double ax, double ay, double az, const Vec3f& translation = Vec3f::Zero());

// A test-name-safe form of a data file's path ("bad/nan.off" -> "bad_nan_off"), for
// parameterized tests' names.
std::string paramName(const std::string& path);

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
