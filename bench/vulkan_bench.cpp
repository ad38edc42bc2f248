// CPU reference vs Vulkan (lavapipe without a GPU) vs GL (llvmpipe without a GPU), side by side on
// the same command lists in one run (raster/vulkan/, docs/vulkan-backend.md).
//
//   BM_CpuVsVulkan_ReducePcs/<mesh>/<triangles per object>: one self-variant reducePCS (the seed
//     paper's Figure 3, both passes, +z, 500 x 500, D24) as one command list, as BM_CpuVsGl_ReducePcs
//     (gl_bench.cpp): 0 = cow subdivided three times (371,456 triangles), 1 = the 75k bunny; k = 0:
//     the whole mesh as one object. The timed loop runs Vulkan; the CPU reference (all cores, best of
//     3) and GL (mean of 3, when built and available) are timed beside it on the same list.
//     Counters: cpu_ms, vk_ms, gl_ms, vk_over_cpu = vk_ms / cpu_ms (>1: the CPU reference is
//     faster), gl_over_cpu, vk_over_gl, exact_vk / exact_gl = share of queries equal to the CPU's.
//   BM_CpuVsVulkan_Prune/<scene>: runCullide (modified, 6 axis directions, 500 x 500, D24) on the
//     middle frame of a bundled scene (0 = bunny_through_cow, 1 = two_cows_and_bunny); counters as
//     above plus pcs_equal_vk / pcs_equal_gl.
// Skipped with the reason when no Vulkan device can be made; gl_* counters are left out without GL.
#include "cullide/cullide.h"
#include "cullide/depth_backend.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gl_backend.h"
#include "cullide/raster/vulkan_backend.h"
#include "cullide/scene_io.h"

#include <benchmark/benchmark.h>

#include "bench_util.h"

#include <chrono>
#include <limits>

namespace {

using namespace cullide;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// The process's one Vulkan backend, or null after marking the benchmark skipped with the reason.
raster::VulkanBackend* sharedVulkanOrSkip(benchmark::State& state) {
    static std::string reason;
    static std::unique_ptr<raster::VulkanBackend> vk = [] {
        try {
            return raster::makeVulkanBackend();
        } catch (const raster::BackendUnavailable& e) {
            reason = e.what();
            return std::unique_ptr<raster::VulkanBackend>();
        }
    }();
    if (!vk) state.SkipWithError(("no Vulkan device: " + reason).c_str());
    return vk.get();
}

// The process's GL backend when there is one (null otherwise: the gl counters are left out).
raster::GpuBackend* sharedGl() {
    static std::unique_ptr<raster::GpuBackend> gl = []() -> std::unique_ptr<raster::GpuBackend> {
        try {
            return raster::makeGlBackend();
        } catch (const raster::BackendUnavailable&) {
            return nullptr;
        }
    }();
    return gl.get();
}

double exactShare(const std::vector<uint64_t>& a, const std::vector<uint64_t>& b) {
    size_t same = 0;
    for (size_t q = 0; q < a.size() && q < b.size(); ++q) same += a[q] == b[q];
    return double(same) / double(std::max<size_t>(1, a.size()));
}

void report(benchmark::State& state, double cpuMs, double vkMs, double glMs) {
    state.counters["cpu_ms"] = cpuMs;
    state.counters["vk_ms"] = vkMs;
    state.counters["vk_over_cpu"] = vkMs / cpuMs;
    if (glMs > 0) {
        state.counters["gl_ms"] = glMs;
        state.counters["gl_over_cpu"] = glMs / cpuMs;
        state.counters["vk_over_gl"] = vkMs / glMs;
    }
}

void BM_CpuVsVulkan_ReducePcs(benchmark::State& state) {
    raster::VulkanBackend* vk = sharedVulkanOrSkip(state);
    if (!vk) return;
    raster::GpuBackend* gl = sharedGl();
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
    std::vector<DepthBackend*> backends{cpu.get(), vk};
    if (gl) backends.push_back(gl);
    for (DepthBackend* b : backends) {
        b->setGeometry(mesh.positions, mesh.triangles);
        b->setView(view);
        b->execute(list);  // warm-up
    }
    std::vector<uint64_t> cpuResults, vkResults, glResults;
    double cpuMs = std::numeric_limits<double>::infinity(), glSum = 0, vkSum = 0;
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
        vkResults = vk->execute(list);
        vkSum += msSince(t);
        ++n;
    }
    report(state, cpuMs, vkSum / double(n), gl ? glSum / 3 : 0);
    state.counters["queries"] = double(list.queryCount());
    state.counters["exact_vk"] = exactShare(cpuResults, vkResults);
    if (gl) state.counters["exact_gl"] = exactShare(cpuResults, glResults);
}
BENCHMARK(BM_CpuVsVulkan_ReducePcs)
    ->ArgNames({"mesh", "perObject"})
    ->ArgsProduct({{0, 1}, {16, 64, 256, 0}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3)
    ->UseRealTime();

void BM_CpuVsVulkan_Prune(benchmark::State& state) {
    raster::VulkanBackend* vk = sharedVulkanOrSkip(state);
    if (!vk) return;
    raster::GpuBackend* gl = sharedGl();
    const char* names[] = {"bunny_through_cow.json", "two_cows_and_bunny.json"};
    const Animation a = loadScene(std::string(CULLIDE_DATA_DIR) + "/scenes/" + names[state.range(0)]);
    const Scene scene = a.sceneAt(a.frameCount() / 2);
    CullideOptions o;
    auto cpu = raster::makeCpuBackend();
    CullideResult cr = runCullide(scene, *cpu, o), vr = runCullide(scene, *vk, o), gr;  // warm-up
    double cpuMs = std::numeric_limits<double>::infinity(), glSum = 0, vkSum = 0;
    for (int k = 0; k < 2; ++k) {
        auto t = Clock::now();
        cr = runCullide(scene, *cpu, o);
        cpuMs = std::min(cpuMs, msSince(t));
        if (gl) {
            t = Clock::now();
            gr = runCullide(scene, *gl, o);
            glSum += msSince(t);
        }
    }
    size_t n = 0;
    for (auto _ : state) {
        const auto t = Clock::now();
        vr = runCullide(scene, *vk, o);
        vkSum += msSince(t);
        ++n;
    }
    report(state, cpuMs, vkSum / double(n), gl ? glSum / 2 : 0);
    state.counters["triangles"] = double(scene.triangleCount());
    state.counters["pcs"] = double(cr.pcs.size());
    state.counters["pcs_equal_vk"] = cr.pcs == vr.pcs ? 1 : 0;
    if (gl) state.counters["pcs_equal_gl"] = cr.pcs == gr.pcs ? 1 : 0;
}
BENCHMARK(BM_CpuVsVulkan_Prune)
    ->ArgName("scene")
    ->DenseRange(0, 1)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2)
    ->UseRealTime();

}  // namespace
