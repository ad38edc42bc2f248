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
//     rate (the whole mesh drawn), and on the 270k modified runs on one thread x_v010 (the 0.1.0
//     reference build's recorded CPU time, bench/baseline.json, over this run's).
//   BM_Views/<scene>/<res>/<views>: one prune (modified) with one fitted view per call (views 0,
//     fit) or one per group of overlapping nodes (views 1, clustered;
//     docs/cullide.md#views-per-cluster); scene 0 = data/scenes/two_cows_and_bunny.json, 1 = 64
//     cylinders of about 100k triangles (make-scene cylinders --count 64 --triangles 100000,
//     seed 1); res 0 = 500 x 500, 1 = `--resolution auto`. Counters: PCS triangles, reducePCS
//     calls, the most views of a call, and on clustered runs x_fit, this run's time over the fit
//     run's of the same scene and resolution (run just before it).
//   BM_Tiles/<res>/<limit>: one prune (modified) of data/scenes/two_cows_and_bunny.json on the CPU
//     reference as a backend that draws at most `limit` px per side (raster::ViewportLimit; 0: no
//     limit), so that larger calls are drawn in tiles (docs/cullide.md#adaptive-resolution); res
//     0 = 2000 x 2000, 1 = `--resolution auto`. Counters: PCS, the most tiles of a call, same_pcs
//     (1 when the PCS equals the unlimited run's) and x_whole, this run's time over the unlimited
//     run's of the same resolution (run just before it).
//   BM_PruneToExact/<scene>/<triangles>/<switch>: prune + exact stage, --exact-switch never vs
//     auto (below); x_never is the acceptance ratio.
//   BM_Hierarchy/<kind>/<triangles>: building one object's hierarchy (the per-frame cost the
//     paper's method pays instead of preprocessing); kind 0 = connectivity, 1 = random. Wall
//     time: nodes of 2^16 triangles and more build their subtrees in parallel. Counters:
//     cpu_ms, the CPU time of all threads per build; for connectivity, x_v010: the 0.1.0
//     reference build's (tests/hierarchy_v010.h, one thread, run in this process right after
//     the timed loop, best of its runs) over this run's wall time, and same_v010: 1 when its
//     hierarchy equals today's (nodes and order).
//   BM_ChosenDirections/<case>: chosen directions against the axes (docs/cullide.md#chosen-directions),
//     both timed in every iteration (thread CPU time), the ratio printed as x_axes (the axes' time
//     over the chosen one's: above 1 is faster). case 0 = coherent over the 16 frames of the 50k
//     deformed bunny animation (make-scene bunny --frames 16), 1 = coherent over the 16 frames of
//     100 bowing cylinders (50k), each run keeping a hierarchy cache and a direction history as
//     `prune` does; 2 = pca on the 8 tilted sheets (make-scene sheets, 5k). Counters: ms per frame
//     of each, calls of each, and the PCS sizes (summed over the frames).
#include "cullide/cullide.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/pipeline/pruner.h"
#include "cullide/scene_io.h"

#include "bench_util.h"
#include "hierarchy_v010.h"  // tests/

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <ctime>
#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace {

using namespace cullide;

// All threads' CPU time in ms (the benchmark runs nothing else meanwhile).
double processCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

// This thread's CPU time in ms. On one thread the backend's arena and the hierarchy build run on
// the calling thread, so this is the run's whole work, and a run descheduled on the shared build
// machine does not look slower than it is.
double threadCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

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
    Pruner pruner(PruneSettings{o}, *backend);  // one frame per iteration, as `cullide prune` runs it
    for (auto _ : state) r = pruner.prune(scene).cull;
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
    // (the last iteration's calls).
    state.counters["lv012_ms"] = 1e3 * seconds012;
    state.counters["lv012_Mtri/s"] = seconds012 > 0 ? 1e-6 * double(rendered012) / seconds012 : 0;
    // The 0.1.0 reference build's recorded CPU time per run of the same row (bench/baseline.json:
    // the 270k modified rows on one thread) over this run's.
    const double oldMs = baselineFigure("BM_Prune/scene:" + std::to_string(state.range(0)) +
                                        "/tris:" + std::to_string(state.range(1)) + "/method:" +
                                        std::to_string(state.range(2)) + "/threads:" + std::to_string(bo.threads));
    if (oldMs > 0) state.counters["x_v010"] = oldMs / cpuMs;
}
BENCHMARK(BM_Prune)
    ->ArgNames({"scene", "tris", "method", "threads"})
    ->ArgsProduct({{0, 1}, {5000, 270000}, {0, 1, 2}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

const Scene& viewsScene(int which) {
    static const Scene cows = loadScene(std::string(CULLIDE_DATA_DIR) + "/scenes/two_cows_and_bunny.json").sceneAt(0);
    static const Scene cylinders = makeCylinders(64, {100000, 1, 0}).scene;
    return which == 0 ? cows : cylinders;
}

void BM_Views(benchmark::State& state) {
    const Scene& scene = viewsScene(int(state.range(0)));
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    if (state.range(1) == 1) o.autoCoverage = kDefaultAutoCoverage;
    o.views = state.range(2) == 0 ? ViewMode::Fit : ViewMode::Clustered;
    CullideResult r;
    const auto begin = std::chrono::steady_clock::now();
    Pruner pruner(PruneSettings{o}, *backend);  // one frame per iteration, as `cullide prune` runs it
    for (auto _ : state) r = pruner.prune(scene).cull;
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count() /
        double(state.iterations());
    static std::map<std::pair<int64_t, int64_t>, double> fitMs;  // by (scene, res)
    const std::pair<int64_t, int64_t> key{state.range(0), state.range(1)};
    if (o.views == ViewMode::Fit) fitMs[key] = ms;
    else if (fitMs.count(key)) state.counters["x_fit"] = ms / fitMs[key];
    uint32_t views = 0;
    for (const PassStats& p : r.passes) views = std::max(views, p.views);
    state.counters["pcs"] = double(r.pcs.size());
    state.counters["calls"] = double(r.passes.size());
    state.counters["views_max"] = double(views);
}
BENCHMARK(BM_Views)
    ->ArgNames({"scene", "res", "views"})
    ->ArgsProduct({{0, 1}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Tiles(benchmark::State& state) {
    const Scene& scene = viewsScene(0);
    auto cpu = raster::makeCpuBackend();
    const int limit = int(state.range(1));
    std::unique_ptr<raster::ViewportLimit> limited;
    if (limit > 0) limited = std::make_unique<raster::ViewportLimit>(*cpu, limit);
    DepthBackend& backend = limited ? static_cast<DepthBackend&>(*limited) : *cpu;
    CullideOptions o;
    if (state.range(0) == 1) o.autoCoverage = kDefaultAutoCoverage;
    else o.width = o.height = 2000;
    CullideResult r;
    const auto begin = std::chrono::steady_clock::now();
    Pruner pruner(PruneSettings{o}, backend);
    for (auto _ : state) r = pruner.prune(scene).cull;
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count() /
        double(state.iterations());
    static std::map<int64_t, std::pair<double, std::vector<PcsTriangle>>> whole;  // by res
    if (limit == 0) whole[state.range(0)] = {ms, r.pcs};
    else if (whole.count(state.range(0))) {
        state.counters["x_whole"] = ms / whole[state.range(0)].first;
        state.counters["same_pcs"] = r.pcs == whole[state.range(0)].second ? 1 : 0;
    }
    uint32_t tiles = 0;
    for (const PassStats& p : r.passes) tiles = std::max(tiles, p.tiles / std::max<uint32_t>(1, p.views));
    state.counters["pcs"] = double(r.pcs.size());
    state.counters["tiles_max"] = double(tiles);
}
BENCHMARK(BM_Tiles)
    ->ArgNames({"res", "limit"})
    ->ArgsProduct({{0, 1}, {0, 1024, 512}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Time to exact pairs: prune, then the exact stage (oracle::exactStage) on its PCS, per iteration,
// through the Pruner (cullide/pipeline/pruner.h) as `prune --exact` runs them; switch 0 = never (the
// whole loop), 1 = auto (a fresh Pruner per iteration, so each pays its cost model's calibration).
// Counters: PCS, the level it switched at (-1: never), prune and exact-stage ms of the last
// iteration, and on the auto runs x_never = never's wall time per iteration over auto's (above 1:
// the switch pays), from the never run of the same scene and size just before.
std::map<std::pair<int64_t, int64_t>, double> neverToExactMs;
void BM_PruneToExact(benchmark::State& state) {
    const Scene& scene = paperScene(int(state.range(0)), size_t(state.range(1)));
    auto backend = raster::makeCpuBackend();
    PruneSettings settings;
    settings.exactStage = true;
    if (state.range(2) == 1) settings.cullide.exactSwitch.kind = ExactSwitchKind::Auto;
    CullideResult r;
    double exactSeconds = 0;
    const auto begin = std::chrono::steady_clock::now();
    for (auto _ : state) {
        Pruner pruner(settings, *backend);
        const FramePrune frame = pruner.prune(scene);
        r = frame.cull;
        exactSeconds = frame.exactSeconds();
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

void BM_Hierarchy(benchmark::State& state) {
    const Scene& scene = paperScene(0, size_t(state.range(1)));
    HierarchyOptions o;
    o.kind = state.range(0) == 0 ? HierarchyKind::Connectivity : HierarchyKind::Random;
    const Mesh& mesh = scene.objects[0].mesh;
    const double cpuBegin = processCpuMs();
    const auto wallBegin = std::chrono::steady_clock::now();
    for (auto _ : state) benchmark::DoNotOptimize(buildHierarchy(mesh, o));
    const double wallMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wallBegin).count() /
        double(state.iterations());
    state.counters["cpu_ms"] = (processCpuMs() - cpuBegin) / double(state.iterations());
    state.counters["Mtri/s"] =
        benchmark::Counter(double(mesh.triangleCount()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
    if (o.kind != HierarchyKind::Connectivity) return;
    // The 0.1.0 reference build's hierarchy build on the same mesh, the best of as many runs as fit in about
    // a second (one at 1M triangles), and whether it builds the same hierarchy.
    double peerMs = std::numeric_limits<double>::infinity(), spentMs = 0;
    Hierarchy peer;
    while (spentMs < 1000) {
        const auto t = std::chrono::steady_clock::now();
        peer = v010::buildConnectivityHierarchy(mesh, o);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
        peerMs = std::min(peerMs, ms), spentMs += ms;
    }
    state.counters["x_v010"] = peerMs / wallMs;
    state.counters["same_v010"] = v010::sameHierarchy(buildHierarchy(mesh, o), peer) ? 1 : 0;
}
BENCHMARK(BM_Hierarchy)
    ->ArgNames({"kind", "tris"})
    ->ArgsProduct({{0, 1}, {5000, 270000, 1000000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The chosen-directions workloads: frames of an animation (still scene: one frame).
const Animation& directionsWorkload(int which) {
    static std::map<int, Animation> cache;
    auto it = cache.find(which);
    if (it != cache.end()) return it->second;
    SceneRequest r;
    r.triangles = which == 2 ? 5000 : 50000;
    r.frames = which == 2 ? 0 : 16;
    Animation a;
    if (which == 0) a = makeDeformedBunny(loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/bunny.off"), r);
    else if (which == 1) a = makeCylinders(100, r);
    else a = makeSheets(8, 3.0, r);
    return cache.emplace(which, std::move(a)).first->second;
}

void BM_ChosenDirections(benchmark::State& state) {
    const Animation& a = directionsWorkload(int(state.range(0)));
    std::vector<Scene> frames;
    for (size_t f = 0; f < a.frameCount(); ++f) frames.push_back(a.sceneAt(f));
    raster::CpuBackendOptions bo;
    bo.threads = 1;
    auto backend = raster::makeCpuBackend(bo);
    const DirectionMode chosen = state.range(0) == 2 ? DirectionMode::Pca : DirectionMode::Coherent;
    struct Totals {
        double ms = 0;
        size_t calls = 0, pcs = 0;
    };
    // Every frame of the workload with one mode, as prune runs them (a hierarchy cache over the
    // frames; a direction history for coherent).
    auto runAll = [&](DirectionMode mode, Totals& t) {
        PruneSettings settings;
        settings.cullide.directionMode = mode;
        Pruner pruner(settings, *backend, frames.size());
        const double begin = threadCpuMs();
        for (const Scene& s : frames) {
            const CullideResult r = pruner.prune(s).cull;
            t.calls += r.passes.size(), t.pcs += r.pcs.size();
        }
        t.ms += threadCpuMs() - begin;
    };
    Totals axes, other;
    for (auto _ : state) {
        runAll(DirectionMode::Fixed, axes);
        runAll(chosen, other);
    }
    const double n = double(state.iterations()), perFrame = n * double(frames.size());
    state.counters["axes_ms_per_frame"] = axes.ms / perFrame;
    state.counters["chosen_ms_per_frame"] = other.ms / perFrame;
    state.counters["x_axes"] = other.ms > 0 ? axes.ms / other.ms : 0;
    state.counters["axes_calls"] = double(axes.calls) / n;
    state.counters["chosen_calls"] = double(other.calls) / n;
    state.counters["axes_pcs"] = double(axes.pcs) / n;
    state.counters["chosen_pcs"] = double(other.pcs) / n;
}
BENCHMARK(BM_ChosenDirections)->ArgNames({"case"})->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace
