// Benchmarks of scene files with a positions file (docs/scene-format.md): what one frame of a
// deforming scene the size of the field's "cloth on a ball" costs to load.
//
//   BM_LoadFrame/<what>: a cloth-like grid of 46,225 vertices (91,592 triangles) deforming over 94
//     frames, written once by writeScene (an OFF base mesh and one positions file); what 0 =
//     loadScene then sceneAt(f), as a command that looks at one frame does, 1 = sceneAt(f) of a
//     scene already loaded (one positions-file read and its checks). f steps through the frames.
//     Counters: MB_on_disk (the scene's files, 10^6 bytes) and frame_MB (one frame's read).
#include "cullide/scene.h"
#include "cullide/scene_io.h"

#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace {

using namespace cullide;
namespace fs = std::filesystem;

constexpr uint32_t kSide = 215;  // vertices per side of the grid
constexpr size_t kFrames = 94;

// The grid, its frames a travelling wave, written once into a folder removed at exit.
const fs::path& clothScene() {
    static const fs::path scene = [] {
        const fs::path dir = fs::temp_directory_path() / ("cullide_bench_scene_" + std::to_string(::getpid()));
        fs::create_directories(dir);
        Animation a;
        Object cloth;
        cloth.name = "cloth";
        for (uint32_t j = 0; j < kSide; ++j)
            for (uint32_t i = 0; i < kSide; ++i) cloth.mesh.positions.push_back(Vec3f(float(i), float(j), 0) / kSide);
        for (uint32_t j = 0; j + 1 < kSide; ++j)
            for (uint32_t i = 0; i + 1 < kSide; ++i) {
                const uint32_t v = j * kSide + i;
                cloth.mesh.triangles.push_back({v, v + 1, v + kSide + 1});
                cloth.mesh.triangles.push_back({v, v + kSide + 1, v + kSide});
            }
        a.frames.resize(kFrames);
        for (size_t f = 0; f < kFrames; ++f) {
            std::vector<Vec3f> p = cloth.mesh.positions;
            for (Vec3f& q : p) q.z() = 0.1f * float(std::sin(8.0 * q.x() + 0.2 * double(f)));
            a.frames[f].poses.resize(1);
            a.frames[f].poses[0].positions = std::move(p);
        }
        a.scene.objects.push_back(std::move(cloth));
        writeScene(a, dir / "cloth.json");
        return dir / "cloth.json";
    }();
    static const struct Remove {
        ~Remove() {
            std::error_code ec;
            fs::remove_all(scene.parent_path(), ec);
        }
    } remove;
    return scene;
}

void BM_LoadFrame(benchmark::State& state) {
    const fs::path& path = clothScene();
    const Animation loaded = loadScene(path);
    size_t f = 0, vertices = 0;
    for (auto _ : state) {
        f = (f + 37) % kFrames;
        const Scene s = state.range(0) == 0 ? loadScene(path).sceneAt(f) : loaded.sceneAt(f);
        vertices = s.vertexCount();
        benchmark::DoNotOptimize(s.objects[0].mesh.positions.data());
    }
    uintmax_t bytes = 0;
    for (const auto& e : fs::directory_iterator(path.parent_path())) bytes += e.file_size();
    state.counters["MB_on_disk"] = double(bytes) / 1e6;
    state.counters["frame_MB"] = double(vertices) * 12 / 1e6;
}
BENCHMARK(BM_LoadFrame)->ArgName("what")->DenseRange(0, 1)->Unit(benchmark::kMillisecond);

}  // namespace
