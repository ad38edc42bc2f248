// Runs of the methods that report pairs themselves, the exact oracle and the peers (methods.h),
// frame after frame: each peer keeps its structures over a scene's frames and refits them, as it
// would for a user's deforming meshes.
#pragma once

#include "cullide/study/study.h"

#include "cullide/oracle/oracle.h"
#include "cullide/peers/peer.h"

#include <tbb/task_arena.h>

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace cullide::study {

// One timed call: its wall time, its split and its pairs.
struct TimedPairs {
    double seconds = 0;
    double updateSeconds = 0;  // the peer's build or refit; the oracle's setup and grid
    std::vector<TrianglePair> pairs;
};

class PairRuns {
public:
    // A run of the exact method or a peer on `scene` (the frame c.frame of c.scene): `repeats`
    // timed runs (median, min, max), then the median run's pairs judged against `truth` (null:
    // not judged) with the audit's tolerance `tolerance` (world units). A peer that cannot take the
    // scene's geometry (InputError) gives a record with its "error" and empty measures.
    nlohmann::ordered_json run(const RunConfig& c, const Scene& scene, const oracle::Truth* truth, double tolerance,
                               int repeats);

private:
    std::vector<TimedPairs> timedExact(const Scene& scene, tbb::task_arena& arena, int repeats);
    // The peer's runs; its first run of a scene builds it, untimed ("build_ms" in `record`).
    std::vector<TimedPairs> timedPeer(const RunConfig& c, const Scene& scene, double tolerance, int repeats,
                                      tbb::task_arena& arena, nlohmann::ordered_json& record);
    // The peer of (scene, method, threads), made on the scene's first run; a new scene string drops
    // the others' (the sweep is scene-major).
    peers::Peer& peerFor(const RunConfig& c, double tolerance, bool& isNew);

    std::string scene_;
    std::map<std::pair<std::string, int>, std::unique_ptr<peers::Peer>> peers_;
    oracle::Workspace workspace_;  // the exact method's, kept over frames as a caller would
};

}  // namespace cullide::study
