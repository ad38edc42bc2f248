// Benchmarks of the Cullide loop (core/cullide.cpp) on the CPU reference backend.
//
//   BM_Prune/<scene>/<triangles>/<method>/<threads>: one full `cullide prune` of a frame: world
//     meshes, hierarchies (connectivity, leaf 16, branching 4), geometry upload and every
//     reducePCS call (six axis directions, 500 x 500, D24), as the paper measures it (its
//     Figure 8: bunny 5k-270k in 20-600 ms, cows 3k-270k in 35-1000 ms on a 2003 GPU; docs/paper.md#figures-8-12).
//     scene 0 = the deformed bunny (make-scene bunny), 1 = two cows merged into one object
//     (make-scene cows); method 0 = original, 1 = modified, 2 = modified with adaptive
//     resolution (`--resolution auto`, docs/cullide.md#adaptive-resolution). Counters: PCS
//     triangles, reducePCS calls, triangles rendered, queries, levels 0-2's time and triangle
//     rate (the whole mesh drawn), and on the 270k modified runs on one thread x_90b80f8 (commit
//     90b80f8's CPU time over this run's).
//   BM_PruneToExact/<scene>/<triangles>/<switch>: prune + exact stage, --exact-switch never vs
//     auto (below); x_never is the acceptance ratio.
//   BM_Hierarchy/<kind>/<triangles>: building one object's hierarchy (the per-frame cost the
//     paper's method pays instead of preprocessing); kind 0 = connectivity, 1 = random. Counter
//     x_90b80f8 (connectivity): the CPU time of commit 90b80f8's build over this run's (see
//     kConnectivityMs90b80f8).
#include "cullide/cullide.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/study/study.h"

#include "bench_util.h"

#include <benchmark/benchmark.h>

#include <array>
#include <chrono>
#include <ctime>
#include <map>
#include <utility>

namespace {

using namespace cullide;

// This thread's CPU time in ms. On one thread the backend's arena and the hierarchy build run on
// the calling thread, so this is the run's whole work, and a run descheduled on the shared build
// machine does not look slower than it is.
double threadCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

// Commit 90b80f8's BM_Prune CPU time per run (ms, one thread) on the 270k scenes, modified
// method, by (scene, tris, method): that commit's own cullide_bench with
// --benchmark_repetitions=5, the least CPU column, in the same A/B run as this one's figure (the
// closing note of issue 16); x_90b80f8 = that over this run's CPU time per run.
constexpr std::pair<std::array<int64_t, 3>, double> kPruneCpuMs90b80f8[] = {
    {{0, 270000, 1}, 1011},
    {{1, 270000, 1}, 1294},
};

void BM_Prune(benchmark::State& state) {
    const Scene& scene = paperScene(int(state.range(0)), size_t(state.range(1)));
    raster::CpuBackendOptions bo;
    bo.threads = int(state.range(3));
    auto backend = raster::makeCpuBackend(bo);
    CullideOptions o;
    o.method = state.range(2) == 0 ? CullMethod::Original : CullMethod::Modified;
    if (state.range(2) == 2) o.autoCoverage = kDefaultAutoCoverage;
    CullideResult r;
    const double cpuBegin = threadCpuMs();
    for (auto _ : state) r = runCullide(scene, *backend, o);
    const double cpuMs = (threadCpuMs() - cpuBegin) / double(state.iterations());
    size_t rendered = 0, queries = 0, rendered012 = 0;
    double seconds012 = 0;
    for (const PassStats& p : r.passes) {
        rendered += p.trianglesRendered, queries += p.queries;
        if (p.level <= 2) rendered012 += p.trianglesRendered, seconds012 += p.seconds;
    }
    state.counters["triangles"] = double(scene.triangleCount());
    state.counters["pcs"] = double(r.pcs.size());
    state.counters["calls"] = double(r.passes.size());
    state.counters["rendered"] = double(rendered);
    state.counters["queries"] = double(queries);
    state.counters["hier_ms"] = 1e3 * r.hierarchySeconds;
    // Levels 0-2 draw (nearly) the whole mesh and prune almost nothing: the setup-bound part
    // (the last iteration's calls; issue 16's row "levels 0-2").
    state.counters["lv012_ms"] = 1e3 * seconds012;
    state.counters["lv012_Mtri/s"] = seconds012 > 0 ? 1e-6 * double(rendered012) / seconds012 : 0;
    for (const auto& [args, oldMs] : kPruneCpuMs90b80f8)
        if (args == std::array<int64_t, 3>{state.range(0), state.range(1), state.range(2)} && bo.threads == 1)
            state.counters["x_90b80f8"] = oldMs / cpuMs;
}
BENCHMARK(BM_Prune)
    ->ArgNames({"scene", "tris", "method", "threads"})
    ->ArgsProduct({{0, 1}, {5000, 270000}, {0, 1, 2}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Time to exact pairs (issue 17, part 4): prune, then the exact stage (oracle::exactStage) on its
// PCS, per iteration; switch 0 = never (the whole loop), 1 = auto (the study's calibrated cost
// model, study::exactStageCostModel, a fresh one per iteration so each pays its calibration).
// Counters: PCS, the level it switched at (-1: never), prune and exact-stage ms of the last
// iteration, and on the auto runs x_never = never's wall time per iteration over auto's (the
// acceptance: > 1), from the never run of the same scene and size just before.
std::map<std::pair<int64_t, int64_t>, double> neverToExactMs;
void BM_PruneToExact(benchmark::State& state) {
    const Scene& scene = paperScene(int(state.range(0)), size_t(state.range(1)));
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    CullideResult r;
    double exactSeconds = 0;
    const auto begin = std::chrono::steady_clock::now();
    for (auto _ : state) {
        if (state.range(2) == 1) {
            o.exactSwitch.kind = ExactSwitchKind::Auto;
            o.exactSwitch.exactCost = study::exactStageCostModel(scene);
        }
        r = runCullide(scene, *backend, o);
        exactSeconds = oracle::exactStage(scene, r.pcs).totalSeconds;
    }
    const double ms = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count() /
        double(state.iterations());
    state.counters["pcs"] = double(r.pcs.size());
    state.counters["switched_at"] = double(r.switchedAtLevel);
    state.counters["prune_ms"] = 1e3 * r.totalSeconds;
    state.counters["exact_ms"] = 1e3 * exactSeconds;
    const std::pair<int64_t, int64_t> key{state.range(0), state.range(1)};
    if (state.range(2) == 0) neverToExactMs[key] = ms;
    else if (neverToExactMs.count(key)) state.counters["x_never"] = neverToExactMs[key] / ms;
}
BENCHMARK(BM_PruneToExact)
    ->ArgNames({"scene", "tris", "switch"})
    ->ArgsProduct({{0, 1}, {20000, 270000}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The connectivity build's CPU time per hierarchy (ms) at commit 90b80f8, before the build moved
// to flat arrays (vectors per set and per piece, searches over triangle ids), by BM_Hierarchy's
// triangle count. Measured on the project's 2-core shared build machine (AMD EPYC, Release,
// GCC 12): this benchmark's binary linked against that commit's core/src/hierarchy.cpp instead
// of today's, run with --benchmark_filter=BM_Hierarchy/kind:0 --benchmark_repetitions=3, the
// median of the CPU column; the 1M figure in issue 16 (~770 ms) was a wall time. Ratios against
// these mean something only on a comparable machine (the shared machine alone varies by 30%).
// Measured 2026-11-22 at load average ~3.5 on the 2 cores.
constexpr std::pair<int64_t, double> kConnectivityMs90b80f8[] = {{5000, 2.24}, {270000, 180.0}, {1000000, 671.0}};

void BM_Hierarchy(benchmark::State& state) {
    const Scene& scene = paperScene(0, size_t(state.range(1)));
    HierarchyOptions o;
    o.kind = state.range(0) == 0 ? HierarchyKind::Connectivity : HierarchyKind::Random;
    const Mesh& mesh = scene.objects[0].mesh;
    // Thread CPU time, not wall time: the build machine is shared, and a build descheduled for a
    // while would otherwise look slower than it is.
    const double begin = threadCpuMs();
    for (auto _ : state) benchmark::DoNotOptimize(buildHierarchy(mesh, o));
    const double ms = (threadCpuMs() - begin) / double(state.iterations());
    state.counters["Mtri/s"] =
        benchmark::Counter(double(mesh.triangleCount()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
    for (const auto& [triangles, oldMs] : kConnectivityMs90b80f8)
        if (o.kind == HierarchyKind::Connectivity && triangles == state.range(1))
            state.counters["x_90b80f8"] = oldMs / ms;
}
BENCHMARK(BM_Hierarchy)
    ->ArgNames({"kind", "tris"})
    ->ArgsProduct({{0, 1}, {5000, 270000, 1000000}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
