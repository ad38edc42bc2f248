// Precision studies: sweeps of Cullide configurations over scenes, each run timed and measured
// against the exact oracle, its false prunes attributed to causes (causes.h).
//
// Conventions
//   - A Spec lists values per axis; the sweep is their product, in a fixed order: scene (and
//     frame) outermost, then method, resolution, depth, directions, views, hierarchy, leaf size,
//     exact switch, backend, threads. RunConfig::index is the position in that order.
//   - A run's id is a 16-hex-digit FNV-1a hash of its canonical key (every axis value, as given,
//     plus branching and seed; views only when not "fit" and the exact switch only when not
//     "never", so that the ids of studies from before those axes stay): stable across processes,
//     shards and machines; resuming and merging key on it. Repeats are not part of the key.
//   - Scenes: "bunny:N" (the deformed bunny, make-scene bunny), "cows:N" (two cows), "cylinders:N"
//     or "cylinders:N:C", "twist:N" (a twisted bunny), "cloth:N" (the draped cloth, the last state
//     of make-scene cloth), "nbody:N" (make-scene nbody at time 0); or a scene/mesh file; "@K" picks frame K
//     of a file's animation, "@all" (the default for files) every frame.
//   - Records are flat JSON objects (plus a "passes" array of per-call stats, a "provenance"
//     object, cullide/provenance.h, and the "command" that ran the sweep, when known); the CSV
//     holds the flat columns of kColumns, in that order. Columns ending in "_ms" (and the passes'
//     seconds) are timings; they, the provenance (its date, and the machine of a shard) and the
//     command (a shard's --shard) may differ between runs: everything else is a pure function of
//     the configuration.
//   - Errors: InputError naming the spec field, option or file.
#pragma once

#include "cullide/cullide.h"
#include "cullide/depth_backend.h"
#include "cullide/options.h"
#include "cullide/oracle/oracle.h"
#include "cullide/scene.h"
#include "cullide/pipeline/progress.h"
#include "cullide/study/methods.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cullide::study {

// What a spec's axes are called in errors: `source`'s keys ("spec.json: field 'depths'").
OptionNames specOptionNames(const std::string& source);

struct Spec {
    std::vector<std::string> scenes;
    std::vector<std::string> methods{"modified"};
    std::vector<std::string> resolutions{"500"};
    std::vector<std::string> depths{"24"};
    std::vector<std::string> directions{"axes"};
    std::vector<std::string> views{"fit"};  // fit | clustered (docs/cullide.md#views-per-cluster)
    std::vector<std::string> hierarchies{"connectivity"};
    std::vector<uint32_t> leafSizes{16};
    std::vector<std::string> exactSwitches{"never"};  // never | auto | N (parseExactSwitch)
    std::vector<std::string> backends{"cpu"};
    std::vector<int> threads{0};
    uint32_t branching = 4;
    uint64_t seed = 1;
    int repeats = 3;  // timed runs per configuration (median, min, max)
    bool oracle = true;  // measure against the oracle and attribute causes
    // Near contacts (cullide/oracle/near_contacts.h) are counted per scene and frame within this
    // fraction of the scene's bounding-box diagonal at its first frame (the same distance in every
    // frame of an animation); 0: not counted (needs the oracle).
    double nearDistance = 0;
    // The audit's tolerance for the pairs of the exact method and the peers (cullide/oracle/audit.h):
    // a fraction of the scene's bounding-box diagonal at its first frame, as the near distance.
    double tolerance = kDefaultTolerance;
    // Each axis' name in errors: its spec key, or the command-line option that set it.
    OptionNames names = specOptionNames("study spec");
    // What errors about the whole sweep name: the spec file it was read from.
    std::string source = "study spec";
};

// Reads a JSON spec: {"scenes": [...], "methods": [...], "resolutions": [...], "depths": [...],
// "directions": [...], "views": [...], "hierarchies": [...], "leaf_sizes": [...], "exact_switches": [...],
// "backends": [...],
// "threads": [...], "branching": B, "seed": S, "repeats": K, "near_distance": F, "tolerance": F, "oracle": true}. Scalars are accepted
// where lists are expected, and a list of one where a scalar is. Every field is checked here,
// before anything runs: an unknown key, an empty list, a wrong type or a value out of range is an
// InputError(source, "field 'KEY': ...") (spec.cpp).
Spec parseSpec(const nlohmann::json& j, const std::string& source);
Spec loadSpec(const std::string& path);
// The paper's Section 6 experiments (docs/paper.md#section-6): bunny 5k..270k, two cows 3k..270k, 500x500, D24,
// modified, axes, connectivity leaf 16; `repeats` timed runs each.
Spec paperPreset(int repeats = 3);
// The field's deforming scenes (docs/scenes.md): cloth:10000, 30000, 92000 and nbody:10000, 50000,
// 146000 (their draped and first states), original, modified and reliable at 500x500, D24, near
// contacts within kDeformingNearDistance of the diagonal.
Spec deformingPreset(int repeats = 3);
inline constexpr double kDeformingNearDistance = 0.001;

struct RunConfig {
    size_t index = 0;
    std::string scene;
    uint32_t frame = 0;
    std::string method, resolution, depth, directions, hierarchy;
    std::string views = "fit";
    uint32_t leafSize = 16, branching = 4;
    uint64_t seed = 1;
    double nearDistance = 0;  // the spec's: part of the key when not 0
    double tolerance = kDefaultTolerance;  // the spec's: part of a pair method's key when not the default
    std::string exactSwitch = "never";
    std::string backend;
    int threads = 0;

    // The exact method and the peers have no image-space axes: empty strings, leaf size and
    // branching 0 (so that their keys name only what they depend on).
    void clearImageAxes();
    std::string key() const;
    std::string id() const;
};

// The largest near distance a spec may ask for: a tenth of the scene's diagonal already makes
// most pairs of a compact scene near contacts.
inline constexpr double kMaxNearDistance = 0.1;

// The most runs a sweep may have: expand refuses a larger one before it makes any.
inline constexpr uint64_t kMaxStudyRuns = 1'000'000;

// The product of the spec's axes (validates every value first: InputError; also when it has more
// than kMaxStudyRuns runs). File scenes are opened to count their frames.
std::vector<RunConfig> expand(const Spec& spec);

// "i/N" with 0 <= i < N: the i-th of N contiguous slices of the sweep (scene-major, so a slice
// computes few oracles). Slices are disjoint and cover the sweep.
struct Shard {
    size_t index = 0, count = 1;
};
Shard parseShard(const std::string& text);  // InputError("option --shard", ...)
std::vector<RunConfig> slice(const std::vector<RunConfig>& all, const Shard& shard);

// The scene of a scene string (see the conventions) at one frame, and its frame count.
Scene loadStudyScene(const std::string& text, uint32_t frame);
size_t studyFrameCount(const std::string& text);

// Options of a configuration (throws InputError on bad values, naming them by `names`).
CullideOptions cullideOptions(const RunConfig& c, const OptionNames& names = specOptionNames("study spec"));

// One reducePCS call's statistics as a record's (and prune --json's) "passes" entry, under
// `options`: with clustered views also its count of views, with chosen directions (pca,
// coherent) also "direction_vector", the direction itself (so that the default entries stay as
// they were).
nlohmann::ordered_json passJson(const PassStats& p, const CullideOptions& options);

// Runs one configuration: `repeats` timed runs, then (with the oracle) `repeats` timed runs of the
// exact stage on the PCS (time to exact pairs: the median run plus the median exact stage) and
// one instrumented run for the causes. `truth` may be null when the oracle is off (the measures are then null). Returns
// the record; `backend` is the configuration's backend.
nlohmann::ordered_json runOne(const RunConfig& c, const Scene& scene, const oracle::Truth* truth, int repeats,
                              DepthBackend& backend);

// Column names of the CSV, in order.
const std::vector<std::string>& columns();
bool isTimingColumn(const std::string& name);
std::string csvHeader();
std::string csvRow(const nlohmann::ordered_json& record);

// Output: `path` ending in .csv (JSON lines beside it, same stem, .jsonl) or .jsonl (CSV beside).
struct OutputPaths {
    std::filesystem::path csv, jsonl;
};
OutputPaths outputPaths(const std::filesystem::path& path);
// Reads the records of a study output (.csv or .jsonl; the .jsonl is read). Incomplete lines
// (a run killed mid-write) are skipped. InputError on unreadable files.
std::vector<nlohmann::ordered_json> readRecords(const std::filesystem::path& path);

struct StudyOptions {
    Spec spec;
    Shard shard;
    std::filesystem::path out;  // .csv or .jsonl
    ProgressMode progress = ProgressMode::Never;  // the bar with ETA on stderr (progress.h)
    std::function<void(const nlohmann::ordered_json&)> onRecord;  // after each run
    // The command line that asked for the sweep (`cullide study ...`); when not empty, each record
    // carries it as "command" (JSON lines only, not a CSV column), so a report can show how the
    // data were made. Like the provenance, it may differ between shards of one sweep.
    std::string command;
};
// Runs the sweep (or its shard), appending to the output; runs whose id is already in the
// output are skipped (resume). Returns the number of runs done now.
size_t runStudy(const StudyOptions& options);

// Joins study outputs (shards) into `out`: records deduplicated by id, sorted by index.
// Returns the number of records.
size_t mergeOutputs(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& out);

}  // namespace cullide::study
