// Runs of the exact method and the peers (pair_run.h).
#include "pair_run.h"

#include "record_fields.h"

#include "cullide/error.h"
#include "cullide/oracle/audit.h"
#include "cullide/parallel.h"
#include "cullide/provenance.h"

#include <algorithm>
#include <vector>

namespace cullide::study {
namespace {

std::vector<TrianglePair> pairsOf(const oracle::Truth& t) {
    std::vector<TrianglePair> out;
    out.reserve(t.pairs.size());
    for (const oracle::IntersectingPair& p : t.pairs) out.push_back({p.a(), p.b()});
    return out;
}

// The columns of the image-space family, empty for a run that has none of them.
void addImageColumnsEmpty(nlohmann::ordered_json& j) {
    for (const char* k : {"resolution", "depth", "directions", "direction_count", "views", "hierarchy", "leaf_size",
                          "branching", "backend"})
        j[k] = nullptr;
}

// The timed runs' median, min and max (sorted by time); empty: none ran, the columns empty.
void addTimes(nlohmann::ordered_json& j, const std::vector<TimedPairs>& timed) {
    for (const char* k : {"calls", "levels", "triangles_rendered", "queries", "pcs"}) j[k] = nullptr;
    if (timed.empty()) {
        for (const char* k : {"time_ms", "time_min_ms", "time_max_ms", "hierarchy_ms"}) j[k] = nullptr;
        return;
    }
    j["time_ms"] = 1e3 * timed[timed.size() / 2].seconds;
    j["time_min_ms"] = 1e3 * timed.front().seconds;
    j["time_max_ms"] = 1e3 * timed.back().seconds;
    j["hierarchy_ms"] = 1e3 * timed[timed.size() / 2].updateSeconds;  // the BVH's build or refit, the grid
}

// The oracle's counts and the missed pairs by class; the image-space causes and PCS measures empty.
void addTruthColumns(nlohmann::ordered_json& j, const oracle::Truth* truth, const oracle::Audit* audit) {
    addOracleColumnsEmpty(j);
    if (!truth) return;
    j["oracle_pairs"] = truth->pairs.size();
    j["oracle_crossing"] = truth->count(oracle::PairClass::Crossing);
    j["oracle_touching"] = truth->count(oracle::PairClass::Touching);
    if (!audit) return;
    j["missed_pairs"] = audit->missed.size();
    j["mp_crossing"] = audit->missedByClass[size_t(oracle::PairClass::Crossing)];
    j["mp_touching"] = audit->missedByClass[size_t(oracle::PairClass::Touching)];
}

}  // namespace

peers::Peer& PairRuns::peerFor(const RunConfig& c, double tolerance, bool& isNew) {
    if (c.scene != scene_) peers_.clear(), scene_ = c.scene;
    std::unique_ptr<peers::Peer>& peer = peers_[{c.method, c.threads}];
    isNew = !peer;
    // Bullet counts pairs within its margin as colliding: the study's tolerance, so that what it
    // reports for its margin is judged within tolerance.
    if (!peer) peer = peers::makePeer(c.method, {.margin = tolerance});
    return *peer;
}

std::vector<TimedPairs> PairRuns::timedExact(const Scene& scene, tbb::task_arena& arena, int repeats) {
    std::vector<TimedPairs> timed;
    for (int k = 0; k < repeats; ++k)
        executeIn(arena, [&] {
            const auto start = Clock::now();
            const oracle::Truth t = oracle::findIntersections(scene, {}, &workspace_);
            timed.push_back({secondsSince(start), t.setupSeconds + t.buildSeconds, pairsOf(t)});
        });
    return timed;
}

std::vector<TimedPairs> PairRuns::timedPeer(const RunConfig& c, const Scene& scene, double tolerance, int repeats,
                                            tbb::task_arena& arena, nlohmann::ordered_json& j) {
    bool isNew = false;
    peers::Peer& peer = peerFor(c, tolerance, isNew);
    j["library"] = peer.info().library;
    j["usage"] = peer.info().usage;
    if (isNew) {  // the build, once per sequence: a user pays it once, then refits every frame
        const auto start = Clock::now();
        executeIn(arena, [&] { (void)peer.collide(scene); });
        j["build_ms"] = 1e3 * secondsSince(start);
    }
    std::vector<TimedPairs> timed;
    for (int k = 0; k < repeats; ++k)
        executeIn(arena, [&] {
            const auto start = Clock::now();
            peers::PeerFrame f = peer.collide(scene);
            timed.push_back({secondsSince(start), f.updateSeconds, std::move(f.pairs)});
        });
    return timed;
}

nlohmann::ordered_json PairRuns::run(const RunConfig& c, const Scene& scene, const oracle::Truth* truth,
                                     double tolerance, int repeats) {
    const MethodFamily family = methodFamily(c.method, "method");
    const std::unique_ptr<tbb::task_arena> arena = runArena(c.threads);
    nlohmann::ordered_json j = recordHead(c, scene);
    addImageColumnsEmpty(j);
    j["threads"] = c.threads;
    j["repeats"] = repeats;
    for (const char* k : {"exact_switch", "switched_at_level", "exact_ms", "time_to_exact_ms"}) j[k] = nullptr;
    j["provenance"] = toJson(provenance(c.threads, {}));

    std::vector<TimedPairs> timed;
    bool selfPairs = true;
    if (family == MethodFamily::Exact) {
        timed = timedExact(scene, *arena, repeats);
    } else {
        try {
            timed = timedPeer(c, scene, tolerance, repeats, *arena, j);
        } catch (const InputError& e) {
            // Geometry this library cannot take (CGAL's self_intersections wants a valid polygon
            // mesh): a row that says so, not the end of the sweep; the next frame builds anew.
            peers_.erase({c.method, c.threads});
            j["error"] = e.what();
            addTimes(j, {});
            addTruthColumns(j, truth, nullptr);
            addPairMeasure(j, {.family = family});
            return j;
        }
        selfPairs = peers_.at({c.method, c.threads})->info().selfPairs;
    }
    std::stable_sort(timed.begin(), timed.end(), [](const auto& a, const auto& b) { return a.seconds < b.seconds; });
    addTimes(j, timed);
    const TimedPairs& median = timed[timed.size() / 2];

    oracle::Audit audit;
    if (truth)
        audit = oracle::audit(scene, *truth, median.pairs,
                              {.tolerance = tolerance, .selfPairsTested = selfPairs, .source = c.method});
    addTruthColumns(j, truth, &audit);
    PairMeasure m{.family = family, .timeToPairsSeconds = median.seconds, .truth = truth, .audit = &audit,
                  .tolerance = tolerance};
    addPairMeasure(j, m);
    j["pairs_reported"] = median.pairs.size();  // not a column: found + spurious, when judged
    return j;
}

}  // namespace cullide::study
