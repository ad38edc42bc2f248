// Benchmarks of the CPU reference rasterizer (raster/).
//
//   BM_Triangles/<leg px>/<viewport>/<threads>/<direct>: throughput of random right triangles with
//     legs of `leg` pixels (bounding box leg x leg, area leg^2/2; leg 1.5 ~ a 1-pixel triangle),
//     one command list: clear, LESS, draw all. One thread takes the direct path (direct:1,
//     CpuBackendOptions::direct) unless told not to (direct:0, the tiles); two threads take it
//     for the small triangles of leg 1 (blocks set up in parallel), the tiles otherwise.
//     Counters: Mtri/s and Mfrag/s (covered centres); on leg 1, 500 px, 1 thread, x_v010 (rate
//     over the 0.1.0 reference build's recorded one, bench/baseline.json), x_tiles (rate over the tiles on one thread,
//     timed in this run just before) and the goal of 30 M triangles/s.
//   BM_ReducePcs/<mesh>/<triangles per object>/<threads>: one self-variant reducePCS (the seed
//     paper's Figure 3) in one view direction (+z), as ONE command list: forward pass
//     (clear; per object: mask on, LESS, draw; mask off, GREATER, query, draw) and reverse pass
//     (clear; per object in reverse: mask off, GREATER, query, draw; mask on, LESS, draw). The mesh
//     is split into consecutive objects of k triangles (0: the whole mesh as one object).
//     Meshes: 0 = cow subdivided 1-to-4 three times (5804 * 64 = 371,456 triangles), 1 = the
//     75k bunny. View: orthographic, fitted to the mesh bounds along +z, 500 x 500, D24.
//     For scale: llvmpipe takes about 0.5 s for cow/16 on a 2-core machine; target <= 50 ms.
#include "cullide/depth_backend.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/raster/cpu_backend.h"

#include <benchmark/benchmark.h>

#include <chrono>

#include "bench_util.h"

#include <map>
#include <random>

namespace {

using namespace cullide;

struct Soup {
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
};

Soup randomTriangles(size_t count, double leg, int W, uint64_t seed) {
    std::mt19937_64 rng(seed);
    auto uni = [&](double lo, double hi) { return lo + (hi - lo) * double(rng() >> 11) * 0x1p-53; };
    Soup s;
    for (size_t t = 0; t < count; ++t) {
        const double x = uni(0, W - leg), y = uni(0, W - leg), z = uni(0.05, 0.95);
        const uint32_t b = uint32_t(s.positions.size());
        s.positions.emplace_back(float(x), float(y), float(z));
        s.positions.emplace_back(float(x + leg), float(y), float(z + uni(-0.04, 0.04)));
        s.positions.emplace_back(float(x), float(y + leg), float(z + uni(-0.04, 0.04)));
        s.triangles.push_back({b, b + 1, b + 2});
    }
    return s;
}

OrthoView windowView(int W) {
    OrthoView v;
    v.xmin = v.ymin = 0;
    v.xmax = v.ymax = W;
    v.znear = 0;
    v.zfar = 1;
    v.width = v.height = W;
    v.depth = DepthFormat::unorm(24);
    return v;
}

// The last rate of BM_Triangles/leg:1/W:500/threads:1/direct:0 in this run (M triangles/s).
double smallTrianglesTilesMtris = 0;

void BM_Triangles(benchmark::State& state) {
    const double leg = state.range(0) == 1 ? 1.5 : double(state.range(0));
    const int W = int(state.range(1));
    raster::CpuBackendOptions o;
    o.threads = int(state.range(2));
    o.direct = state.range(3) != 0;
    o.viewCacheBytes = 0;  // the same list every iteration: set up and rasterized each time, not replayed
    // Enough triangles for a few million fragments per list.
    const size_t count = leg < 2 ? 400000 : leg < 20 ? 100000 : 1000;
    const Soup s = randomTriangles(count, leg, W, 42);
    auto backend = raster::makeCpuBackend(o);
    backend->setGeometry(s.positions, s.triangles);
    backend->setView(windowView(W));
    CommandList list;
    list.clear();
    list.depthFunc(DepthFunc::Less);
    list.draw(0, uint32_t(count));
    const auto start = std::chrono::steady_clock::now();
    for (auto _ : state) benchmark::DoNotOptimize(backend->execute(list));
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / double(state.iterations());
    // One thread takes the direct path when allowed; several take it for small triangles only
    // (leg 1 here).
    if (backend->lastRanDirect() != (o.direct && (o.threads == 1 || leg < 2)))
        state.SkipWithError("not the path expected");
    state.counters["Mtri/s"] = benchmark::Counter(double(count) / 1e6, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["Mfrag/s"] =
        benchmark::Counter(double(backend->lastStats().fragments) / 1e6, benchmark::Counter::kIsIterationInvariantRate);
    // The "~1 px triangles" row: the 0.1.0 reference build's recorded rate on leg 1, W 500, 1 thread
    // (bench/baseline.json), and the
    // goal (Masked Occlusion Culling does 20 M tris/s per thread at 10x10 px; ours is depth-exact).
    if (state.range(0) == 1 && W == 500 && o.threads == 1) {
        const double rate = double(count) / 1e6 / seconds;
        if (!o.direct) smallTrianglesTilesMtris = rate;
        else if (smallTrianglesTilesMtris > 0) state.counters["x_tiles"] = rate / smallTrianglesTilesMtris;
        const double oldRate = baselineFigure("BM_Triangles/leg:1/W:500/threads:1/direct:1");
        if (oldRate > 0) state.counters["x_v010"] = rate / oldRate;
        state.counters["goal_Mtri/s"] = 30;
    }
}
BENCHMARK(BM_Triangles)
    ->ArgNames({"leg", "W", "threads", "direct"})
    ->ArgsProduct({{1, 10, 100}, {500, 1024}, {1}, {0, 1}})  // the tiles first, for x_tiles
    ->ArgsProduct({{1, 10, 100}, {500, 1024}, {2}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Orthographic view along +z fitted to the mesh's bounds, with a 1% margin on every side (so
// no vertex lands exactly on the far plane and gets clipped by rounding).
OrthoView fittedView(const Mesh& mesh, int W, int H) {
    OrthoView v = OrthoView::looking(Vec3d(0, 0, 1));
    v.width = W;
    v.height = H;
    v.depth = DepthFormat::unorm(24);
    constexpr double inf = std::numeric_limits<double>::infinity();
    Vec3d lo(inf, inf, inf), hi(-inf, -inf, -inf);
    for (const Vec3f& p : mesh.positions) {
        const Vec3d q(v.right.dot(p.cast<double>()), v.up.dot(p.cast<double>()), v.dir.dot(p.cast<double>()));
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    const Vec3d pad = (hi - lo) * 0.01;
    lo -= pad;
    hi += pad;
    const double pixel = std::max((hi.x() - lo.x()) / W, (hi.y() - lo.y()) / H);  // square pixels
    const double cx = 0.5 * (lo.x() + hi.x()), cy = 0.5 * (lo.y() + hi.y());
    v.xmin = cx - 0.5 * pixel * W;
    v.xmax = cx + 0.5 * pixel * W;
    v.ymin = cy - 0.5 * pixel * H;
    v.ymax = cy + 0.5 * pixel * H;
    v.znear = lo.z();
    v.zfar = hi.z();
    return v;
}

void BM_ReducePcs(benchmark::State& state) {
    const Mesh& mesh = benchMesh(int(state.range(0)));
    raster::CpuBackendOptions o;
    o.threads = int(state.range(2));
    o.viewCacheBytes = 0;  // the same list every iteration: set up and rasterized each time, not replayed
    auto backend = raster::makeCpuBackend(o);
    backend->setGeometry(mesh.positions, mesh.triangles);
    backend->setView(fittedView(mesh, 500, 500));
    const CommandList list = reducePcsList(uint32_t(mesh.triangleCount()), uint32_t(state.range(1)));
    std::vector<uint64_t> results;
    for (auto _ : state) {
        results = backend->execute(list);
        benchmark::DoNotOptimize(results.data());
    }
    size_t visible = 0;  // queries with no fragment (objects fully visible in that pass)
    for (uint64_t r : results) visible += r == 0;
    state.counters["triangles"] = double(mesh.triangleCount());
    state.counters["queries"] = double(list.queryCount());
    state.counters["zeroQueries"] = double(visible);
    state.counters["Mfrag"] = double(backend->lastStats().fragments) / 1e6;
}
BENCHMARK(BM_ReducePcs)
    ->ArgNames({"mesh", "perObject", "threads"})
    ->ArgsProduct({{0, 1}, {16, 64, 256, 0}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
