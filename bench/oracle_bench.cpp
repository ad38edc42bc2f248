// Benchmarks of the exact oracle (oracle/) against CGAL's self_intersections, side by side.
//
//   BM_Oracle/<mesh>/<impl>/<threads>: all self-intersecting pairs of one mesh.
//     mesh 0 = bunny75k (data/meshes/bunny75k.off, 75,408 triangles), 1 = the cow subdivided
//     1-to-4 three times (371,456), 2 = two such cows merged into one mesh (742,912: the second
//     turned 35 degrees about y and shifted so that they interpenetrate). The small meshes, where
//     fixed costs weigh most: 3 = the cow (data/meshes/cow.off, 5,804), 4 = two cows merged
//     (11,608), 5 = the bunny (data/meshes/bunny.off) subdivided once (14,696), 6 = the cow
//     subdivided once (23,216), 7 = two such cows merged (46,432).
//     impl 0 = ours (findIntersections: validation, world positions, degeneracy, the grid build and
//     collide with the exact narrow phase, sort), 1 = CGAL self_intersections<Sequential_tag>
//     on a prebuilt Surface_mesh (its faster form on two cores), 2 = CGAL with Parallel_tag.
//     threads: tbb::global_control for ours and CGAL's Parallel_tag.
//     Counters: pairs found; `same` = 1 when our pair set (degenerate (f, f) included) equals
//     CGAL's, checked once per mesh; on ours, `vs_cgal` = CGAL sequential's time per call on the
//     same mesh over ours (from CGAL's run in this process, which is registered first; timed
//     here, best of 5, when a filter left it out). Reference figures: CGAL about 106 ms
//     (bunny75k), 3.1 s (two cows); target: ours at least 4x faster with identical pairs.
//   BM_OracleInterleaved/<mesh>/<workspace>/<threads>: meshes 3-7, one call of ours then one
//     of CGAL sequential per iteration (40), so that both are timed in the same minutes of a
//     machine whose speed drifts (BM_Oracle's vs_cgal divides two runs taken a second apart, and
//     moves with it). Each call starts with caches the other call left, as a user's single call
//     does. workspace 1 passes one oracle::Workspace to every call of ours, as a caller that runs
//     the oracle per frame does; 0, none: our call's arrays come from its PageArena (huge pages,
//     with the chunks the previous call pooled) or malloc, with whatever memory each kept;
//     2, none and cold: before each call of ours the pool is released and malloc_trim(0) gives
//     malloc's free memory back, so every page is fresh, as in a process's first call.
//     threads: ours on one thread (every workspace), or on two (without one, warm and cold: the
//     default call on this 2-core machine, against CGAL's faster form here, the sequential one).
//     Counters: ours_ms, cgal_ms (the fastest call of each), vs_cgal_best (their ratio),
//     vs_cgal_median (the median of the per-iteration ratios); ours' phases as in BM_Oracle
//     (means).
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/cgal_reference.h"
#include "cullide/oracle/oracle.h"
#include "cullide/unwritten.h"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <vector>

namespace {

using namespace cullide;

// Two copies of `m` as one mesh, the second moved so that they interpenetrate.
Mesh twoCopies(const Mesh& m) {
    Transform t = Transform::Identity();
    t.translate(Vec3f(0.25f, 0.02f, 0.05f));
    t.rotate(Eigen::AngleAxisf(float(35.0 * std::numbers::pi / 180.0), Vec3f::UnitY()));
    Scene two;  // the mesh and a moved copy, as one mesh
    two.objects.push_back({"cow", m, Transform::Identity()});
    two.objects.push_back({"moved", m, t});
    return flatten(two).mesh;
}

Mesh subdivided(Mesh m, int times) {
    for (int k = 0; k < times; ++k) m = subdivide(m);
    return m;
}

const Mesh& benchMesh(int which) {
    static std::map<int, Mesh> cache;
    auto it = cache.find(which);
    if (it != cache.end()) return it->second;
    const std::string dir = std::string(CULLIDE_DATA_DIR) + "/meshes/";
    Mesh m;
    switch (which) {
        case 0: m = loadMesh(dir + "bunny75k.off"); break;
        case 1: m = subdivided(loadMesh(dir + "cow.off"), 3); break;
        case 2: m = twoCopies(subdivided(loadMesh(dir + "cow.off"), 3)); break;
        case 3: m = loadMesh(dir + "cow.off"); break;
        case 4: m = twoCopies(loadMesh(dir + "cow.off")); break;
        case 5: m = subdivided(loadMesh(dir + "bunny.off"), 1); break;
        case 6: m = subdivided(loadMesh(dir + "cow.off"), 1); break;
        default: m = twoCopies(subdivided(loadMesh(dir + "cow.off"), 1)); break;
    }
    return cache.emplace(which, std::move(m)).first->second;
}

Scene sceneOf(const Mesh& m) {
    Scene s;
    s.objects.push_back({"mesh", m, Transform::Identity()});
    return s;
}

// Whether ours equals CGAL's pair set on mesh `which` (computed once).
bool samePairs(int which) {
    static std::map<int, bool> cache;
    auto it = cache.find(which);
    if (it != cache.end()) return it->second;
    const Mesh& m = benchMesh(which);
    const bool same = oracle::selfPairsOf(oracle::findIntersections(sceneOf(m)), 0) ==
        oracle::CgalSelfIntersections(m, "bench mesh").run(false);
    return cache.emplace(which, same).first->second;
}

// CGAL sequential's seconds per call on mesh `which`: from its benchmark run when that ran
// (registered before ours), else the best of 5 calls timed here.
std::map<int, double>& cgalSeconds() {
    static std::map<int, double> seconds;
    return seconds;
}
double cgalSecondsOn(int which) {
    auto it = cgalSeconds().find(which);
    if (it != cgalSeconds().end()) return it->second;
    const oracle::CgalSelfIntersections cgal(benchMesh(which), "bench mesh");
    double best = 1e300;
    for (int k = 0; k < 5; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(cgal.run(false).data());
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return cgalSeconds()[which] = best;
}

void BM_Oracle(benchmark::State& state) {
    const int which = int(state.range(0)), impl = int(state.range(1));
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(state.range(2)));
    const Mesh& mesh = benchMesh(which);
    size_t pairs = 0;
    std::chrono::steady_clock::time_point t0;  // the timed loop's start
    if (impl == 0) {
        const Scene scene = sceneOf(mesh);
        double phase[5] = {0, 0, 0, 0, 0};
        size_t candidates = 0;
        t0 = std::chrono::steady_clock::now();
        for (auto _ : state) {
            const oracle::Truth t = oracle::findIntersections(scene);
            pairs = t.pairs.size() + t.degenerate.size();
            candidates = t.candidatePairs;
            phase[0] += t.setupSeconds, phase[1] += t.buildSeconds, phase[2] += t.collideSeconds;
            phase[3] += t.sortSeconds;
            benchmark::DoNotOptimize(t.pairs.data());
        }
        // Phase times (ms per iteration) and the broad phase's candidate count.
        const double it = double(state.iterations()) / 1000.0;
        state.counters["setup_ms"] = phase[0] / it;
        state.counters["build_ms"] = phase[1] / it;
        state.counters["collide_ms"] = phase[2] / it;
        state.counters["sort_ms"] = phase[3] / it;
        state.counters["candidates"] = double(candidates);
        const double ours =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / double(state.iterations());
        state.counters["vs_cgal"] = cgalSecondsOn(which) / ours;
    } else {
        const oracle::CgalSelfIntersections cgal(mesh, "bench mesh");
        t0 = std::chrono::steady_clock::now();
        for (auto _ : state) {
            const auto p = cgal.run(impl == 2);
            pairs = p.size();
            benchmark::DoNotOptimize(p.data());
        }
        if (impl == 1)
            cgalSeconds()[which] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
                double(state.iterations());
    }
    state.counters["pairs"] = double(pairs);
    state.counters["triangles"] = double(mesh.triangleCount());
    state.counters["same"] = samePairs(which) ? 1 : 0;
}

// CGAL's sequential run of each mesh before ours (ours' vs_cgal reads its time).
BENCHMARK(BM_Oracle)
    ->ArgNames({"mesh", "impl", "threads"})
    ->Args({3, 1, 1})
    ->Args({3, 0, 2})
    ->Args({3, 0, 1})
    ->Args({4, 1, 1})
    ->Args({4, 0, 2})
    ->Args({4, 0, 1})
    ->Args({5, 1, 1})
    ->Args({5, 0, 2})
    ->Args({5, 0, 1})
    ->Args({6, 1, 1})
    ->Args({6, 0, 2})
    ->Args({6, 0, 1})
    ->Args({7, 1, 1})
    ->Args({7, 0, 2})
    ->Args({7, 0, 1})
    ->Args({0, 1, 1})
    ->Args({0, 0, 2})
    ->Args({0, 0, 1})
    ->Args({1, 1, 1})
    ->Args({1, 0, 2})
    ->Args({1, 0, 1})
    ->Args({2, 1, 1})
    ->Args({2, 0, 2})
    ->Args({2, 0, 1})
    ->Args({2, 2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Ours against CGAL sequential, interleaved (see the top of this file).
void BM_OracleInterleaved(benchmark::State& state) {
    const int which = int(state.range(0));
    oracle::Workspace workspace;  // used with workspace:1 (oracle::Workspace)
    oracle::Workspace* const reuse = state.range(1) == 1 ? &workspace : nullptr;
    const bool cold = state.range(1) == 2;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(state.range(2)));
    const Mesh& mesh = benchMesh(which);
    const Scene scene = sceneOf(mesh);
    const oracle::CgalSelfIntersections cgal(mesh, "bench mesh");
    std::vector<double> ours, theirs, ratio;
    double phase[3] = {0, 0, 0};
    for (auto _ : state) {
        if (cold) {
            PageArena::releasePool();
            malloc_trim(0);
        }
        const auto t0 = std::chrono::steady_clock::now();
        const oracle::Truth t = oracle::findIntersections(scene, {}, reuse);
        benchmark::DoNotOptimize(t.pairs.data());
        const auto t1 = std::chrono::steady_clock::now();
        const auto p = cgal.run(false);
        benchmark::DoNotOptimize(p.data());
        const auto t2 = std::chrono::steady_clock::now();
        phase[0] += t.setupSeconds, phase[1] += t.buildSeconds, phase[2] += t.collideSeconds;
        ours.push_back(std::chrono::duration<double>(t1 - t0).count());
        theirs.push_back(std::chrono::duration<double>(t2 - t1).count());
        ratio.push_back(theirs.back() / ours.back());
    }
    std::sort(ratio.begin(), ratio.end());
    const double perCall = 1e3 / double(ours.size());  // ms
    state.counters["setup_ms"] = phase[0] * perCall;
    state.counters["build_ms"] = phase[1] * perCall;
    state.counters["collide_ms"] = phase[2] * perCall;
    state.counters["ours_ms"] = *std::min_element(ours.begin(), ours.end()) * 1e3;
    state.counters["cgal_ms"] = *std::min_element(theirs.begin(), theirs.end()) * 1e3;
    state.counters["vs_cgal_best"] = state.counters["cgal_ms"] / state.counters["ours_ms"];
    state.counters["vs_cgal_median"] = ratio[ratio.size() / 2];
}
BENCHMARK(BM_OracleInterleaved)
    ->ArgNames({"mesh", "workspace", "threads"})
    ->ArgsProduct({{3, 4, 5, 6, 7}, {0, 1, 2}, {1}})
    ->ArgsProduct({{3, 4, 5, 6, 7}, {0, 2}, {2}})
    ->Iterations(40)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
