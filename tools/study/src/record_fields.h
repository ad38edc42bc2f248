// What every run's record shares, whatever its method's family (study.h's record conventions).
#pragma once

#include "cullide/study/study.h"

#include "cullide/oracle/audit.h"

#include <tbb/task_arena.h>

#include <chrono>
#include <memory>

namespace cullide::study {

using Clock = std::chrono::steady_clock;
inline double secondsSince(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// The arena a run's timed work runs in: `threads` workers, or all cores for 0.
inline std::unique_ptr<tbb::task_arena> runArena(int threads) {
    return threads > 0 ? std::make_unique<tbb::task_arena>(threads) : std::make_unique<tbb::task_arena>();
}

// The record's first fields: index, id, scene, frame, triangles, objects, method.
nlohmann::ordered_json recordHead(const RunConfig& c, const Scene& scene);

// The oracle's columns (its pairs, the PCS's false prunes and missed pairs by class and cause,
// false positives, efficiency, attribution_ms), empty: filled where a run measures them.
void addOracleColumnsEmpty(nlohmann::ordered_json& record);

// The columns every family fills in its own way: family, time_to_pairs_ms, pairs_found,
// pairs_missed, pairs_spurious, tolerance and the audit's causes (null where `audit` is).
// `timeToPairs` < 0: not known (null).
struct PairMeasure {
    MethodFamily family = MethodFamily::ImageSpace;
    double timeToPairsSeconds = -1;
    const oracle::Truth* truth = nullptr;  // null: no oracle, the pair counts are null
    size_t missed = 0;  // without an audit (image-space): the missed pairs
    const oracle::Audit* audit = nullptr;  // the exact method and the peers
    double tolerance = 0;  // world units, with an audit
};
void addPairMeasure(nlohmann::ordered_json& record, const PairMeasure& m);

}  // namespace cullide::study
