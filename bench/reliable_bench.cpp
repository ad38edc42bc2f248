// The reliable method's cost (docs/reliable.md, Section 5) against the modified method, on the
// paper's scenes, on the CPU reference backend (six axis directions, connectivity hierarchy,
// branching 4, D24).
//
//   BM_ReliableCost/<scene>/<tris>/<method>/<res>/<leaf>: one full prune of the frame.
//     scene 0 = deformed bunny, 1 = two cows merged into one object, 2 = 12 cylinders;
//     method 1 = modified, 2 = reliable; res = viewport side; leaf = hierarchy leaf size.
//     Counters (measured once, outside the timed loop, with the exact oracle):
//       pcs            PCS triangles
//       colliding      triangles in some intersecting pair (the exact set; the ideal PCS)
//       pcs_per_exact  pcs / colliding
//       false_prunes   colliding triangles missing from the PCS (0 is the reliable promise)
//       false_pos      PCS triangles in no intersecting pair
//       rendered       triangles rasterized (all passes); queries
//   Where the false positives come from: compare rows that change one factor — resolution
//   (dilated coverage and pixel-wide intervals shrink with the pixel), leaf size (unit
//   granularity: one conflicting triangle keeps its leaf).
#include "cullide/cullide.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/study/measures.h"

#include "bench_util.h"

#include <benchmark/benchmark.h>

#include <map>

namespace {

using namespace cullide;

const oracle::Truth& truth(int which, size_t triangles) {
    static std::map<std::pair<int, size_t>, oracle::Truth> cache;
    auto it = cache.find({which, triangles});
    if (it == cache.end())
        it = cache.emplace(std::make_pair(which, triangles), oracle::findIntersections(paperScene(which, triangles)))
                 .first;
    return it->second;
}

void BM_ReliableCost(benchmark::State& state) {
    const int which = int(state.range(0));
    const size_t tris = size_t(state.range(1));
    const Scene& s = paperScene(which, tris);
    auto backend = raster::makeCpuBackend();
    CullideOptions o;
    o.method = state.range(2) == 1 ? CullMethod::Modified : CullMethod::Reliable;
    o.width = o.height = int(state.range(3));
    o.hierarchy.leafSize = uint32_t(state.range(4));
    CullideResult r;
    for (auto _ : state) r = runCullide(s, *backend, o);
    const study::PcsReport rep = study::measurePcs(s, truth(which, tris), r.pcs, o);
    size_t rendered = 0, queries = 0;
    for (const PassStats& p : r.passes) rendered += p.trianglesRendered, queries += p.queries;
    state.counters["triangles"] = double(s.triangleCount());
    state.counters["pcs"] = double(r.pcs.size());
    state.counters["colliding"] = double(rep.collidingTriangles);
    state.counters["pcs_per_exact"] =
        rep.collidingTriangles ? double(r.pcs.size()) / double(rep.collidingTriangles) : 0.0;
    state.counters["false_prunes"] = double(rep.falsePruneCount());
    state.counters["false_pos"] = double(rep.falsePositives);
    state.counters["rendered"] = double(rendered);
    state.counters["queries"] = double(queries);
}
BENCHMARK(BM_ReliableCost)
    ->ArgNames({"scene", "tris", "method", "res", "leaf"})
    // The paper's scenes at ~5k: modified vs reliable at 500, reliable at 1000 and 2000 and leaf 4.
    ->Args({0, 5000, 1, 500, 16})
    ->Args({0, 5000, 2, 500, 16})
    ->Args({0, 5000, 2, 1000, 16})
    ->Args({0, 5000, 2, 2000, 16})
    ->Args({0, 5000, 2, 500, 4})
    ->Args({1, 5000, 1, 500, 16})
    ->Args({1, 5000, 2, 500, 16})
    ->Args({1, 5000, 2, 1000, 16})
    ->Args({1, 5000, 2, 500, 4})
    ->Args({2, 5000, 1, 500, 16})
    ->Args({2, 5000, 2, 500, 16})
    // A larger one.
    ->Args({0, 50000, 1, 500, 16})
    ->Args({0, 50000, 2, 500, 16})
    ->Args({0, 50000, 2, 1000, 16})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
