// Benchmarks of traces (raster/verify/src/trace_*.cpp): what recording and replaying cost over the plain
// prune they capture. Compare the three in one run (the machines are noisy):
//
//   BM_TraceOverhead/<scene>/<triangles>/<what>/<threads>: one frame of the paper's scenes
//     (bench_util.h: 0 = the deformed bunny, 1 = two cows), modified method, 500 x 500, D24, axes,
//     leaf 16, on the CPU reference; what 0 = the plain prune, 1 = the same prune recorded to a
//     trace file (CPU reference + interval evaluator + writer), 2 = the trace replayed on the CPU
//     reference (reader + backend). Counters: the trace's size (MB) and queries; record/prune and
//     replay/prune are the ratios of the rows' times.
#include "cullide/cullide.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/trace.h"

#include "bench_util.h"

#include <benchmark/benchmark.h>

#include <unistd.h>

#include <filesystem>
#include <string>

namespace {

using namespace cullide;

std::filesystem::path benchTrace(int scene, size_t triangles) {
    return std::filesystem::temp_directory_path() /
        ("cullide_bench_" + std::to_string(::getpid()) + "_" + std::to_string(scene) + "_" + std::to_string(triangles) +
         ".trace");
}

// Records frame 0 of the scene into `path`; returns the file's size.
uint64_t record(const Scene& scene, const std::filesystem::path& path, int threads) {
    raster::CpuBackendOptions bo;
    bo.threads = threads;
    auto cpu = raster::makeCpuBackend(bo);
    const raster::TraceRules rules;
    raster::TraceWriter writer(path, rules, {{"scene", "bench"}}, {{"cullide_version", "bench"}});
    raster::TraceRecorder recorder(*cpu, writer, rules);
    runCullide(scene, recorder, CullideOptions{});
    return recorder.finish();
}

void BM_TraceOverhead(benchmark::State& state) {
    const int which = int(state.range(0));
    const size_t triangles = size_t(state.range(1));
    const int what = int(state.range(2)), threads = int(state.range(3));
    const Scene& scene = paperScene(which, triangles);
    const std::filesystem::path path = benchTrace(which, triangles);
    raster::CpuBackendOptions bo;
    bo.threads = threads;
    auto cpu = raster::makeCpuBackend(bo);
    uint64_t bytes = 0;
    if (what == 0) {
        for (auto _ : state) benchmark::DoNotOptimize(runCullide(scene, *cpu, CullideOptions{}));
    } else if (what == 1) {
        for (auto _ : state) bytes = record(scene, path, threads);
    } else {
        bytes = record(scene, path, threads);
        const raster::TraceReader trace(path);
        for (auto _ : state) benchmark::DoNotOptimize(raster::replayTrace(trace, *cpu));
    }
    if (what != 0) {
        const raster::TraceReader trace(path);
        state.counters["MB"] = double(bytes) / 1e6;
        state.counters["queries"] = trace.header()["summary"]["queries"].get<double>();
        std::error_code ec;
        std::filesystem::remove(path, ec);
    }
}
BENCHMARK(BM_TraceOverhead)
    ->ArgNames({"scene", "tris", "what", "threads"})
    ->ArgsProduct({{0, 1}, {5000, 270000}, {0, 1, 2}, {2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
