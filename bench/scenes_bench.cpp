// Generating the deforming scenes (cloth.h, nbody.h): what `cullide make-scene` and `study`'s
// generated scenes cost before anything is written.
//
//   BM_MakeNBody/<triangles>/<frames>: makeNBody on the bundled bunny and cow (loaded once,
//     outside the timed loop), 100 bodies, seed 1: resampling each source once, the seeded draws
//     and every frame's poses. Counters: bodies, triangles (the scene's, about the request).
//   BM_MakeCloth/<triangles>/<frames>: makeCloth with repulsion, seed 1. The simulation runs its
//     whole duration whatever the frame count, so the time is about proportional to the triangles
//     (the default, 92k triangles and 94 frames, takes about 11x the 10k row); the frames only
//     add their copies. Counters: triangles (as made), frames.
#include "cullide/cloth.h"
#include "cullide/mesh_io.h"
#include "cullide/nbody.h"

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

namespace {

void BM_MakeNBody(benchmark::State& state) {
    static const std::vector<cullide::Mesh> sources = {
        cullide::loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/bunny.off"),
        cullide::loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/cow.off")};
    cullide::NBodyRequest request;
    request.triangles = size_t(state.range(0));
    request.frames = size_t(state.range(1));
    size_t triangles = 0;
    for (auto _ : state) {
        const cullide::Animation a = cullide::makeNBody(sources, request);
        triangles = a.scene.triangleCount();
        benchmark::DoNotOptimize(triangles);
    }
    state.counters["bodies"] = double(request.count);
    state.counters["triangles"] = double(triangles);
}
// The field's N-body size (146k triangles, 76 frames), and a small one where fixed costs weigh.
BENCHMARK(BM_MakeNBody)->Args({146'000, 76})->Args({10'000, 76})->Unit(benchmark::kMillisecond);

void BM_MakeCloth(benchmark::State& state) {
    cullide::ClothRequest request;
    request.triangles = size_t(state.range(0));
    request.frames = size_t(state.range(1));
    size_t triangles = 0;
    for (auto _ : state) {
        const cullide::Animation a = cullide::makeCloth(request);
        triangles = a.scene.objects[0].mesh.triangles.size();
        benchmark::DoNotOptimize(triangles);
    }
    state.counters["triangles"] = double(triangles);
    state.counters["frames"] = double(request.frames);
}
BENCHMARK(BM_MakeCloth)->Args({10'000, 10})->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
