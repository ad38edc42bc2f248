// Runs of the methods that report pairs themselves, the exact oracle and the peers (methods.h),
// frame after frame: each peer keeps its structures over a scene's frames and refits them, as it
// would for a user's deforming meshes.
#pragma once

#include "cullide/study/study.h"

#include "cullide/oracle/oracle.h"
#include "cullide/peers/peer.h"

#include <map>
#include <memory>
#include <string>
#include <utility>

namespace cullide::study {

class PairRuns {
public:
    // A run of the exact method or a peer on `scene` (the frame c.frame of c.scene): `repeats`
    // timed runs (median, min, max), then the median run's pairs judged against `truth` (null:
    // not judged) with the audit's tolerance `tolerance` (world units).
    nlohmann::ordered_json run(const RunConfig& c, const Scene& scene, const oracle::Truth* truth, double tolerance,
                               int repeats);

private:
    // The peer of (scene, method, threads), made on the scene's first run; a new scene string drops
    // the others' (the sweep is scene-major).
    peers::Peer& peerFor(const RunConfig& c, double tolerance, bool& isNew);

    std::string scene_;
    std::map<std::pair<std::string, int>, std::unique_ptr<peers::Peer>> peers_;
    oracle::Workspace workspace_;  // the exact method's, kept over frames as a caller would
};

}  // namespace cullide::study
