// CPU reference vs the GPU backends, side by side on the same command lists in one run
// (raster/gl/, raster/vulkan/; docs/gl-backend.md, docs/vulkan-backend.md). The same two
// benchmarks for each GPU backend this build has, named after it (Gl: llvmpipe without a GPU;
// Vulkan: lavapipe without a GPU):
//
//   BM_CpuVsGl_ReducePcs/<mesh>/<triangles per object>, BM_CpuVsVulkan_ReducePcs/...: one
//     self-variant reducePCS (the seed paper's Figure 3, both passes, +z, 500 x 500, D24) as one
//     command list, the mesh split into objects of k triangles (0: the whole mesh). Meshes: 0 = cow
//     subdivided three times (371,456 triangles), 1 = the 75k bunny. The timed loop runs the row's
//     backend; the CPU reference (all cores, best of 3) is timed beside it on the same list, and in
//     the Vulkan rows GL as well (mean of 3, when built and available).
//   BM_CpuVsGl_Prune/<scene>, BM_CpuVsVulkan_Prune/<scene>: runCullide (modified, 6 axis
//     directions, 500 x 500, D24) on the middle frame of a bundled scene: 0 = bunny_through_cow,
//     1 = two_cows_and_bunny; in the GL rows also 2 = the generated 270k bunny (make-scene bunny
//     --triangles 270000, frame 0).
//
// Counters: cpu_ms and the row's backend's ms (gl_ms, vk_ms); its time over the CPU's (GL:
// speedup, Vulkan: vk_over_cpu; >1: the CPU reference is faster); the share of queries equal to
// the CPU's (exact_rate, exact_vk) or whether the PCS is (pcs_equal, pcs_equal_vk); queries,
// triangles, pcs. The Vulkan rows add gl_ms, gl_over_cpu, vk_over_gl, exact_gl and pcs_equal_gl
// when GL is there. Each row keeps the protocol its published figures were measured with (the
// Row table below). A row is skipped with the reason when its backend cannot be made here.
#include "cullide/cullide.h"
#include "cullide/depth_backend.h"
#include "cullide/generators.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene_io.h"

#include <benchmark/benchmark.h>

#include "bench_util.h"

#include <chrono>
#include <limits>
#include <map>

namespace {

using namespace cullide;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// One GPU backend's benchmarks: names, counter names, and protocol.
struct Row {
    const char* name;  // BM_CpuVs<name>_ReducePcs, BM_CpuVs<name>_Prune
    const char* kind;  // the backend's name in backends.h
    const char* unavailable;  // the skip message's start
    const char* ms;  // the row's backend's time counter
    const char* overCpu;  // its time over the CPU's
    const char* exact;  // its share of queries equal to the CPU's (ReducePcs)
    const char* pcsEqual;  // whether its PCS equals the CPU's (Prune)
    bool glBeside;  // GL is timed beside it (when built and available)
    int pruneScenes;  // Prune rows: scenes 0..pruneScenes-1
    int pruneCpuRuns;  // Prune rows: the CPU's best of this many runs (and GL's mean, beside)
    bool pruneWarmup;  // Prune rows: the row's backend runs once before the timed loop
};

const Row kRows[] = {
    {"Gl", "gl", "no GL context: ", "gl_ms", "speedup", "exact_rate", "pcs_equal", false, 3, 3, false},
    {"Vulkan", "vulkan", "no Vulkan device: ", "vk_ms", "vk_over_cpu", "exact_vk", "pcs_equal_vk", true, 2, 2, true},
};

// The process's one backend of a kind, or null (with the reason) when it cannot be made here.
raster::GpuBackend* sharedGpu(const std::string& kind, std::string* why = nullptr) {
    struct Made {
        std::unique_ptr<raster::GpuBackend> backend;
        std::string reason;
    };
    static std::map<std::string, Made> made;
    auto it = made.find(kind);
    if (it == made.end()) {
        Made m;
        try {
            m.backend = raster::makeGpuBackend(kind);
        } catch (const raster::BackendUnavailable& e) {
            m.reason = e.what();
        }
        it = made.emplace(kind, std::move(m)).first;
    }
    if (why) *why = it->second.reason;
    return it->second.backend.get();
}

// The row's backend, or null after marking the benchmark skipped with the reason.
raster::GpuBackend* sharedGpuOrSkip(benchmark::State& state, const Row& row) {
    std::string why;
    raster::GpuBackend* gpu = sharedGpu(row.kind, &why);
    if (!gpu) state.SkipWithError((row.unavailable + why).c_str());
    return gpu;
}

// GL, timed beside the row's backend where the row asks for it and GL can be made; else null.
raster::GpuBackend* besideGl(const Row& row) {
    return row.glBeside ? sharedGpu("gl") : nullptr;
}

double exactShare(const std::vector<uint64_t>& a, const std::vector<uint64_t>& b) {
    size_t same = 0;
    for (size_t q = 0; q < a.size() && q < b.size(); ++q) same += a[q] == b[q];
    return double(same) / double(std::max<size_t>(1, a.size()));
}

// The times: the CPU's, the row's backend's, GL's beside it (0: none).
void report(benchmark::State& state, const Row& row, double cpuMs, double gpuMs, double glMs) {
    state.counters["cpu_ms"] = cpuMs;
    state.counters[row.ms] = gpuMs;
    state.counters[row.overCpu] = gpuMs / cpuMs;
    if (glMs > 0) {
        state.counters["gl_ms"] = glMs;
        state.counters["gl_over_cpu"] = glMs / cpuMs;
        state.counters["vk_over_gl"] = gpuMs / glMs;
    }
}

void reducePcs(benchmark::State& state, const Row& row) {
    raster::GpuBackend* gpu = sharedGpuOrSkip(state, row);
    if (!gpu) return;
    raster::GpuBackend* gl = besideGl(row);
    const Mesh& mesh = benchMesh(int(state.range(0)));
    const uint32_t all = uint32_t(mesh.triangleCount());
    const TriangleRange range{0, all};
    const OrthoView view =
        fitView(mesh.positions, mesh.triangles, std::span(&range, 1), Vec3d(0, 0, 1), 500, 500, DepthFormat::unorm(24));
    const CommandList list = reducePcsList(all, uint32_t(state.range(1)));
    // The same list every time: the CPU sets it up and rasterizes it each time, as the GPUs do,
    // instead of replaying the first run's fragments (CpuBackendOptions::viewCacheBytes).
    raster::CpuBackendOptions bo;
    bo.viewCacheBytes = 0;
    auto cpu = raster::makeCpuBackend(bo);
    std::vector<DepthBackend*> backends{cpu.get(), gpu};
    if (gl) backends.push_back(gl);
    for (DepthBackend* b : backends) {
        b->setGeometry(mesh.positions, mesh.triangles);
        b->setView(view);
        b->execute(list);  // warm-up
    }
    std::vector<uint64_t> cpuResults, gpuResults, glResults;
    double cpuMs = std::numeric_limits<double>::infinity(), glSum = 0, gpuSum = 0;
    for (int k = 0; k < 3; ++k) {
        auto t = Clock::now();
        cpuResults = cpu->execute(list);
        cpuMs = std::min(cpuMs, msSince(t));
        if (gl) {
            t = Clock::now();
            glResults = gl->execute(list);
            glSum += msSince(t);
        }
    }
    size_t n = 0;
    for (auto _ : state) {
        const auto t = Clock::now();
        gpuResults = gpu->execute(list);
        gpuSum += msSince(t);
        ++n;
    }
    report(state, row, cpuMs, gpuSum / double(n), gl ? glSum / 3 : 0);
    state.counters["queries"] = double(list.queryCount());
    state.counters[row.exact] = exactShare(cpuResults, gpuResults);
    if (gl) state.counters["exact_gl"] = exactShare(cpuResults, glResults);
}

// The scene of a Prune row: the middle frame of a bundled scene, or the generated 270k bunny.
Scene pruneScene(int which) {
    if (which == 2) return paperScene(0, 270000);
    const char* names[] = {"bunny_through_cow.json", "two_cows_and_bunny.json"};
    const Animation a = loadScene(std::string(CULLIDE_DATA_DIR) + "/scenes/" + names[which]);
    return a.sceneAt(a.frameCount() / 2);
}

void prune(benchmark::State& state, const Row& row) {
    raster::GpuBackend* gpu = sharedGpuOrSkip(state, row);
    if (!gpu) return;
    raster::GpuBackend* gl = besideGl(row);
    const Scene scene = pruneScene(int(state.range(0)));
    CullideOptions o;
    auto cpu = raster::makeCpuBackend();
    CullideResult cr = runCullide(scene, *cpu, o), gr, glr;  // warm-up
    if (row.pruneWarmup) gr = runCullide(scene, *gpu, o);
    double cpuMs = std::numeric_limits<double>::infinity(), glSum = 0, gpuSum = 0;
    for (int k = 0; k < row.pruneCpuRuns; ++k) {
        auto t = Clock::now();
        cr = runCullide(scene, *cpu, o);
        cpuMs = std::min(cpuMs, msSince(t));
        if (gl) {
            t = Clock::now();
            glr = runCullide(scene, *gl, o);
            glSum += msSince(t);
        }
    }
    size_t n = 0;
    for (auto _ : state) {
        const auto t = Clock::now();
        gr = runCullide(scene, *gpu, o);
        gpuSum += msSince(t);
        ++n;
    }
    report(state, row, cpuMs, gpuSum / double(n), gl ? glSum / row.pruneCpuRuns : 0);
    state.counters["triangles"] = double(scene.triangleCount());
    state.counters["pcs"] = double(cr.pcs.size());
    state.counters[row.pcsEqual] = cr.pcs == gr.pcs ? 1 : 0;
    if (gl) state.counters["pcs_equal_gl"] = cr.pcs == glr.pcs ? 1 : 0;
}

bool built(const Row& row) {
    return std::string(row.kind) == "gl" ? raster::glBuilt() : raster::vulkanBuilt();
}

// Both benchmarks of every GPU backend this build has.
const bool registered = [] {
    for (const Row& row : kRows) {
        if (!built(row)) continue;
        const std::string prefix = std::string("BM_CpuVs") + row.name;
        benchmark::RegisterBenchmark((prefix + "_ReducePcs").c_str(),
                                     [&row](benchmark::State& state) { reducePcs(state, row); })
            ->ArgNames({"mesh", "perObject"})
            ->ArgsProduct({{0, 1}, {16, 64, 256, 0}})
            ->Unit(benchmark::kMillisecond)
            ->Iterations(3)
            ->UseRealTime();
        benchmark::RegisterBenchmark((prefix + "_Prune").c_str(),
                                     [&row](benchmark::State& state) { prune(state, row); })
            ->ArgName("scene")
            ->DenseRange(0, row.pruneScenes - 1)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(2)
            ->UseRealTime();
    }
    return true;
}();

}  // namespace
