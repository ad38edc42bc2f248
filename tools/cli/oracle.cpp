// `cullide oracle SCENE`: the exact oracle's intersecting pairs of every frame (or one), counts by
// class and times; `--json FILE` writes them as [objectA, triA, objectB, triB, class] rows,
// sorted, degenerate triangles as [object, tri, object, tri, "degenerate"] (CGAL's (f, f)).
#include "commands.h"
#include "oracle.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/oracle/oracle.h"
#include "cullide/provenance.h"
#include "cullide/scene_io.h"
#include "cullide/study/measures.h"
#include "cullide/pipeline/progress.h"

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <tuple>

namespace cullide::cli {
namespace {

struct OracleCommandOptions {
    std::string scene;
    std::string json;
    long frame = -1;
    int threads = 0;
    bool weld = false;
    std::string broadPhase = "grid";
    ProgressMode progress = ProgressMode::Auto;
};

int runOracle(const OracleCommandOptions& o) {
    preferSmallFootprint();  // its peak memory is a promise (commands.h)
    std::optional<tbb::global_control> limit;
    if (o.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    const Animation animation = loadScene(o.scene);
    const auto [first, last] = selectFrames(animation, o.frame, o.scene);
    oracle::OracleOptions options;
    options.weldByPosition = o.weld;
    options.broadPhase = oracle::parseBroadPhase(o.broadPhase);

    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    // Over several frames the oracle's arrays are kept from one frame to the next (fresh pages
    // cost a page fault each); one frame keeps nothing, so that its peak stays the promised one.
    std::optional<oracle::Workspace> workspace;
    if (last - first > 1) workspace.emplace();
    // Per frame: the oracle has no hook within a frame (and its results must not depend on one).
    Progress bar("oracle", last - first, "frames", o.progress);
    for (size_t f = first; f < last; ++f) {
        if (bar.shown()) {
            std::string detail = "frame ";
            detail += std::to_string(f);
            detail += ": ";
            detail += std::to_string(animation.scene.triangleCount());
            detail += " triangles";
            bar.update(f - first, detail);
        }
        // A still scene is its base scene: no copy of its meshes (18 MB on a 1M-triangle mesh).
        std::optional<Scene> moved;
        if (!animation.frames.empty()) moved = animation.sceneAt(f);
        const oracle::Truth t =
            oracle::findIntersections(moved ? *moved : animation.scene, options, workspace ? &*workspace : nullptr);
        size_t self = 0;
        for (const oracle::IntersectingPair& p : t.pairs) self += p.selfPair();
        bar.update(f - first + 1);
        const Progress::Pause pause(&bar);  // the frame's line on stdout
        std::printf(
            "frame %zu: %zu intersecting pair(s): %zu crossing, %zu touching (%zu within objects, %zu between); "
            "%zu degenerate triangle(s); %zu triangles, %zu candidate pairs; %.1f ms (setup %.1f, build %.1f, "
            "collide+exact %.1f, sort %.1f)\n",
            f, t.pairs.size(), t.count(oracle::PairClass::Crossing), t.count(oracle::PairClass::Touching), self,
            t.pairs.size() - self, t.degenerate.size(), t.trianglesTested, t.candidatePairs, 1e3 * t.totalSeconds,
            1e3 * t.setupSeconds, 1e3 * t.buildSeconds, 1e3 * t.collideSeconds, 1e3 * t.sortSeconds);
        if (o.json.empty()) continue;
        // Rows sorted as tuples; a degenerate (o, t) sorts among the pairs as (o, t, o, t).
        struct Row {
            uint32_t oa, ta, ob, tb;
            const char* cls;
        };
        std::vector<Row> rows;
        for (const oracle::IntersectingPair& p : t.pairs)
            rows.push_back({p.objectA, p.triangleA, p.objectB, p.triangleB, toString(p.cls)});
        for (const oracle::TriangleRef& d : t.degenerate)
            rows.push_back({d.object, d.triangle, d.object, d.triangle, "degenerate"});
        std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
            return std::tie(a.oa, a.ta, a.ob, a.tb) < std::tie(b.oa, b.ta, b.ob, b.tb);
        });
        nlohmann::ordered_json pairs = nlohmann::ordered_json::array();
        for (const Row& r : rows) pairs.push_back({r.oa, r.ta, r.ob, r.tb, r.cls});
        frames.push_back({{"frame", f},
                          {"crossing", t.count(oracle::PairClass::Crossing)},
                          {"touching", t.count(oracle::PairClass::Touching)},
                          {"degenerate", t.degenerate.size()},
                          {"seconds", t.totalSeconds},
                          {"pairs", pairs}});
    }
    bar.finish();
    if (!o.json.empty()) {
        nlohmann::ordered_json objects = nlohmann::ordered_json::array();
        for (const Object& obj : animation.scene.objects) objects.push_back(obj.name);
        const nlohmann::ordered_json j = {{"scene", o.scene},
                                          {"weld_by_position", o.weld},
                                          {"objects", objects},
                                          {"frames", frames},
                                          {"provenance", toJson(provenance(o.threads))}};
        writeFileAtomically(o.json, j.dump(1) + "\n");
    }
    return 0;
}

}  // namespace

PcsCheck checkPcs(const Scene& scene, std::span<const PcsTriangle> pcs, const CullideOptions& options, bool check,
                  const oracle::Truth* exact) {
    PcsCheck out;
    out.json = nlohmann::ordered_json::object();
    if (check) {
        const oracle::Truth truth = oracle::findIntersections(scene);
        const study::PcsReport r = study::measurePcs(scene, truth, pcs, options);
        const size_t X = size_t(oracle::PairClass::Crossing), T = size_t(oracle::PairClass::Touching);
        size_t promised = 0;
        for (const study::MissedPair& m : r.missed)
            promised += promisesToKeep(options.method, m.pair.cls == oracle::PairClass::Crossing, m.pair.selfPair());
        out.guaranteeBroken = promised > 0;
        std::printf(
            "  check: %zu intersecting pair(s) (%zu crossing, %zu touching); false prunes: %zu triangle(s) "
            "(%zu crossing, %zu touching), %zu pair(s) missed (%zu crossing, %zu touching; %zu the method "
            "promises to keep); false positives %zu; efficiency %.4f (%zu of %zu PCS triangles collide)\n",
            truth.pairs.size(), truth.count(oracle::PairClass::Crossing), truth.count(oracle::PairClass::Touching),
            r.falsePruneCount(), r.falsePrunes[X], r.falsePrunes[T], r.missedPairs[X] + r.missedPairs[T],
            r.missedPairs[X], r.missedPairs[T], promised, r.falsePositives, r.efficiency, r.collidingInPcs,
            r.pcsTriangles);
        nlohmann::ordered_json missed = nlohmann::ordered_json::array();
        for (const study::MissedPair& m : r.missed) {
            nlohmann::ordered_json dirs = nlohmann::ordered_json::array();
            for (const study::DirectionMeasure& d : m.directions)
                dirs.push_back(
                    {{"penetration",
                      std::isnan(d.penetration) ? nlohmann::ordered_json() : nlohmann::ordered_json(d.penetration)},
                     {"depth_unit", d.depthUnit},
                     {"pixel_centre", d.pixelCentre}});
            missed.push_back(
                {{"pair", {m.pair.objectA, m.pair.triangleA, m.pair.objectB, m.pair.triangleB, toString(m.pair.cls)}},
                 {"missing", {m.missingA, m.missingB}},
                 {"edge_on", {m.edgeOnA, m.edgeOnB}},
                 {"directions", dirs}});
        }
        out.json["check"] = {{"crossing_pairs", truth.count(oracle::PairClass::Crossing)},
                             {"touching_pairs", truth.count(oracle::PairClass::Touching)},
                             {"false_prunes", {{"crossing", r.falsePrunes[X]}, {"touching", r.falsePrunes[T]}}},
                             {"missed_pairs", {{"crossing", r.missedPairs[X]}, {"touching", r.missedPairs[T]}}},
                             {"promised_missed_pairs", promised},
                             {"false_positives", r.falsePositives},
                             {"efficiency", r.efficiency},
                             {"missed", missed}};
    }
    if (exact) {
        const oracle::Truth& t = *exact;
        std::printf(
            "  exact: %zu intersecting pair(s) among the PCS (%zu crossing, %zu touching), %zu degenerate "
            "triangle(s); %.1f ms\n",
            t.pairs.size(), t.count(oracle::PairClass::Crossing), t.count(oracle::PairClass::Touching),
            t.degenerate.size(), 1e3 * t.totalSeconds);
        nlohmann::ordered_json pairs = nlohmann::ordered_json::array();
        for (const oracle::IntersectingPair& p : t.pairs)
            pairs.push_back({p.objectA, p.triangleA, p.objectB, p.triangleB, toString(p.cls)});
        out.json["exact"] = {{"crossing", t.count(oracle::PairClass::Crossing)},
                             {"touching", t.count(oracle::PairClass::Touching)},
                             {"seconds", t.totalSeconds},
                             {"pairs", pairs}};
    }
    return out;
}

void addOracleCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<OracleCommandOptions>();
    CLI::App* sub = app.add_subcommand("oracle",
                                       "Find the truly intersecting triangle pairs of a scene, exactly "
                                       "(grid or Embree broad phase, exact predicates), by class");
    sub->add_option("scene", o->scene, "Scene file (.json) or mesh")->required();
    sub->add_option("--json", o->json, "Write the pairs as [objectA, triA, objectB, triB, class] rows, sorted");
    addNumber(sub, "--frame", o->frame, "Only this frame (default: every frame)", 0L, std::numeric_limits<long>::max());
    addThreadsOption(sub, o->threads);
    sub->add_flag("--weld", o->weld, "Treat bit-identical vertices of an object as one vertex (soups)");
    sub->add_option("--broad-phase", o->broadPhase, "grid (ours, faster) | embree (Embree 3 rtcCollide); same pairs")
        ->capture_default_str();
    addProgressOption(sub, o->progress);
    sub->callback([o, &action] { action = [o] { return runOracle(*o); }; });
}

}  // namespace cullide::cli
