// One run of an image-space method in a study: timed prunes, the exact stage on the PCS, the PCS
// measured against the oracle and its false prunes attributed to causes (study.h's runOne).
#include "cullide/study/study.h"

#include "cullide/study/causes.h"
#include "cullide/study/measures.h"
#include "cullide/pipeline/pruner.h"

#include "cullide/parallel.h"
#include "cullide/provenance.h"

#include "record_fields.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <memory>

namespace cullide::study {

nlohmann::ordered_json passJson(const PassStats& p, const CullideOptions& options) {
    nlohmann::ordered_json j = {{"level", p.level},
                                {"direction", p.direction},
                                {"nodes_in", p.nodesIn},
                                {"nodes_out", p.nodesOut},
                                {"triangles_in", p.trianglesIn},
                                {"triangles_out", p.trianglesOut},
                                {"triangles_rendered", p.trianglesRendered},
                                {"queries", p.queries},
                                {"width", p.width},
                                {"height", p.height},
                                {"round", p.round},
                                {"seconds", p.seconds}};
    if (options.views != ViewMode::Fit) j["views"] = p.views;
    if (p.tiles != p.views) j["tiles"] = p.tiles;  // drawn in tiles (a backend's limit)
    if (options.directionMode != DirectionMode::Fixed)
        j["direction_vector"] = {p.dirVector.x(), p.dirVector.y(), p.dirVector.z()};
    return j;
}

namespace {

// `repeats` timed prunes of the scene, each a first frame on its own Pruner, so that auto's cost
// model is fresh per run and every timed run pays for its calibration. Sorted by time.
std::vector<std::pair<double, CullideResult>> timedPrunes(const CullideOptions& options, bool recordPrunes,
                                                          const Scene& scene, int repeats, tbb::task_arena& arena,
                                                          DepthBackend& backend) {
    std::vector<std::pair<double, CullideResult>> timed;
    // Which call pruned each triangle, for the attribution of false prunes to explain this very run
    // (a write per pruned triangle: nothing measurable beside the run).
    PruneSettings settings;
    settings.cullide = options;
    settings.cullide.recordPrunes = recordPrunes;
    for (int k = 0; k < repeats; ++k) {
        executeIn(arena, [&] {
            Pruner pruner(settings, backend);
            const auto start = Clock::now();
            CullideResult r = pruner.prune(scene).cull;
            timed.emplace_back(secondsSince(start), std::move(r));
        });
    }
    std::stable_sort(timed.begin(), timed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    return timed;
}

// The exact stage on the median run's PCS (the oracle restricted to its triangles), timed like the
// runs: its median, in seconds.
double medianExactStage(const Scene& scene, const CullideResult& r, int repeats, tbb::task_arena& arena) {
    std::vector<double> exact;
    for (int k = 0; k < repeats; ++k)
        executeIn(arena, [&] { exact.push_back(oracle::exactStage(scene, r.pcs).totalSeconds); });
    std::sort(exact.begin(), exact.end());
    return exact[exact.size() / 2];
}

// The PCS against the oracle, and its false prunes attributed to causes. The median timed run
// itself is explained, from the calls that pruned its triangles (so an auto switch, which depends
// on timings, needs no replay). Returns the missed pairs.
size_t addOracleMeasures(nlohmann::ordered_json& j, const Scene& scene, const oracle::Truth& truth,
                         const CullideOptions& options, const CullideResult& r, tbb::task_arena& arena,
                         DepthBackend& backend) {
    const PcsReport rep = measurePcs(scene, truth, r.pcs, options);
    const auto start = Clock::now();
    Attribution a;
    executeIn(arena, [&] { a = attributeFalsePrunes(scene, truth, backend, options, r); });
    j["attribution_ms"] = 1e3 * secondsSince(start);
    const bool same = a.result.pcs == r.pcs;
    const size_t missed = rep.missedPairs[0] + rep.missedPairs[1];
    size_t attributedPairs = 0, attributedTriangles = 0;
    for (int k = 0; k < kCauseCount; ++k)
        attributedPairs += a.pairs[size_t(k)], attributedTriangles += a.triangles[size_t(k)];
    if (!same || attributedPairs != missed || attributedTriangles != rep.falsePruneCount()) {
        a.pairs = {}, a.triangles = {};
        a.pairs[size_t(Cause::Unexplained)] = missed;
        a.triangles[size_t(Cause::Unexplained)] = rep.falsePruneCount();
    }
    j["oracle_pairs"] = truth.pairs.size();
    j["oracle_crossing"] = truth.count(oracle::PairClass::Crossing);
    j["oracle_touching"] = truth.count(oracle::PairClass::Touching);
    j["colliding"] = rep.collidingTriangles;
    j["false_prunes"] = rep.falsePruneCount();
    j["fp_crossing"] = rep.falsePrunes[0];
    j["fp_touching"] = rep.falsePrunes[1];
    j["missed_pairs"] = missed;
    j["mp_crossing"] = rep.missedPairs[0];
    j["mp_touching"] = rep.missedPairs[1];
    for (int k = 0; k < kCauseCount; ++k) {
        j[std::string("fp_") + toString(Cause(k))] = a.triangles[size_t(k)];
        j[std::string("mp_") + toString(Cause(k))] = a.pairs[size_t(k)];
    }
    j["false_positives"] = rep.falsePositives;
    j["efficiency"] = rep.efficiency;
    return missed;
}

}  // namespace

nlohmann::ordered_json runOne(const RunConfig& c, const Scene& scene, const oracle::Truth* truth, int repeats,
                              DepthBackend& backend) {
    const CullideOptions options = cullideOptions(c);
    const std::unique_ptr<tbb::task_arena> arena = runArena(c.threads);
    const auto timed = timedPrunes(options, truth != nullptr, scene, repeats, *arena, backend);
    const double median = timed[timed.size() / 2].first;
    const CullideResult& r = timed[timed.size() / 2].second;
    size_t rendered = 0, queries = 0;
    for (const PassStats& p : r.passes) rendered += p.trianglesRendered, queries += p.queries;

    nlohmann::ordered_json j = recordHead(c, scene);
    j["resolution"] = c.resolution;
    j["depth"] = options.depth.name();
    j["directions"] = c.directions;
    j["direction_count"] = options.directions.size();
    j["views"] = c.views;
    j["hierarchy"] = c.hierarchy;
    j["leaf_size"] = c.leafSize;
    j["branching"] = c.branching;
    j["backend"] = c.backend;
    j["threads"] = c.threads;
    j["repeats"] = repeats;
    j["time_ms"] = 1e3 * median;
    j["time_min_ms"] = 1e3 * timed.front().first;
    j["time_max_ms"] = 1e3 * timed.back().first;
    j["hierarchy_ms"] = 1e3 * r.hierarchySeconds;
    j["calls"] = r.passes.size();
    j["levels"] = r.levels;
    j["triangles_rendered"] = rendered;
    j["queries"] = queries;
    j["pcs"] = r.pcs.size();
    addOracleColumnsEmpty(j);
    j["exact_switch"] = c.exactSwitch;
    j["switched_at_level"] = r.switchedAtLevel >= 0 ? nlohmann::ordered_json(r.switchedAtLevel) : nullptr;
    j["exact_ms"] = nullptr;
    j["time_to_exact_ms"] = nullptr;
    PairMeasure pairs{.family = MethodFamily::ImageSpace, .truth = truth};
    if (truth) {
        const double exact = medianExactStage(scene, r, repeats, *arena);
        j["exact_ms"] = 1e3 * exact;
        j["time_to_exact_ms"] = 1e3 * (median + exact);
        pairs.timeToPairsSeconds = median + exact;
        pairs.missed = addOracleMeasures(j, scene, *truth, options, r, *arena, backend);
    }
    addPairMeasure(j, pairs);
    j["backend_description"] = backend.describe();
    nlohmann::ordered_json passes = nlohmann::ordered_json::array();
    for (const PassStats& p : r.passes) passes.push_back(passJson(p, options));
    j["passes"] = passes;
    // Not a column of the CSV; like the timings, it differs between runs of one configuration.
    std::vector<std::string> drivers;
    if (c.backend != "cpu") drivers.push_back(backend.describe());
    j["provenance"] = toJson(provenance(c.threads, drivers));
    return j;
}

}  // namespace cullide::study
