// `cullide audit SCENE PAIRS`: a pair list from any collision detector judged against the exact
// oracle, frame by frame: found, missed and spurious pairs, each disagreement with its cause
// (cullide/oracle/audit.h); `--json OUT` lists them. Exit 1 when a pair is missed or spurious.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/oracle/audit.h"
#include "cullide/oracle/oracle.h"
#include "cullide/pipeline/pair_list.h"
#include "cullide/provenance.h"
#include "cullide/scene_io.h"
#include "cullide/study/measures.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cullide::cli {
namespace {

struct AuditCommandOptions {
    std::string scene;
    std::string pairs;
    std::string json;
    long frame = -1;
    double tolerance = 1e-5;  // a fraction of the scene's bounding-box diagonal
    bool noSelfPairs = false;
};

// A frame to judge: the scene's frame and the list's entry for it (nullptr: a CSV list without
// rows for it, so no pairs).
struct JudgedFrame {
    size_t frame = 0;
    const pipeline::PairListFrame* entry = nullptr;
};

std::vector<JudgedFrame> framesToJudge(const Animation& animation, const pipeline::PairList& list,
                                       const AuditCommandOptions& o) {
    const bool csv = list.format == pipeline::PairListFormat::Csv;
    if (o.frame >= 0) {
        const size_t k = selectFrames(animation, o.frame, o.scene).first;
        const pipeline::PairListFrame* entry = list.find(k);
        if (!entry && !csv && list.frames.size() == 1) entry = &list.frames[0];
        if (!entry && !csv)
            throw InputError(list.source, "no frame " + std::to_string(k) + " in the list (it has " +
                                              std::to_string(list.frames.size()) + " frames)");
        return {{k, entry}};
    }
    for (const pipeline::PairListFrame& f : list.frames)
        if (f.frame >= animation.frameCount())
            throw InputError(list.source, "frame " + std::to_string(f.frame) + ", but " + o.scene + " has " +
                                              std::to_string(animation.frameCount()) + " frame(s)");
    std::vector<JudgedFrame> out;
    for (size_t f = 0; f < animation.frameCount(); ++f) {
        const pipeline::PairListFrame* entry = list.find(f);
        if (!entry && !csv)
            throw InputError(list.source, "no entry for frame " + std::to_string(f) + " of " + o.scene + " (" +
                                              std::to_string(animation.frameCount()) +
                                              " frame(s)); --frame K judges one frame");
        out.push_back({f, entry});
    }
    return out;
}

// "untested 2, shared_edge 1" for the causes with a count, or "" when none has one.
std::string causeCounts(const std::vector<oracle::AuditCause>& causes, const std::array<size_t, oracle::kAuditCauseCount>& by) {
    std::string text;
    for (oracle::AuditCause c : causes) {
        if (by[size_t(c)] == 0) continue;
        text += (text.empty() ? "" : ", ") + std::string(toString(c)) + " " + std::to_string(by[size_t(c)]);
    }
    return text;
}

void printFrame(size_t frame, const oracle::Audit& a, double tolerance) {
    const size_t X = size_t(oracle::PairClass::Crossing), T = size_t(oracle::PairClass::Touching);
    std::printf("frame %zu: %zu pair(s) reported, %zu found, %zu missed", frame, a.reported, a.found, a.missed.size());
    if (!a.missed.empty())
        std::printf(" (%zu crossing, %zu touching: %s)", a.missedByClass[X], a.missedByClass[T],
                    causeCounts(oracle::missedCauses(), a.missedBy).c_str());
    std::printf(", %zu spurious", a.spurious.size());
    if (!a.spurious.empty()) std::printf(" (%s)", causeCounts(oracle::spuriousCauses(), a.spuriousBy).c_str());
    std::printf("; tolerance %.6g\n", tolerance);
}

nlohmann::ordered_json pairJson(const TrianglePair& p) {
    return {p.a.object, p.a.triangle, p.b.object, p.b.triangle};
}

nlohmann::ordered_json frameJson(size_t frame, const oracle::Audit& a, double tolerance) {
    nlohmann::ordered_json missed = nlohmann::ordered_json::array(), spurious = nlohmann::ordered_json::array();
    for (const oracle::AuditedPair& m : a.missed)
        missed.push_back(
            {{"pair", pairJson(m.pair)}, {"class", toString(m.cls)}, {"cause", toString(m.cause)}, {"distance", m.distance}});
    for (const oracle::AuditedPair& s : a.spurious)
        spurious.push_back({{"pair", pairJson(s.pair)}, {"cause", toString(s.cause)}, {"distance", s.distance}});
    nlohmann::ordered_json missedBy = nlohmann::ordered_json::object(), spuriousBy = nlohmann::ordered_json::object();
    for (oracle::AuditCause c : oracle::missedCauses()) missedBy[toString(c)] = a.missedBy[size_t(c)];
    for (oracle::AuditCause c : oracle::spuriousCauses()) spuriousBy[toString(c)] = a.spuriousBy[size_t(c)];
    return {{"frame", frame},         {"tolerance", tolerance},       {"reported", a.reported},
            {"found", a.found},       {"missed_by_cause", missedBy}, {"spurious_by_cause", spuriousBy},
            {"missed", missed},       {"spurious", spurious}};
}

int runAudit(const AuditCommandOptions& o) {
    const Animation animation = loadScene(o.scene);
    const pipeline::PairList list = pipeline::readPairList(o.pairs);
    const std::vector<JudgedFrame> frames = framesToJudge(animation, list, o);
    oracle::AuditOptions options;
    options.selfPairsTested = !o.noSelfPairs;
    options.source = list.source;
    nlohmann::ordered_json framesJson = nlohmann::ordered_json::array();
    size_t disagreeing = 0;
    for (const JudgedFrame& judged : frames) {
        // A still scene is its base scene: no copy of its meshes.
        std::optional<Scene> moved;
        if (!animation.frames.empty()) moved = animation.sceneAt(judged.frame);
        const Scene& scene = moved ? *moved : animation.scene;
        const std::vector<TrianglePair> none;
        const std::vector<TrianglePair>& pairs = judged.entry ? judged.entry->pairs : none;
        if (judged.entry) pipeline::checkPairsInScene(list, *judged.entry, scene);
        options.tolerance = o.tolerance * study::sceneDiagonal(scene);
        const oracle::Audit a = oracle::audit(scene, oracle::findIntersections(scene), pairs, options);
        disagreeing += !a.agrees();
        printFrame(judged.frame, a, options.tolerance);
        if (!o.json.empty()) framesJson.push_back(frameJson(judged.frame, a, options.tolerance));
    }
    std::printf("%zu of %zu frame(s) agree with the oracle\n", frames.size() - disagreeing, frames.size());
    if (!o.json.empty()) {
        const nlohmann::ordered_json j = {{"scene", o.scene},
                                          {"pairs", o.pairs},
                                          {"tolerance_fraction", o.tolerance},
                                          {"self_pairs_tested", !o.noSelfPairs},
                                          {"frames", framesJson},
                                          {"provenance", toJson(provenance(0))}};
        writeFileAtomically(o.json, j.dump(1) + "\n");
    }
    return disagreeing == 0 ? 0 : 1;
}

}  // namespace

void addAuditCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<AuditCommandOptions>();
    CLI::App* sub = app.add_subcommand(
        "audit", "Judge a list of intersecting triangle pairs (any library's) against the exact oracle: every "
                 "missed and spurious pair with its cause; exit 1 if any");
    sub->add_option("scene", o->scene, "Scene file (.json) or mesh")->required();
    sub->add_option("pairs", o->pairs,
                    "Pair list, by content: JSON {\"frames\": [{\"pairs\": [[objA, triA, objB, triB], ...]}]} "
                    "(`oracle --json` writes it) when it begins with '{', else CSV "
                    "frame,object_a,triangle_a,object_b,triangle_b")
        ->required();
    addNumber(sub, "--frame", o->frame, "Only this frame (default: every frame of the scene)", 0L,
              std::numeric_limits<long>::max());
    sub->add_option("--json", o->json, "Write per frame the missed and spurious pairs with their causes");
    addNumber(sub, "--tolerance", o->tolerance,
              "Within-tolerance distance, as a fraction of the scene's bounding-box diagonal at the frame", 0.0, 0.1)
        ->capture_default_str();
    sub->add_flag("--no-self-pairs", o->noSelfPairs,
                  "The list's maker tests no pairs within an object: missed ones are untested");
    sub->callback([o, &action] { action = [o] { return runAudit(*o); }; });
}

}  // namespace cullide::cli
