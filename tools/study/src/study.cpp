// The study engine: specs, the sweep, one run, resumable output, shards and merging (study.h).
#include "cullide/study/study.h"

#include "cullide/study/causes.h"
#include "cullide/study/measures.h"
#include "cullide/study/methods.h"
#include "cullide/pipeline/progress.h"
#include "cullide/pipeline/pruner.h"

#include "pair_run.h"
#include "record_fields.h"

#include "cullide/cloth.h"
#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/generators.h"
#include "cullide/json_read.h"
#include "cullide/mesh_io.h"
#include "cullide/nbody.h"
#include "cullide/parallel.h"
#include "cullide/parse_number.h"
#include "cullide/provenance.h"
#include "cullide/resources.h"
#include "cullide/raster/backends.h"
#include "cullide/scene_io.h"

#include <tbb/task_arena.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace cullide::study {
namespace {

std::string dataDir() {
    return cullide::dataDir().string();
}

// "name:a:b" split at ':' (a Windows drive letter is not a concern here).
std::vector<std::string> splitColon(const std::string& s) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : s) {
        if (c == ':') out.push_back(cur), cur.clear();
        else cur += c;
    }
    out.push_back(cur);
    return out;
}

size_t parseCount(const std::string& text, const std::string& scene) {
    return parseNumber(text, "scene '" + scene + "'", size_t(1), size_t(50'000'000));
}

bool isGenerated(const std::string& text) {
    const std::string head = splitColon(text)[0];
    return head == "bunny" || head == "cows" || head == "cylinders" || head == "twist" || head == "cloth" ||
           head == "nbody";
}

// The file part of "path@K" and the frame selector ("" when none).
std::pair<std::string, std::string> splitFrame(const std::string& text) {
    const size_t at = text.rfind('@');
    if (at == std::string::npos) return {text, ""};
    return {text.substr(0, at), text.substr(at + 1)};
}

uint64_t fnv1a(const std::string& s) {
    uint64_t h = 1469598103934665603ull;
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
    return h;
}

std::string csvField(const nlohmann::ordered_json& v) {
    if (v.is_null()) return "";
    if (v.is_string()) {
        const std::string s = v.get<std::string>();
        if (s.find_first_of(",\"\n") == std::string::npos) return s;
        std::string q = "\"";
        for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
        return q + "\"";
    }
    if (v.is_number_float()) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
        return buf;
    }
    return v.dump();
}

}  // namespace

OptionNames specOptionNames(const std::string& source) {
    auto field = [&](const char* key) { return source + ": field '" + key + "'"; };
    OptionNames n;
    n.method = field("methods"), n.resolution = field("resolutions"), n.depth = field("depths");
    n.directions = field("directions"), n.hierarchy = field("hierarchies"), n.leafSize = field("leaf_sizes");
    n.branching = field("branching"), n.views = field("views"), n.exactSwitch = field("exact_switches");
    return n;
}

Spec paperPreset(int repeats) {
    Spec s;
    // Five sizes per scene over the paper's ranges (bunny 5k-270k, cows 3k-270k).
    s.scenes = {"bunny:5000", "bunny:20000", "bunny:70000", "bunny:150000", "bunny:270000",
                "cows:3000",  "cows:20000",  "cows:70000",  "cows:150000",  "cows:270000"};
    s.methods = {"modified"};
    s.resolutions = {"500"};
    s.depths = {"24"};
    s.repeats = repeats;
    return s;
}

Spec deformingPreset(int repeats) {
    Spec s;
    // From 10k to the sizes of the field's sequences (cloth on a ball 92k, N-body 146k).
    s.scenes = {"cloth:10000", "cloth:30000", "cloth:92000", "nbody:10000", "nbody:50000", "nbody:146000"};
    s.methods = {"original", "modified", "reliable"};
    s.resolutions = {"500"};
    s.depths = {"24"};
    s.nearDistance = kDeformingNearDistance;
    s.repeats = repeats;
    return s;
}

void RunConfig::clearImageAxes() {
    resolution.clear(), depth.clear(), directions.clear(), hierarchy.clear(), backend.clear();
    views = "fit", exactSwitch = "never";  // their defaults: not in the key
    leafSize = 0, branching = 0, seed = 0;
}

std::string RunConfig::key() const {
    std::ostringstream k;
    k << scene << '|' << frame << '|' << method << '|' << resolution << '|' << depth << '|' << directions << '|'
      << hierarchy << '|' << leafSize << '|' << branching << '|' << seed << '|' << backend << '|' << threads;
    if (views != "fit") k << "|views=" << views;
    if (exactSwitch != "never") k << "|exact=" << exactSwitch;  // the defaults keep the ids they always had
    if (nearDistance > 0) k << "|near=" << numberText(nearDistance);
    if (resolution.empty() && tolerance != kDefaultTolerance) k << "|tol=" << numberText(tolerance);  // a pair method
    return k.str();
}

std::string RunConfig::id() const {
    char buf[24];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)fnv1a(key()));
    return buf;
}

namespace {

// A generated scene "kind:N" or "cylinders:N:C": its kind, request and cylinder count, every number
// checked (expand() and studyFrameCount call it, so a bad one is refused before any run).
struct Generated {
    std::string kind;
    SceneRequest request;
    size_t cylinders = 8;
};

Generated parseGenerated(const std::string& text) {
    const std::vector<std::string> parts = splitColon(text);
    if (parts.size() < 2 || parts.size() > 3 || (parts.size() == 3 && parts[0] != "cylinders"))
        throw InputError("scene '" + text + "'", "expected bunny:N, cows:N, twist:N, cylinders:N[:C], cloth:N or nbody:N");
    Generated g;
    g.kind = parts[0];
    g.request.triangles = parseCount(parts[1], text);
    if (parts.size() == 3) g.cylinders = parseCount(parts[2], text);
    return g;
}

}  // namespace

size_t studyFrameCount(const std::string& text) {
    if (isGenerated(text)) return (void)parseGenerated(text), size_t(1);
    return loadScene(splitFrame(text).first).frameCount();
}

Scene loadStudyScene(const std::string& text, uint32_t frame) {
    if (isGenerated(text)) {
        const Generated g = parseGenerated(text);
        const SceneRequest& r = g.request;
        if (g.kind == "bunny") return makeDeformedBunny(loadMesh(dataDir() + "/meshes/bunny.off"), r).scene;
        if (g.kind == "cows") return makeTwoCows(loadMesh(dataDir() + "/meshes/cow.off"), r).scene;
        if (g.kind == "twist")
            return makeTwistAnimation(resample(loadMesh(dataDir() + "/meshes/bunny.off"), r.triangles), r).scene;
        if (g.kind == "cloth") return makeCloth({.triangles = r.triangles, .frames = 1}).sceneAt(0);  // draped
        if (g.kind == "nbody") {
            std::vector<Mesh> meshes;
            for (const auto& path : nbodyMeshPaths()) meshes.push_back(loadMesh(path));
            // make-scene's 100 bodies; fewer where N leaves a body under the minimum of triangles.
            const size_t count = std::min(NBodyRequest{}.count, std::max<size_t>(1, r.triangles / kMinNBodyTrianglesPerBody));
            return makeNBody(meshes, {.count = count, .triangles = r.triangles, .frames = 1}).sceneAt(0);  // time 0
        }
        return makeCylinders(g.cylinders, r).scene;
    }
    const Animation a = loadScene(splitFrame(text).first);
    if (frame >= a.frameCount())
        throw InputError("scene '" + text + "'",
                         "has " + std::to_string(a.frameCount()) + " frame(s), no frame " + std::to_string(frame));
    return a.sceneAt(frame);
}

namespace {

// The frames a scene string selects: a generated scene's one frame, or a file's "file:K", "file:all"
// or every frame.
std::vector<uint32_t> framesOf(const std::string& scene) {
    if (isGenerated(scene)) return (void)parseGenerated(scene), std::vector<uint32_t>{0};
    const auto [file, sel] = splitFrame(scene);
    const size_t count = studyFrameCount(scene);
    std::vector<uint32_t> frames;
    if (sel.empty() || sel == "all") {
        for (uint32_t f = 0; f < count; ++f) frames.push_back(f);
        return frames;
    }
    if (count == 0) throw InputError("scene '" + scene + "'", "frame '" + sel + "': the file has no frames");
    return {parseNumber(sel, "scene '" + scene + "': frame", uint32_t(0), uint32_t(count - 1))};
}

// Every combination of the spec's lists for one frame of one scene, appended in the order of the
// lists (methods, resolutions, depths, directions, views, hierarchies, leaf sizes, exact switches,
// backends, threads), the last varying fastest. Every list is non-empty.
void appendCombinations(const Spec& spec, const std::string& scene, uint32_t frame, std::vector<RunConfig>& out) {
    constexpr size_t kAxes = 10;
    const std::array<size_t, kAxes> sizes = {spec.methods.size(),     spec.resolutions.size(), spec.depths.size(),
                                             spec.directions.size(),  spec.views.size(),       spec.hierarchies.size(),
                                             spec.leafSizes.size(),   spec.exactSwitches.size(), spec.backends.size(),
                                             spec.threads.size()};
    std::array<size_t, kAxes> i{};
    for (;;) {
        // The exact method and the peers have only the threads axis: one run per thread count.
        if (methodFamily(spec.methods[i[0]], spec.names.method) != MethodFamily::ImageSpace &&
            (i[1] | i[2] | i[3] | i[4] | i[5] | i[6] | i[7] | i[8]) != 0) {
            size_t k = kAxes;
            while (k > 0 && ++i[k - 1] == sizes[k - 1]) i[--k] = 0;
            if (k == 0) return;
            continue;
        }
        RunConfig c;
        c.index = out.size();
        c.scene = scene, c.frame = frame, c.method = spec.methods[i[0]], c.resolution = spec.resolutions[i[1]];
        c.depth = spec.depths[i[2]], c.directions = spec.directions[i[3]], c.views = spec.views[i[4]];
        c.hierarchy = spec.hierarchies[i[5]], c.leafSize = spec.leafSizes[i[6]], c.exactSwitch = spec.exactSwitches[i[7]];
        c.backend = spec.backends[i[8]], c.threads = spec.threads[i[9]];
        c.branching = spec.branching, c.seed = spec.seed, c.nearDistance = spec.nearDistance;
        c.tolerance = spec.tolerance;
        if (methodFamily(c.method, spec.names.method) != MethodFamily::ImageSpace) c.clearImageAxes();
        out.push_back(c);
        size_t k = kAxes;
        while (k > 0 && ++i[k - 1] == sizes[k - 1]) i[--k] = 0;
        if (k == 0) return;
    }
}

}  // namespace

std::vector<RunConfig> expand(const Spec& spec) {
    if (spec.scenes.empty()) throw InputError("study spec", "no scenes");
    if (spec.repeats < 1 || spec.repeats > 1000) throw InputError("study spec", "repeats must be 1 to 1000");
    auto nonEmpty = [](const auto& v, const char* what) {
        if (v.empty()) throw InputError("study spec", std::string("no ") + what);
    };
    nonEmpty(spec.methods, "methods"), nonEmpty(spec.resolutions, "resolutions"), nonEmpty(spec.depths, "depths");
    nonEmpty(spec.directions, "directions"), nonEmpty(spec.hierarchies, "hierarchies"), nonEmpty(spec.views, "views");
    nonEmpty(spec.leafSizes, "leaf sizes"), nonEmpty(spec.backends, "backends"), nonEmpty(spec.threads, "threads");
    nonEmpty(spec.exactSwitches, "exact switches");
    if (!(spec.nearDistance >= 0 && spec.nearDistance <= kMaxNearDistance))
        throw InputError("study spec", "near distance " + numberText(spec.nearDistance) + " is out of range (0 to " +
                                           numberText(kMaxNearDistance) + ")");
    if (spec.nearDistance > 0 && !spec.oracle)
        throw InputError("study spec", "near contacts are counted against the oracle: a near distance needs it");
    for (const std::string& b : spec.backends)
        if (!raster::isBackendName(b))
            throw InputError("study spec", "backend '" + b + "': " + raster::backendNameList());
    for (int t : spec.threads) checkThreads(t, "study spec: threads");
    // Counted before anything is expanded (a few axes of a few hundred values make billions of
    // runs): the configurations per frame first, then per scene as its frames are known.
    constexpr uint64_t kSaturated = std::numeric_limits<uint64_t>::max();
    const auto product = [](uint64_t a, uint64_t b) {
        uint64_t p;
        return __builtin_mul_overflow(a, b, &p) ? kSaturated : p;
    };
    const auto shown = [](uint64_t n) { return n == kSaturated ? std::string("over 2^64") : std::to_string(n); };
    uint64_t perFrame = 1;
    for (size_t n : {spec.methods.size(), spec.resolutions.size(), spec.depths.size(), spec.directions.size(),
                     spec.views.size(), spec.hierarchies.size(), spec.leafSizes.size(), spec.exactSwitches.size(),
                     spec.backends.size(), spec.threads.size()})
        perFrame = product(perFrame, n);
    const auto tooMany = [&](uint64_t frames) {
        const uint64_t runs = product(frames, perFrame);
        if (runs <= kMaxStudyRuns) return;
        throw InputError(spec.source,
                         "the sweep has " + shown(runs) + " runs (" + std::to_string(frames) + " scene frames x " +
                             shown(perFrame) + " configurations), more than the limit of " +
                             std::to_string(kMaxStudyRuns) + " runs: split it into several studies");
    };
    tooMany(spec.scenes.size());  // at least a frame each
    std::vector<std::vector<uint32_t>> frames;
    uint64_t frameCount = 0;
    for (const std::string& scene : spec.scenes) {
        frames.push_back(framesOf(scene));
        tooMany(frameCount += frames.back().size());
    }
    std::vector<RunConfig> out;
    for (size_t s = 0; s < spec.scenes.size(); ++s)
        for (uint32_t frame : frames[s]) appendCombinations(spec, spec.scenes[s], frame, out);
    for (const std::string& m : spec.methods) (void)methodFamily(m, spec.names.method);
    if (!(spec.tolerance >= 0 && spec.tolerance <= kMaxTolerance))
        throw InputError("study spec", "tolerance " + numberText(spec.tolerance) + " is out of range (0 to " +
                                           numberText(kMaxTolerance) + ")");
    for (const RunConfig& c : out)  // every value checked before any run
        if (methodFamily(c.method, spec.names.method) == MethodFamily::ImageSpace) (void)cullideOptions(c, spec.names);
    return out;
}

Shard parseShard(const std::string& text) {
    const size_t slash = text.find('/');
    if (slash == std::string::npos)
        throw InputError("option --shard", "'" + text + "': expected i/N with 0 <= i < N (e.g. 0/4)");
    Shard s;
    s.count = parseNumber(std::string_view(text).substr(slash + 1), "option --shard: N", size_t(1), size_t(1'000'000));
    s.index = parseNumber(std::string_view(text).substr(0, slash), "option --shard: i", size_t(0), s.count - 1);
    return s;
}

std::vector<RunConfig> slice(const std::vector<RunConfig>& all, const Shard& shard) {
    const size_t begin = all.size() * shard.index / shard.count, end = all.size() * (shard.index + 1) / shard.count;
    return {all.begin() + ptrdiff_t(begin), all.begin() + ptrdiff_t(end)};
}

CullideOptions cullideOptions(const RunConfig& c, const OptionNames& names) {
    OptionText t;
    t.method = c.method, t.resolution = c.resolution, t.depth = c.depth, t.directions = c.directions;
    t.hierarchy = c.hierarchy, t.leafSize = c.leafSize, t.branching = c.branching, t.seed = c.seed;
    t.views = c.views;
    t.exactSwitch = c.exactSwitch;
    return parseCullideOptions(t, names);
}

const std::vector<std::string>& columns() {
    static const std::vector<std::string> c = {"index",
                                               "id",
                                               "scene",
                                               "frame",
                                               "triangles",
                                               "objects",
                                               "method",
                                               "resolution",
                                               "depth",
                                               "directions",
                                               "direction_count",
                                               "views",
                                               "hierarchy",
                                               "leaf_size",
                                               "branching",
                                               "backend",
                                               "threads",
                                               "repeats",
                                               "time_ms",
                                               "time_min_ms",
                                               "time_max_ms",
                                               "hierarchy_ms",
                                               "calls",
                                               "levels",
                                               "triangles_rendered",
                                               "queries",
                                               "pcs",
                                               "oracle_pairs",
                                               "oracle_crossing",
                                               "oracle_touching",
                                               "colliding",
                                               "false_prunes",
                                               "fp_crossing",
                                               "fp_touching",
                                               "fp_depth_rounding",
                                               "fp_sampling",
                                               "fp_edge_on",
                                               "fp_untested",
                                               "fp_unexplained",
                                               "missed_pairs",
                                               "mp_crossing",
                                               "mp_touching",
                                               "mp_depth_rounding",
                                               "mp_sampling",
                                               "mp_edge_on",
                                               "mp_untested",
                                               "mp_unexplained",
                                               "false_positives",
                                               "efficiency",
                                               "attribution_ms"};
    // Switch to exact (the exact_switches axis): after the others, so an older CSV's columns stay a prefix.
    static const std::vector<std::string> all = [] {
        std::vector<std::string> v = c;
        for (const char* k : {"exact_switch", "switched_at_level", "exact_ms", "time_to_exact_ms"}) v.push_back(k);
        for (const char* k : {"near_distance", "near_contacts", "near_contacts_self"}) v.push_back(k);
        // Every family's measure (methods.h): after the others, so an older CSV's columns stay a prefix.
        for (const char* k : {"family", "time_to_pairs_ms", "pairs_found", "pairs_missed", "pairs_spurious", "tolerance"})
            v.push_back(k);
        for (oracle::AuditCause a : oracle::missedCauses()) v.push_back(std::string("missed_") + toString(a));
        for (oracle::AuditCause a : oracle::spuriousCauses()) v.push_back(std::string("spurious_") + toString(a));
        return v;
    }();
    return all;
}

bool isTimingColumn(const std::string& name) {
    return name.size() > 3 && name.compare(name.size() - 3, 3, "_ms") == 0;
}

std::string csvHeader() {
    std::string s;
    for (const std::string& c : columns()) s += (s.empty() ? "" : ",") + c;
    return s + "\n";
}

std::string csvRow(const nlohmann::ordered_json& record) {
    std::string s;
    bool first = true;
    for (const std::string& c : columns()) {
        s += first ? "" : ",";
        first = false;
        if (record.contains(c)) s += csvField(record[c]);
    }
    return s + "\n";
}

OutputPaths outputPaths(const std::filesystem::path& path) {
    OutputPaths p;
    const std::string ext = path.extension().string();
    if (ext != ".csv" && ext != ".jsonl")
        throw InputError(path.string(), "a study output ends in .csv or .jsonl (both are written)");
    p.csv = std::filesystem::path(path).replace_extension(".csv");
    p.jsonl = std::filesystem::path(path).replace_extension(".jsonl");
    return p;
}

std::vector<nlohmann::ordered_json> readRecords(const std::filesystem::path& path) {
    const OutputPaths p = outputPaths(path);
    // A record is a few KiB; a line of more is no record of ours (and is skipped, as cut lines are).
    constexpr JsonLimits kRecordJson{.kind = "a study record", .maxBytes = uint64_t(16) << 20};
    const std::string text = readFile(p.jsonl, kMaxInputFileBytes, "a study output");
    const std::string source = p.jsonl.string();
    std::vector<nlohmann::ordered_json> out;
    for (size_t begin = 0; begin < text.size();) {
        const size_t newline = text.find('\n', begin), end = newline == std::string::npos ? text.size() : newline;
        const std::string_view line(text.data() + begin, end - begin);
        begin = end + 1;
        if (newline == std::string::npos && !line.empty() && line.back() != '}') break;  // cut by a killed run
        try {
            nlohmann::ordered_json j = parseOrderedJson(line, source, kRecordJson);
            if (j.is_object() && j.contains("id") && j["id"].is_string()) out.push_back(std::move(j));
        } catch (const InputError&) {}
    }
    return out;
}

namespace {

// Both files or neither. The JSON lines first: when they cannot be written, nothing has changed;
// when the CSV then cannot be, JSON lines this call created go again (rewritten ones stay: they
// hold the records they held).
void writeAll(const OutputPaths& p, const std::vector<nlohmann::ordered_json>& records) {
    std::string csv = csvHeader(), jsonl;
    for (const auto& r : records) csv += csvRow(r), jsonl += r.dump() + "\n";
    std::error_code ec;
    const bool jsonlWasThere = std::filesystem::exists(p.jsonl, ec);
    writeFileAtomically(p.jsonl, jsonl);
    try {
        writeFileAtomically(p.csv, csv);
    } catch (const InputError&) {
        if (!jsonlWasThere) std::filesystem::remove(p.jsonl, ec);
        throw;
    }
}

// A record appended to one output: its write checked, so a full disk stops the study by name
// instead of losing records unnoticed.
void append(std::ofstream& out, const std::filesystem::path& path, const std::string& line) {
    out << line << std::flush;
    if (!out) throw InputError(path.string(), std::string("cannot write: ") + std::strerror(errno));
}

}  // namespace

namespace {

// The scene's near contacts into a record (null: not counted; the columns stay empty).
void addNear(nlohmann::ordered_json& r, const NearMeasure* near) {
    r["near_distance"] = near ? nlohmann::ordered_json(near->distance) : nullptr;
    r["near_contacts"] = near ? nlohmann::ordered_json(near->contacts.total()) : nullptr;
    r["near_contacts_self"] = near ? nlohmann::ordered_json(near->contacts.selfPairs) : nullptr;
}

}  // namespace

size_t runStudy(const StudyOptions& opt) {
    const OutputPaths paths = outputPaths(opt.out);
    const std::vector<RunConfig> mine = slice(expand(opt.spec), opt.shard);

    // Resume: keep the complete records already there (rewritten, so a cut line is healed).
    std::vector<nlohmann::ordered_json> records;
    std::set<std::string> done;
    if (std::filesystem::exists(paths.jsonl)) {
        records = readRecords(paths.jsonl);
        for (const auto& r : records) done.insert(r["id"].get<std::string>());
    }
    writeAll(paths, records);
    std::vector<RunConfig> todo;
    for (const RunConfig& c : mine)
        if (!done.count(c.id())) todo.push_back(c);

    std::ofstream csv(paths.csv, std::ios::app), jsonl(paths.jsonl, std::ios::app);
    for (const auto& [stream, path] : {std::pair{&csv, paths.csv}, std::pair{&jsonl, paths.jsonl}})
        if (!*stream) throw InputError(path.string(), std::string("cannot append: ") + std::strerror(errno));

    std::string sceneKey;
    Scene scene;
    std::unique_ptr<oracle::Truth> truth;
    NearMeasure near;
    std::string diagonalScene;  // the scene whose first frame's diagonal `diagonal` is
    double diagonal = 0;
    std::map<std::pair<std::string, int>, std::unique_ptr<DepthBackend>> backends;
    PairRuns pairRuns;
    Progress bar("study", todo.size(), "runs", opt.progress);
    for (size_t i = 0; i < todo.size(); ++i) {
        const RunConfig& c = todo[i];
        const std::string key = c.scene + "@" + std::to_string(c.frame);
        if (key != sceneKey) {  // the sweep is scene-major: one scene and one oracle at a time
            // Loading a large scene and its oracle can take a while: say so.
            if (bar.shown()) bar.update(i, key + (opt.spec.oracle ? ": scene and oracle" : ": scene"));
            scene = loadStudyScene(c.scene, c.frame);
            truth.reset();
            if (opt.spec.oracle) truth = std::make_unique<oracle::Truth>(oracle::findIntersections(scene));
            // One near distance and one tolerance for every frame of a scene: fractions of its first
            // frame's diagonal, found once per scene (its frames come in a row).
            if (truth && c.scene != diagonalScene)
                diagonal = sceneDiagonal(c.frame == 0 ? scene : loadStudyScene(c.scene, 0)), diagonalScene = c.scene;
            if (truth && opt.spec.nearDistance > 0) near = measureNear(scene, *truth, opt.spec.nearDistance * diagonal);
            sceneKey = key;
        }
        nlohmann::ordered_json r;
        if (methodFamily(c.method, opt.spec.names.method) == MethodFamily::ImageSpace) {
            auto& backend = backends[{c.backend, c.threads}];
            if (!backend) backend = raster::makeBackend(c.backend, c.threads);
            r = runOne(c, scene, truth.get(), opt.spec.repeats, *backend);
        } else {
            r = pairRuns.run(c, scene, truth.get(), opt.spec.tolerance * diagonal, opt.spec.repeats);
        }
        addNear(r, truth && opt.spec.nearDistance > 0 ? &near : nullptr);
        if (!opt.command.empty()) r["command"] = opt.command;
        append(csv, paths.csv, csvRow(r));
        append(jsonl, paths.jsonl, r.dump() + "\n");
        if (opt.onRecord) {
            const Progress::Pause pause = bar.pause();  // its lines on stdout
            opt.onRecord(r);
        }
        bar.update(i + 1);
    }
    bar.finish();
    return todo.size();
}

size_t mergeOutputs(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& out) {
    std::map<std::string, nlohmann::ordered_json> byId;
    for (const auto& in : inputs)
        for (auto& r : readRecords(in)) byId.emplace(r["id"].get<std::string>(), std::move(r));
    std::vector<nlohmann::ordered_json> records;
    for (auto& [id, r] : byId) records.push_back(std::move(r));
    std::stable_sort(records.begin(), records.end(), [](const auto& a, const auto& b) {
        return a["index"].template get<size_t>() < b["index"].template get<size_t>();
    });
    writeAll(outputPaths(out), records);
    return records.size();
}

}  // namespace cullide::study
