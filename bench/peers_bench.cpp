// Every method's time to a frame's intersecting pairs, against the exact pipeline's, in the same
// run: cullide's exact oracle alone (the fastest way cullide has to exact pairs on the CPU),
// the modified method with its exact stage, and the peers (peers/peer.h).
//
//   BM_Peers/<scene>/<method>/<threads>: one frame per iteration, the scene's frames in turn.
//     scene 0 = the field's cloth on a ball (make-scene cloth: 92k triangles, seed 1), its frames
//     60, 64, ..., 92 (where it folds onto itself); 1 = the field's N-body (make-scene nbody: 100
//     bodies, 146k triangles, seed 1), frames 0, 8, ..., 72; scenes nothing was tuned on, one
//     frame each: 2 = two cows (make-scene cows, 50k triangles), 3 = the deformed bunny (make-scene
//     bunny, 50k), 4 = N-body with seed 2, 50 bodies and 80k triangles, frames 0, 10, ..., 70.
//     method 0 = exact (oracle::findIntersections with a Workspace kept over frames, as a caller
//     running it per frame does); 1 = modified at 500x500, D24, axes, `--exact-switch auto`, with
//     the exact stage on its PCS (the image-space pipeline's time to exact pairs, a new Pruner per
//     frame); 2 = fcl, 3 = embree, 4 = bullet, 5 = cgal, each built once on the first frame before
//     the timed loop (a deforming-mesh user builds once and refits), then refit + query per frame.
//     threads: tbb::global_control for every method (FCL and Bullet use one thread whatever it says).
//     Each iteration runs the exact pipeline, then the method, on the same frame (A/B alternated,
//     so that both are timed in the same seconds of a machine whose speed drifts).
//     Counters: exact_ms and method_ms (medians over the iterations); vs_exact, the median of the
//     per-iteration ratios method / exact (> 1: the exact pipeline is faster); oracle_pairs, missed
//     and spurious (the method's pairs on every frame of the scene, judged once by the audit,
//     tolerance 1e-5 of the diagonal); qualifies = 1 when the method misses at most 1 % of the
//     oracle's pairs (docs/peers.md: the goal is exact at least 3x faster than every peer that
//     qualifies, on scenes 0 and 1 at two threads).
//   BM_EmbreeTutorial/<scene>/<threads>: the embree peer against Embree's own `collide` tutorial as
//     written (below), on the same frames: is the peer used as Embree's demo uses it?
#include "cullide/cloth.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/nbody.h"
#include "cullide/oracle/audit.h"
#include "cullide/oracle/oracle.h"
#include "cullide/peers/peer.h"
#include "cullide/pipeline/pruner.h"
#include "cullide/raster/backends.h"
#include "cullide/resources.h"
#include "cullide/study/measures.h"
#include "cullide/study/methods.h"

#include "bench_util.h"

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace {

using namespace cullide;

// The frames of an animation, from `first` to its last in steps of `step` (at most `count`).
std::vector<Scene> framesOf(const Animation& a, size_t first, size_t step, size_t count) {
    std::vector<Scene> out;
    for (size_t f = first; f < a.frameCount() && out.size() < count; f += step) out.push_back(a.sceneAt(f));
    return out;
}

std::vector<Mesh> nbodySources() {
    std::vector<Mesh> meshes;
    for (const auto& path : nbodyMeshPaths()) meshes.push_back(loadMesh(path));
    return meshes;
}

// The benchmark's scenes (see the top of this file), made once.
const std::vector<Scene>& sceneFrames(int which) {
    static std::map<int, std::vector<Scene>> cache;
    auto it = cache.find(which);
    if (it != cache.end()) return it->second;
    std::vector<Scene> frames;
    switch (which) {
        case 0: frames = framesOf(makeCloth({.triangles = 92'000, .frames = 94, .seed = 1}), 60, 4, 9); break;
        case 1: frames = framesOf(makeNBody(nbodySources(), {.count = 100, .triangles = 146'000, .frames = 76, .seed = 1}), 0, 8, 10); break;
        case 2: frames = {paperScene(1, 50'000)}; break;
        case 3: frames = {paperScene(0, 50'000)}; break;
        default: frames = framesOf(makeNBody(nbodySources(), {.count = 50, .triangles = 80'000, .frames = 76, .seed = 2}), 0, 10, 8); break;
    }
    return cache.emplace(which, std::move(frames)).first->second;
}

const char* const kMethods[] = {"exact", "modified", "fcl", "embree", "bullet", "cgal"};

// One frame's pairs by method `m` (1..5), timed; `peer` is the method's when it is a peer.
double timeMethod(int m, const Scene& scene, peers::Peer* peer, DepthBackend* backend, std::vector<TrianglePair>* pairs) {
    const auto t0 = std::chrono::steady_clock::now();
    if (m == 1) {
        PruneSettings settings;
        settings.cullide.method = CullMethod::Modified;
        settings.cullide.exactSwitch.kind = ExactSwitchKind::Auto;
        settings.exactStage = true;
        Pruner pruner(settings, *backend);
        const FramePrune f = pruner.prune(scene);
        if (pairs)
            for (const oracle::IntersectingPair& p : f.exact->pairs) pairs->push_back({p.a(), p.b()});
    } else {
        peers::PeerFrame f = peer->collide(scene);
        if (pairs) *pairs = std::move(f.pairs);
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void BM_Peers(benchmark::State& state) {
    const int which = int(state.range(0)), m = int(state.range(1));
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(state.range(2)));
    const std::vector<Scene>& frames = sceneFrames(which);
    std::unique_ptr<peers::Peer> peer;
    std::unique_ptr<DepthBackend> backend;
    // The study's default tolerance, as a study would set it: a fraction of the first frame's diagonal.
    const double tolerance = study::kDefaultTolerance * study::sceneDiagonal(frames[0]);
    if (m >= 2) peer = peers::makePeer(kMethods[m], {.margin = tolerance});
    if (m == 1) backend = raster::makeBackend("cpu", int(state.range(2)));

    // Untimed: the method's pairs on every frame judged by the audit (a peer's first call builds it).
    size_t truthPairs = 0, missed = 0, spurious = 0;
    if (m >= 1)
        for (const Scene& s : frames) {
            const oracle::Truth truth = oracle::findIntersections(s);
            std::vector<TrianglePair> pairs;
            timeMethod(m, s, peer.get(), backend.get(), &pairs);
            const oracle::Audit a = oracle::audit(s, truth, pairs,
                                                  {.tolerance = tolerance,
                                                   .selfPairsTested = !peer || peer->info().selfPairs});
            truthPairs += truth.pairs.size(), missed += a.missed.size(), spurious += a.spurious.size();
        }

    oracle::Workspace workspace;
    std::vector<double> exact, method, ratio;
    size_t frame = 0;
    for (auto _ : state) {
        const Scene& scene = frames[frame++ % frames.size()];
        const auto t0 = std::chrono::steady_clock::now();
        const oracle::Truth t = oracle::findIntersections(scene, {}, &workspace);
        benchmark::DoNotOptimize(t.pairs.data());
        exact.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        if (m == 0) continue;
        method.push_back(timeMethod(m, scene, peer.get(), backend.get(), nullptr));
        ratio.push_back(method.back() / exact.back());
    }
    const auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v.empty() ? 0.0 : v[v.size() / 2];
    };
    state.counters["exact_ms"] = 1e3 * median(exact);
    if (m == 0) return;
    state.counters["method_ms"] = 1e3 * median(method);
    state.counters["vs_exact"] = median(ratio);
    state.counters["oracle_pairs"] = double(truthPairs);
    state.counters["missed"] = double(missed);
    state.counters["spurious"] = double(spurious);
    state.counters["qualifies"] = double(missed) <= 0.01 * double(truthPairs) ? 1 : 0;
}
BENCHMARK(BM_Peers)
    ->ArgNames({"scene", "method", "threads"})
    ->ArgsProduct({{0, 1}, {0, 1, 2, 3, 4, 5}, {2}})
    ->ArgsProduct({{2, 3, 4}, {0, 2, 3, 4, 5}, {2}})
    ->ArgsProduct({{0, 1}, {0, 3, 5}, {1}})
    ->Iterations(10)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Embree's `collide` tutorial as written, for a cross-check of the embree peer's time: one user
// geometry per object (world positions, bounds callback), RTC_SCENE_FLAG_DYNAMIC, build quality
// LOW, and per frame every geometry committed again, the scene committed and rtcCollide(scene,
// scene) into one vector under a mutex, as the tutorial's callback collects its pairs. No
// triangle test: its broad phase alone, which the peer's whole frame (refit, rtcCollide, the
// triangle test) should not exceed by much if the peer is used as the tutorial uses Embree.
class TutorialCollide {
public:
    explicit TutorialCollide(const Scene& scene) : device_(rtcNewDevice(nullptr)), scene_(rtcNewScene(device_)) {
        rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_DYNAMIC);
        rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_LOW);
        meshes_.reserve(scene.objects.size());  // the geometries hold their addresses
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            meshes_.push_back(scene.worldMesh(i));
            RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
            rtcSetGeometryUserPrimitiveCount(g, unsigned(meshes_.back().triangles.size()));
            rtcSetGeometryUserData(g, &meshes_.back());
            rtcSetGeometryBoundsFunction(g, bounds, nullptr);
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(scene_, g, unsigned(i));
            rtcReleaseGeometry(g);
        }
        rtcCommitScene(scene_);
    }
    ~TutorialCollide() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }
    TutorialCollide(const TutorialCollide&) = delete;
    TutorialCollide& operator=(const TutorialCollide&) = delete;

    // One frame of the same geometry: commit again, collide; the box pairs (both orders).
    size_t frame(const Scene& scene) {
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            meshes_[i].positions = scene.worldMesh(i).positions;
            rtcCommitGeometry(rtcGetGeometry(scene_, unsigned(i)));
        }
        rtcCommitScene(scene_);
        hits_.clear();
        rtcCollide(scene_, scene_, collect, this);
        return hits_.size();
    }

private:
    static void bounds(const RTCBoundsFunctionArguments* args) {
        const Mesh& m = *static_cast<const Mesh*>(args->geometryUserPtr);
        const Triangle& t = m.triangles[args->primID];
        const Vec3f lo = m.positions[t[0]].cwiseMin(m.positions[t[1]]).cwiseMin(m.positions[t[2]]);
        const Vec3f hi = m.positions[t[0]].cwiseMax(m.positions[t[1]]).cwiseMax(m.positions[t[2]]);
        *args->bounds_o = {lo.x(), lo.y(), lo.z(), 0, hi.x(), hi.y(), hi.z(), 0};
    }
    static void collect(void* user, RTCCollision* c, unsigned n) {
        auto* self = static_cast<TutorialCollide*>(user);
        const std::lock_guard<std::mutex> lock(self->mutex_);
        self->hits_.insert(self->hits_.end(), c, c + n);
    }

    RTCDevice device_;
    RTCScene scene_;
    std::vector<Mesh> meshes_;  // world meshes, one per geometry (its user data)
    std::mutex mutex_;
    std::vector<RTCCollision> hits_;
};

//   BM_EmbreeTutorial/<scene>/<threads>: the embree peer's frame (refit, rtcCollide, triangle
//     test) and the tutorial's broad phase as written (TutorialCollide) on the same frame,
//     alternated. Counters: peer_ms, tutorial_ms (medians), peer_vs_tutorial (median ratio),
//     tutorial_pairs (box pairs, both orders, of the last frame).
void BM_EmbreeTutorial(benchmark::State& state) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(state.range(1)));
    const std::vector<Scene>& frames = sceneFrames(int(state.range(0)));
    std::unique_ptr<peers::Peer> peer = peers::makePeer("embree");
    (void)peer->collide(frames[0]);  // the build
    TutorialCollide tutorial(frames[0]);
    std::vector<double> ours, theirs, ratio;
    size_t frame = 0, pairs = 0;
    for (auto _ : state) {
        const Scene& scene = frames[frame++ % frames.size()];
        auto t0 = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(peer->collide(scene).pairs.size());
        auto t1 = std::chrono::steady_clock::now();
        pairs = tutorial.frame(scene);
        auto t2 = std::chrono::steady_clock::now();
        ours.push_back(std::chrono::duration<double>(t1 - t0).count());
        theirs.push_back(std::chrono::duration<double>(t2 - t1).count());
        ratio.push_back(ours.back() / theirs.back());
    }
    const auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
    };
    state.counters["peer_ms"] = 1e3 * median(ours);
    state.counters["tutorial_ms"] = 1e3 * median(theirs);
    state.counters["peer_vs_tutorial"] = median(ratio);
    state.counters["tutorial_pairs"] = double(pairs);
}
BENCHMARK(BM_EmbreeTutorial)
    ->ArgNames({"scene", "threads"})
    ->ArgsProduct({{0, 1, 2}, {2}})
    ->Iterations(10)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
