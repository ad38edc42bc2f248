// Where the bundled files are (resources.h).
#include "cullide/resources.h"

#include <cstdlib>
#include <string>
#include <system_error>

#if !defined(CULLIDE_SOURCE_DIR) || !defined(CULLIDE_BINARY_DIR)
#error "CULLIDE_SOURCE_DIR and CULLIDE_BINARY_DIR are set by core/CMakeLists.txt"
#endif

namespace cullide {
namespace {

std::filesystem::path& overrideDir() {
    static std::filesystem::path dir;
    return dir;
}

// Whether `path` is `root` or below it, compared on normalized absolute paths component by component
// (so /build-asan is not below /build).
bool isWithin(const std::filesystem::path& path, const std::filesystem::path& root) {
    const std::filesystem::path p = path.lexically_normal(), r = root.lexically_normal();
    auto pi = p.begin();
    for (auto ri = r.begin(); ri != r.end(); ++ri, ++pi) {
        if (ri->empty()) continue;  // a trailing separator
        if (pi == p.end() || *pi != *ri) return false;
    }
    return true;
}

}  // namespace

std::filesystem::path sourceResourceDir() {
    return CULLIDE_SOURCE_DIR;
}

void setResourceDir(const std::filesystem::path& dir) {
    overrideDir() = dir;
}

std::filesystem::path resourceDir() {
    if (!overrideDir().empty()) return overrideDir();
    if (const char* env = std::getenv("CULLIDE_RESOURCE_DIR"); env && *env) return env;
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (ec) return sourceResourceDir();  // no /proc: nothing better to go by
    const std::filesystem::path installed = (exe.parent_path() / ".." / "share" / "cullide").lexically_normal();
    // An installed layout wins even inside the build tree (an install test's prefix may lie there).
    if (!std::filesystem::exists(installed, ec) && isWithin(exe, CULLIDE_BINARY_DIR)) return sourceResourceDir();
    return installed;
}

std::filesystem::path dataDir() {
    return resourceDir() / "data";
}

std::vector<std::filesystem::path> nbodyMeshPaths() {
    return {dataDir() / "meshes" / "bunny.off", dataDir() / "meshes" / "cow.off"};
}

}  // namespace cullide
