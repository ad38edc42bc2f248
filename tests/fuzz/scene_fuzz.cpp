// libFuzzer harness for loadScene: each input is written as scene.json into a temporary folder
// that also holds small valid meshes under the names tests/data/good/scene.json refers to
// (polys.off, polys_moved.off, polys_ascii.ply, cube_binary.stl), so mutated scenes reach the
// transform, frame and positions code, not only the JSON parser. The contract under test: an
// Animation or InputError, nothing else. Build and run: see docs/fuzzing.md.
// Seeds: tests/data/good/scene.json and tests/data/bad/*.json.
#include "cullide/error.h"
#include "cullide/scene_io.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace {

void writeText(const std::filesystem::path& p, const std::string& text) {
    std::FILE* f = std::fopen(p.c_str(), "wb");
    if (!f) __builtin_trap();
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
}

const std::filesystem::path& folder() {
    static const std::filesystem::path dir = [] {
        auto d = std::filesystem::temp_directory_path() / ("cullide_scene_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        const std::string off =
            "OFF\n7 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n3 0.5 0\n3 4 5 1\n4 0 1 2 3\n5 1 4 6 5 2\n";
        writeText(d / "polys.off", off);
        writeText(d / "polys_moved.off", off);
        writeText(d / "polys_ascii.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        writeText(d / "cube_binary.stl",
                  "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 "
                  "0\nendloop\nendfacet\nendsolid t\n");
        return d;
    }();
    return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const auto path = folder() / "scene.json";
    writeText(path, std::string(reinterpret_cast<const char*>(data), size));
    try {
        const cullide::Animation a = cullide::loadScene(path);
        for (size_t f = 0; f < a.frameCount(); ++f) (void)a.sceneAt(f);
    } catch (const cullide::InputError&) {}
    return 0;
}
