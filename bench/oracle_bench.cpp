// Benchmarks of the exact oracle (oracle/) against CGAL's self_intersections, side by side.
//
//   BM_Oracle/<mesh>/<impl>/<threads>: all self-intersecting pairs of one mesh.
//     mesh 0 = bunny75k (data/meshes/bunny75k.off, 75,408 triangles), 1 = the cow subdivided
//     1-to-4 three times (371,456), 2 = two such cows merged into one mesh (742,912: the second
//     turned 35 degrees about y and shifted so that they interpenetrate).
//     impl 0 = ours (findIntersections: validation, world positions, degeneracy, Embree build and
//     collide with the exact narrow phase, sort), 1 = CGAL self_intersections<Sequential_tag>
//     on a prebuilt Surface_mesh (its faster form on two cores), 2 = CGAL with Parallel_tag.
//     threads: tbb::global_control for ours and CGAL's Parallel_tag.
//     Counters: pairs found; `same` = 1 when our pair set (degenerate (f, f) included) equals
//     CGAL's, checked once per mesh. Reference figures: CGAL about 106 ms (bunny75k), 3.1 s
//     (two cows); target: ours at least 4x faster with identical pairs.
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/cgal_reference.h"
#include "cullide/oracle/oracle.h"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <memory>
#include <numbers>

namespace {

using namespace cullide;

const Mesh& benchMesh(int which) {
    static std::map<int, Mesh> cache;
    auto it = cache.find(which);
    if (it != cache.end()) return it->second;
    const std::string dir = std::string(CULLIDE_DATA_DIR) + "/meshes/";
    Mesh m;
    if (which == 0) {
        m = loadMesh(dir + "bunny75k.off");
    } else {
        m = subdivide(subdivide(subdivide(loadMesh(dir + "cow.off"))));
        if (which == 2) {
            Transform t = Transform::Identity();
            t.translate(Vec3f(0.25f, 0.02f, 0.05f));
            t.rotate(Eigen::AngleAxisf(float(35.0 * std::numbers::pi / 180.0), Vec3f::UnitY()));
            Scene two;  // the mesh and a moved copy, as one mesh
            two.objects.push_back({"cow", m, Transform::Identity()});
            two.objects.push_back({"moved", m, t});
            m = flatten(two).mesh;
        }
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

void BM_Oracle(benchmark::State& state) {
    const int which = int(state.range(0)), impl = int(state.range(1));
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(state.range(2)));
    const Mesh& mesh = benchMesh(which);
    size_t pairs = 0;
    if (impl == 0) {
        const Scene scene = sceneOf(mesh);
        double phase[5] = {0, 0, 0, 0, 0};
        size_t candidates = 0;
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
    } else {
        const oracle::CgalSelfIntersections cgal(mesh, "bench mesh");
        for (auto _ : state) {
            const auto p = cgal.run(impl == 2);
            pairs = p.size();
            benchmark::DoNotOptimize(p.data());
        }
    }
    state.counters["pairs"] = double(pairs);
    state.counters["triangles"] = double(mesh.triangleCount());
    state.counters["same"] = samePairs(which) ? 1 : 0;
}

BENCHMARK(BM_Oracle)
    ->ArgNames({"mesh", "impl", "threads"})
    ->Args({0, 0, 2})
    ->Args({0, 0, 1})
    ->Args({0, 1, 1})
    ->Args({1, 0, 2})
    ->Args({1, 0, 1})
    ->Args({1, 1, 1})
    ->Args({2, 0, 2})
    ->Args({2, 0, 1})
    ->Args({2, 1, 1})
    ->Args({2, 2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
