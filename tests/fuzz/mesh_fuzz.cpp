// libFuzzer harness for loadMesh: each input is written to a temporary file under every mesh
// extension (.obj .off .ply .stl) and loaded. The contract under test: a valid mesh or
// InputError, nothing else (no crash, no other exception, no hang, no leak, no sanitizer report).
// Build and run: see docs/fuzzing.md. Seeds: tests/data/good/.
#include "cullide/error.h"
#include "cullide/mesh_io.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace {

const std::filesystem::path& folder() {
    static const std::filesystem::path dir = [] {
        auto d = std::filesystem::temp_directory_path() / ("cullide_mesh_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    for (const char* ext : {".obj", ".off", ".ply", ".stl"}) {
        const auto path = folder() / (std::string("input") + ext);
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) __builtin_trap();
        if (size) std::fwrite(data, 1, size, f);
        std::fclose(f);
        try {
            const cullide::Mesh m = cullide::loadMesh(path);
            cullide::validateMesh(m, path.string());  // must not throw for what loadMesh returned
        } catch (const cullide::InputError&) {}
    }
    return 0;
}
