// `cullide study`: precision studies (sweeps timed and measured against the oracle, false prunes
// attributed to causes), their shards and merging, and the stability sweeps. The engine is in
// tools/study/ (cullide/study/: study.h, causes.h, probes.h); the rules are in docs/studies.md.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/oracle/audit.h"
#include "cullide/raster/backends.h"
#include "cullide/study/probes.h"
#include "cullide/study/study.h"

#include <algorithm>
#include <cstdio>

namespace cullide::cli {
namespace {

struct StudyCliOptions {
    std::string spec;
    std::string preset;
    std::vector<std::string> scenes, methods, resolutions, depths, directions, views, hierarchies, backends,
        exactSwitches;
    std::vector<uint32_t> leafSizes;
    std::vector<int> threads;
    int repeats = 0;  // 0: the spec's
    double nearDistance = -1;  // < 0: the spec's
    double tolerance = -1;  // < 0: the spec's
    bool noOracle = false;
    std::string shard;
    std::string out = "study.csv";
    bool quiet = false;
    ProgressMode progress = ProgressMode::Auto;
    // Stability sweeps
    std::string stability;
    int trials = 0, resolution = 0;
    uint64_t seed = 1;
};

struct MergeCliOptions {
    std::vector<std::string> inputs;
    std::string out;
};

study::Spec buildSpec(const StudyCliOptions& o) {
    study::Spec s;
    if (!o.preset.empty()) {
        const int repeats = o.repeats > 0 ? o.repeats : 3;
        if (o.preset == "paper") s = study::paperPreset(repeats);
        else if (o.preset == "deforming") s = study::deformingPreset(repeats);
        else throw InputError("option --preset", "'" + o.preset + "': the presets are: paper, deforming");
    }
    if (!o.spec.empty()) s = study::loadSpec(o.spec);
    if (!o.scenes.empty()) s.scenes = o.scenes;
    // A value from the command line is named by its option in errors, one from the spec by its key.
    if (!o.methods.empty()) s.methods = o.methods, s.names.method = "option --methods";
    if (!o.resolutions.empty()) s.resolutions = o.resolutions, s.names.resolution = "option --resolutions";
    if (!o.depths.empty()) s.depths = o.depths, s.names.depth = "option --depths";
    if (!o.directions.empty()) s.directions = o.directions, s.names.directions = "option --directions";
    if (!o.views.empty()) s.views = o.views, s.names.views = "option --views";
    if (!o.hierarchies.empty()) s.hierarchies = o.hierarchies, s.names.hierarchy = "option --hierarchies";
    if (!o.leafSizes.empty()) s.leafSizes = o.leafSizes, s.names.leafSize = "option --leaf-sizes";
    if (!o.exactSwitches.empty()) s.exactSwitches = o.exactSwitches, s.names.exactSwitch = "option --exact-switches";
    if (!o.backends.empty()) s.backends = o.backends;
    if (!o.threads.empty()) s.threads = o.threads;
    if (o.repeats > 0) s.repeats = o.repeats;
    if (o.noOracle) s.oracle = false;
    if (o.nearDistance >= 0) s.nearDistance = o.nearDistance;
    if (o.tolerance >= 0) s.tolerance = o.tolerance;
    if (s.nearDistance > 0 && !s.oracle)
        throw InputError("option --no-oracle", "near contacts are counted against the oracle (--near-distance)");
    if (s.scenes.empty()) throw InputError("study", "no scenes: give a SPEC file, --preset paper|deforming or --scenes");
    return s;
}

// A number of the record, or 0 for null.
size_t countOf(const nlohmann::ordered_json& r, const char* key) {
    return r.contains(key) && r[key].is_number() ? r[key].get<size_t>() : 0;
}

// What the study could not explain: false prunes of image-space runs, missed and spurious pairs of
// the others.
size_t unexplainedOf(const nlohmann::ordered_json& r) {
    return countOf(r, "fp_unexplained") + countOf(r, "missed_unexplained") + countOf(r, "spurious_unexplained");
}

std::string msText(const char* what, double ms) {
    char text[96];
    std::snprintf(text, sizeof text, what, ms);
    return text;
}

// "bunny:5000 modified 500 24 axes: 12.3 ms, 9 calls, PCS 120 of 5000; false prunes ..."
std::string imageRunLine(const nlohmann::ordered_json& r) {
    std::string causes;
    if (!r["false_prunes"].is_null())
        causes = " false prunes " + r["false_prunes"].dump() + " (depth " + r["fp_depth_rounding"].dump() +
                 ", sampling " + r["fp_sampling"].dump() + ", edge-on " + r["fp_edge_on"].dump() + ", untested " +
                 r["fp_untested"].dump() + ", unexplained " + r["fp_unexplained"].dump() + ")";
    // The switch is named only when set, and the time to exact pairs only when the oracle ran.
    std::string exact;
    if (r.value("exact_switch", "never") != "never") exact = " exact switch " + r["exact_switch"].get<std::string>();
    if (r["time_to_exact_ms"].is_number()) causes += msText(", %.1f ms to exact pairs", r["time_to_exact_ms"].get<double>());
    return r["scene"].get<std::string>() + " " + r["method"].get<std::string>() + " " +
           r["resolution"].get<std::string>() + " " + r["depth"].get<std::string>() + " " +
           r["directions"].get<std::string>() + exact + msText(": %.1f ms, ", r["time_ms"].get<double>()) +
           r["calls"].dump() + " calls, PCS " + r["pcs"].dump() + " of " + r["triangles"].dump() + ";" + causes;
}

// "cloth:10000 embree: 8.1 ms to pairs; found 40, missed 2 (shared_vertex 2), spurious 0"
std::string pairRunLine(const nlohmann::ordered_json& r) {
    std::string line = r["scene"].get<std::string>() + " " + r["method"].get<std::string>() +
                       msText(": %.1f ms to pairs", r["time_to_pairs_ms"].get<double>());
    if (r["pairs_found"].is_null()) return line + " (no oracle)";
    const auto causes = [&](const std::string& prefix, const std::vector<oracle::AuditCause>& list) {
        std::string text;
        for (oracle::AuditCause c : list)
            if (const size_t n = countOf(r, (prefix + toString(c)).c_str()); n > 0)
                text += (text.empty() ? "" : ", ") + std::string(toString(c)) + " " + std::to_string(n);
        return text.empty() ? std::string() : " (" + text + ")";
    };
    return line + "; found " + r["pairs_found"].dump() + ", missed " + r["pairs_missed"].dump() +
           causes("missed_", oracle::missedCauses()) + ", spurious " + r["pairs_spurious"].dump() +
           causes("spurious_", oracle::spuriousCauses());
}

int runStability(const StudyCliOptions& o) {
    study::ProbeOptions p;
    if (o.trials > 0) p.trials = o.trials;
    if (o.resolution > 0) p.resolution = o.resolution;
    p.seed = o.seed;
    if (!o.methods.empty()) p.methods = o.methods;
    if (!o.depths.empty()) p.depths = o.depths;
    std::vector<nlohmann::ordered_json> rows;
    if (o.stability == "penetration") {
        rows = study::penetrationSweep(p, {0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 1.0, 1.1, 1.5, 2, 3, 5, 10});
    } else if (o.stability == "tilt") {
        std::vector<double> angles;
        for (double a = 0; a <= 80; a += 10) angles.push_back(a);
        for (double a : {85.0, 88.0, 89.0, 89.5, 89.9, 90.0}) angles.push_back(a);
        rows = study::tiltSweep(p, angles,
                                o.directions.empty() ? std::vector<std::string>{"z", "axes", "14"} : o.directions);
    } else if (o.stability == "overlap") {
        if (o.depths.empty()) p.depths = {"24"};
        rows = study::overlapSweep(p, {0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 4.0});
    } else if (o.stability == "jitter") {
        if (o.resolution <= 0) p.resolution = 500;
        if (o.trials <= 0) p.trials = 4;
        if (o.depths.empty()) p.depths = {"24"};
        rows = study::jitterSweep(p, o.scenes.empty() ? std::vector<std::string>{"bunny:5000", "cows:3000"} : o.scenes,
                                  {1e-7, 1e-5, 1e-3, 1e-2});
    } else {
        throw InputError("option --stability", "'" + o.stability + "': penetration, tilt, overlap or jitter");
    }
    size_t unexplained = 0, detected = 0;
    for (const auto& r : rows) unexplained += r["fp_unexplained"].get<size_t>(), detected += r["detected"].get<int>();
    writeFileAtomically(o.out, study::rowsToCsv(rows));
    std::printf("%s: %zu trials, %zu without false prunes; unexplained false prunes: %zu; wrote %s\n",
                o.stability.c_str(), rows.size(), detected, unexplained, o.out.c_str());
    return unexplained ? 1 : 0;
}

// The sweep's options and the stability sweeps' are apart: an option that does not apply is
// refused, not ignored.
void refuseInapplicable(const StudyCliOptions& o, const CLI::App& sub) {
    auto refuse = [&](const char* name, const char* why) {
        if (sub.count(name) > 0) throw CLI::ValidationError(name, why);
    };
    if (o.stability.empty()) {
        for (const char* name : {"--trials", "--resolution", "--seed"}) refuse(name, "applies to --stability only");
        return;
    }
    if (!o.spec.empty()) throw CLI::ValidationError("spec", "a study spec does not apply to --stability");
    for (const char* name :
         {"--preset", "--resolutions", "--views", "--hierarchies", "--leaf-sizes", "--exact-switches", "--backends",
          "--threads", "--repeats", "--no-oracle", "--near-distance", "--shard", "--progress"})
        refuse(name, "does not apply to --stability");
    if (o.stability != "tilt") refuse("--directions", "applies to --stability tilt only");
    if (o.stability != "jitter") refuse("--scenes", "applies to --stability jitter only");
}

int runStudyCommand(const StudyCliOptions& o) {
    if (!o.stability.empty()) return runStability(o);
    study::StudyOptions so;
    so.spec = buildSpec(o);
    // The sweep is a product, so gl and vulkan runs get every thread count too; say that they ignore it.
    const auto& sp = so.spec;
    const bool gpu =
        std::any_of(sp.backends.begin(), sp.backends.end(), [](const std::string& b) { return b != "cpu"; });
    if (gpu && std::any_of(sp.threads.begin(), sp.threads.end(), [](int t) { return t != 0; }))
        std::fprintf(stderr,
                     "cullide: warning: threads apply to the cpu backend only; the gl and vulkan runs ignore them\n");
    if (!o.shard.empty()) so.shard = study::parseShard(o.shard);
    so.out = o.out;
    so.command = commandLine();
    so.progress = o.quiet ? ProgressMode::Never : o.progress;
    size_t unexplained = 0;
    so.onRecord = [&](const nlohmann::ordered_json& r) {
        unexplained += unexplainedOf(r);
        if (r.contains("error"))  // a peer that cannot take the scene: said even with -q
            std::fprintf(stderr, "cullide: warning: %s %s: %s\n", r["scene"].get<std::string>().c_str(),
                         r["method"].get<std::string>().c_str(), r["error"].get<std::string>().c_str());
        if (o.quiet || r.contains("error")) return;
        std::printf("%s\n", (r["family"] == "image-space" ? imageRunLine(r) : pairRunLine(r)).c_str());
        std::fflush(stdout);
    };
    const size_t done = study::runStudy(so);
    const study::OutputPaths paths = study::outputPaths(so.out);
    std::printf("study: %zu run(s) done, results in %s and %s; unexplained false prunes and pairs: %zu\n", done,
                paths.csv.string().c_str(), paths.jsonl.string().c_str(), unexplained);
    return unexplained ? 1 : 0;
}

}  // namespace

void addStudyCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<StudyCliOptions>();
    CLI::App* sub = app.add_subcommand(
        "study", "Sweep configurations over scenes: time, PCS, false prunes by class and cause (docs/studies.md)");
    sub->add_option("spec", o->spec, "Study spec (.json); command-line lists override its fields");
    sub->add_option("--preset", o->preset,
                    "paper: the seed paper's Section 6 (bunny 5k-270k, two cows 3k-270k, 500x500, D24, modified); "
                    "deforming: cloth 10k-92k and N-body 10k-146k, original, modified and reliable, with near contacts");
    sub->add_option("--scenes", o->scenes,
                    "Scenes: bunny:N, cows:N, twist:N, cylinders:N[:C], cloth:N, nbody:N, or files (FILE@K: frame K)");
    sub->add_option("--methods", o->methods,
                    "Methods: original, modified, reliable (as prune --method); exact (the oracle alone); the peers "
                    "fcl, embree, bullet, cgal (docs/peers.md)");
    sub->add_option("--resolutions", o->resolutions, "Viewports: N or WxH, or auto / auto:K (adaptive)");
    sub->add_option("--depths", o->depths, "Depth formats: 8..32 or float");
    sub->add_option("--directions", o->directions,
                    "Direction sets: axes, N, a list, pca or coherent[:LIST] (one set per argument; a study runs "
                    "each frame alone, so coherent is its full list)");
    sub->add_option("--views", o->views, "View modes: fit | clustered (docs/cullide.md#views-per-cluster)");
    sub->add_option("--hierarchies", o->hierarchies, "connectivity | random");
    addNumbers(sub, "--leaf-sizes", o->leafSizes, "Hierarchy leaf sizes", 1u, kMaxLeafSize);
    sub->add_option("--exact-switches", o->exactSwitches,
                    "Switches to exact: never, auto or N (as prune --exact-switch); with the oracle, each run records "
                    "its time to exact pairs");
    sub->add_option("--backends", o->backends, "Backends: " + raster::backendNameList());
    addNumbers(sub, "--threads", o->threads, "Worker threads per run (0: all cores)", 0, kMaxThreads);
    addNumber(sub, "--repeats", o->repeats, "Timed runs per configuration (median, min, max)", 1, 1000);
    sub->add_flag("--no-oracle", o->noOracle, "Time only: no oracle, no false prunes");
    addNumber(sub, "--near-distance", o->nearDistance,
              "Count near contacts (pairs this close that do not intersect) per scene and frame, the distance as a "
              "fraction of the scene's bounding-box diagonal at its first frame (0: not counted, the default; at most "
              "0.1)",
              0.0, study::kMaxNearDistance);
    addNumber(sub, "--tolerance", o->tolerance,
              "The audit's tolerance for the pairs of exact and the peers: pairs closer than this, or crossing less "
              "deep, are judged within tolerance (a fraction of the scene's bounding-box diagonal at its first frame; "
              "default 1e-05, at most 0.1)",
              0.0, study::kMaxTolerance);
    sub->add_option("--shard", o->shard,
                    "Run only slice i of N (i/N, 0-based; e.g. $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT)");
    sub->add_option("-o,--out", o->out,
                    "Output .csv (JSON lines beside it as .jsonl); existing runs are skipped (resume)")
        ->capture_default_str();
    sub->add_flag("-q,--quiet", o->quiet, "No per-run lines and no progress bar (whatever --progress says)");
    addProgressOption(sub, o->progress);
    sub->add_option("--stability", o->stability,
                    "Run a stability sweep instead: penetration | tilt | overlap | jitter (CSV to --out)");
    addNumber(sub, "--trials", o->trials, "Stability: trials per point", 1, 100000);
    addNumber(sub, "--resolution", o->resolution, "Stability: viewport side", 1, kMaxViewportSide);
    addNumber(sub, "--seed", o->seed, "Stability: random seed");
    sub->callback([o, sub, &action] {
        if (!sub->get_subcommands().empty()) return;
        refuseInapplicable(*o, *sub);
        action = [o] { return runStudyCommand(*o); };
    });

    auto m = std::make_shared<MergeCliOptions>();
    CLI::App* merge = sub->add_subcommand("merge", "Join study outputs (shards) into one, by run id, in sweep order");
    merge->add_option("inputs", m->inputs, "Study outputs (.csv or .jsonl)")->required();
    merge->add_option("-o,--out", m->out, "Merged output (.csv; .jsonl beside it)")->required();
    merge->callback([m, &action] {
        action = [m] {
            std::vector<std::filesystem::path> in(m->inputs.begin(), m->inputs.end());
            const size_t n = study::mergeOutputs(in, m->out);
            std::printf("merged %zu run(s) from %zu file(s) into %s\n", n, in.size(), m->out.c_str());
            return 0;
        };
    });
}

}  // namespace cullide::cli
