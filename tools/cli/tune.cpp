// `cullide tune SCENE`: the cheapest configuration of Cullide that meets an accuracy target on a
// scene (false prunes from the oracle at most K; optionally a time budget), by a staged search
// over the candidate values of each option, run through the study engine (cullide/study/study.h).
//
// The search (docs/cullide.md#tune): coordinate descent from the default configuration. Each
// stage is one study over one axis' candidates, the other axes at the current choice; the stage
// keeps the best value (among those meeting the target, the fastest; if none does, the fewest false
// prunes, then the fastest). Rounds over all axes repeat until a round changes nothing (at most
// kMaxRounds). The full product (3 x 6 x 3 x 2 x 3 x 2 = 648 runs) is too dear; a round costs the
// sum of the axes' sizes (19 runs), and a repeated configuration runs once (the study resumes by
// run id). The time of a configuration is the time to exact pairs: the median prune plus the
// median exact stage on its PCS, summed over the scene's frames.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/parse_number.h"
#include "cullide/pipeline/progress.h"
#include "cullide/study/study.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace cullide::cli {
namespace {

// One searched option: its column name, prune's option, the candidates (the default among them).
// Adding a candidate value is one word in `values`; adding an axis, one entry (with its setter
// and getter).
// The descent visits the axes in this order.
struct TuneAxis {
    const char* name;
    const char* option;
    std::vector<std::string> values;
    std::string defaultValue;
    void (*set)(study::Spec&, const std::vector<std::string>&);
    std::string (*get)(const study::RunConfig&);  // a run's value of this axis
};

const std::vector<TuneAxis>& tuneAxes() {
    static const std::vector<TuneAxis> axes = {
        // First: the switch decides how much the image side must get right, so it changes which
        // choices of the others meet the target (at never only reliable keeps every pair).
        {"exact_switch",
         "--exact-switch",
         {"never", "auto"},
         "never",
         [](study::Spec& s, const std::vector<std::string>& v) { s.exactSwitches = v; },
         [](const study::RunConfig& rc) { return std::string(rc.exactSwitch); }},
        {"method",
         "--method",
         {"original", "modified", "reliable"},
         "modified",
         [](study::Spec& s, const std::vector<std::string>& v) { s.methods = v; },
         [](const study::RunConfig& rc) { return std::string(rc.method); }},
        {"resolution",
         "--resolution",
         {"250", "500", "1000", "2000", "auto", "auto:4"},
         "500",
         [](study::Spec& s, const std::vector<std::string>& v) { s.resolutions = v; },
         [](const study::RunConfig& rc) { return std::string(rc.resolution); }},
        {"depth",
         "--depth",
         {"16", "24", "float"},
         "24",
         [](study::Spec& s, const std::vector<std::string>& v) { s.depths = v; },
         [](const study::RunConfig& rc) { return std::string(rc.depth); }},
        {"directions",
         "--directions",
         // coherent is left out: a study runs each frame alone, where it is the axes' full list.
         {"axes", "14", "pca"},
         "axes",
         [](study::Spec& s, const std::vector<std::string>& v) { s.directions = v; },
         [](const study::RunConfig& rc) { return std::string(rc.directions); }},
        {"views",
         "--views",
         {"fit", "clustered"},
         "fit",
         [](study::Spec& s, const std::vector<std::string>& v) { s.views = v; },
         [](const study::RunConfig& rc) { return std::string(rc.views); }},
        {"leaf_size",
         "--leaf-size",
         {"8", "16", "32"},
         "16",
         [](study::Spec& s, const std::vector<std::string>& v) {
             s.leafSizes.clear();
             for (const std::string& x : v) s.leafSizes.push_back(parseNumber(x, "option --leaf-size", 1u, kMaxLeafSize));
         },
         [](const study::RunConfig& rc) { return std::to_string(rc.leafSize); }},
    };
    return axes;
}

constexpr int kMaxRounds = 3;

struct TuneOptions {
    std::string scene;
    long maxFalsePrunes = 0;
    double budgetMs = 0;  // 0: none
    int threads = 0;
    int repeats = 3;
    std::string out;  // empty: a temporary study output, removed at the end
    ProgressMode progress = ProgressMode::Auto;
};

using Choice = std::vector<std::string>;  // one value per axis, in tuneAxes() order

struct Measured {
    double timeMs = 0, pruneMs = 0, exactMs = 0;
    size_t falsePrunes = 0, pcs = 0;
};

class Tuner {
public:
    Tuner(const TuneOptions& o, std::filesystem::path out) : o_(o), out_(std::move(out)) {}

    // The study spec of `base` with axis `a` over `values`.
    study::Spec spec(const Choice& base, size_t a, const std::vector<std::string>& values) const {
        study::Spec s;
        s.scenes = {o_.scene};
        s.threads = {o_.threads};
        s.repeats = o_.repeats;
        s.oracle = true;
        const auto& axes = tuneAxes();
        for (size_t k = 0; k < axes.size(); ++k) axes[k].set(s, k == a ? values : std::vector<std::string>{base[k]});
        return s;
    }

    // Measures every choice of `base` with axis `a` over its candidates (runs only the new ones).
    std::vector<std::pair<Choice, Measured>> stage(const Choice& base, size_t a, Progress& bar,
                                                   const std::string& what) {
        const TuneAxis& axis = tuneAxes()[a];
        study::StudyOptions so;
        so.spec = spec(base, a, axis.values);
        so.out = out_;
        so.progress = ProgressMode::Never;  // the tune's bar is the one drawn
        size_t runs = 0;
        so.onRecord = [&](const nlohmann::ordered_json&) {
            bar.update(++done_, what + ": " + std::to_string(++runs) + " run(s)");
        };
        bar.update(done_, what);
        study::runStudy(so);
        std::map<std::string, nlohmann::ordered_json> byId;
        for (auto& r : study::readRecords(out_)) {
            const std::string id = r["id"].get<std::string>();  // before the move (operator= takes by value)
            byId[id] = std::move(r);
        }
        std::vector<std::pair<Choice, Measured>> out;
        const std::vector<study::RunConfig> configs = study::expand(so.spec);
        for (const std::string& value : axis.values) {
            Choice c = base;
            c[a] = value;
            Measured m;
            for (const study::RunConfig& rc : configs) {
                if (!matches(rc, a, value)) continue;
                const auto it = byId.find(rc.id());
                if (it == byId.end() || it->second["time_to_exact_ms"].is_null())
                    throw InputError(out_.string(),
                                     "a study record is missing or has no exact stage (run id " + rc.id() +
                                         "); remove the file and tune again");
                const nlohmann::ordered_json& r = it->second;
                m.timeMs += r["time_to_exact_ms"].get<double>();
                m.pruneMs += r["time_ms"].get<double>();
                m.exactMs += r["exact_ms"].get<double>();
                m.falsePrunes += r["false_prunes"].get<size_t>();
                m.pcs += r["pcs"].get<size_t>();
            }
            measured_[c] = m;
            out.push_back({c, m});
        }
        return out;
    }

    bool meets(const Measured& m) const {
        return m.falsePrunes <= size_t(o_.maxFalsePrunes) && (o_.budgetMs <= 0 || m.timeMs <= o_.budgetMs);
    }
    // Whether `a` is a better choice than `b`: meeting the target first, then fewer false prunes
    // (when neither meets it), then faster.
    bool better(const Measured& a, const Measured& b) const {
        if (meets(a) != meets(b)) return meets(a);
        if (!meets(a) && a.falsePrunes != b.falsePrunes) return a.falsePrunes < b.falsePrunes;
        return a.timeMs < b.timeMs;
    }

    const std::map<Choice, Measured>& measured() const { return measured_; }
    size_t done() const { return done_; }

private:
    // Whether run `rc` is the stage's run of `value` on axis `a` (any frame).
    static bool matches(const study::RunConfig& rc, size_t a, const std::string& value) {
        return tuneAxes()[a].get(rc) == value;
    }

    const TuneOptions& o_;
    std::filesystem::path out_;
    std::map<Choice, Measured> measured_;
    size_t done_ = 0;
};

std::string pad(const std::string& s, size_t width) {
    return s.size() >= width ? s : s + std::string(width - s.size(), ' ');
}

std::string shellQuote(const std::string& s) {
    if (!s.empty() &&
        s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./:@,+=") ==
            std::string::npos)
        return s;
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// prune's command line for a choice: the scene (FILE@K as --frame K), every searched option.
std::string pruneCommand(const std::string& scene, const Choice& c) {
    std::string file = scene, frame;
    const size_t at = scene.rfind('@');
    if (at != std::string::npos) {
        file = scene.substr(0, at);
        if (scene.substr(at + 1) != "all") frame = scene.substr(at + 1);
    }
    std::string cmd = "cullide prune " + shellQuote(file);
    if (!frame.empty()) cmd += " --frame " + frame;
    const auto& axes = tuneAxes();
    for (size_t k = 0; k < axes.size(); ++k) cmd += std::string(" ") + axes[k].option + " " + shellQuote(c[k]);
    return cmd + " --exact";
}

int runTune(const TuneOptions& o) {
    if (o.scene.empty()) throw InputError("tune", "no scene");
    (void)study::studyFrameCount(o.scene);  // a missing or bad file: InputError naming it, before anything runs
    std::filesystem::path out = o.out;
    const bool temporary = out.empty();
    if (temporary)
        out = std::filesystem::temp_directory_path() / ("cullide_tune_" + std::to_string(::getpid()) + ".csv");
    else (void)study::outputPaths(out);  // .csv or .jsonl, else InputError naming it
    struct Cleanup {
        bool on;
        study::OutputPaths p;
        ~Cleanup() {
            if (!on) return;
            std::error_code ec;
            std::filesystem::remove(p.csv, ec);
            std::filesystem::remove(p.jsonl, ec);
        }
    } cleanup{temporary, study::outputPaths(out)};

    const auto& axes = tuneAxes();
    Choice current;
    size_t perRound = 0;
    for (const TuneAxis& a : axes) current.push_back(a.defaultValue), perRound += a.values.size();
    Tuner tuner(o, out);
    // The bar counts runs against a round's worth per round (later rounds mostly reuse runs).
    Progress bar("tune", perRound * kMaxRounds, "runs", o.progress);
    for (int round = 0; round < kMaxRounds; ++round) {
        bool changed = false;
        for (size_t a = 0; a < axes.size(); ++a) {
            const std::string what = "round " + std::to_string(round + 1) + ", " + axes[a].name;
            const auto results = tuner.stage(current, a, bar, what);
            const Measured* best = &tuner.measured().at(current);
            Choice choice = current;
            for (const auto& [c, m] : results)
                if (tuner.better(m, *best)) best = &tuner.measured().at(c), choice = c;
            if (choice != current) current = choice, changed = true;
        }
        if (!changed) break;
    }
    bar.update(perRound * kMaxRounds);
    bar.finish();

    // The Pareto front of every configuration measured: time to exact pairs against false prunes.
    std::vector<std::pair<Choice, Measured>> all(tuner.measured().begin(), tuner.measured().end());
    std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
        return a.second.timeMs != b.second.timeMs ? a.second.timeMs < b.second.timeMs
                                                  : a.second.falsePrunes < b.second.falsePrunes;
    });
    std::vector<std::pair<Choice, Measured>> front;
    for (const auto& e : all)
        if (front.empty() || e.second.falsePrunes < front.back().second.falsePrunes) front.push_back(e);
    std::printf("tune %s: %zu configuration(s) measured; Pareto front (time to exact pairs vs false prunes):\n",
                o.scene.c_str(), all.size());
    std::string header = " ";
    for (const TuneAxis& a : axes) header.append(" ").append(pad(a.name, 12));
    std::printf("%s %10s %10s %10s %12s %10s\n", header.c_str(), "time_ms", "prune_ms", "exact_ms", "false_prunes",
                "pcs");
    for (const auto& [c, m] : front) {
        std::string row = " ";
        for (const std::string& v : c) row.append(" ").append(pad(v, 12));
        std::printf("%s %10.2f %10.2f %10.2f %12zu %10zu\n", row.c_str(), m.timeMs, m.pruneMs, m.exactMs, m.falsePrunes,
                    m.pcs);
    }
    const std::pair<Choice, Measured>* best = nullptr;
    for (const auto& e : all)
        if (tuner.meets(e.second)) {
            best = &e;
            break;
        }
    std::string target = "at most " + std::to_string(o.maxFalsePrunes) + " false prune(s)";
    if (o.budgetMs > 0) {
        char b[64];
        std::snprintf(b, sizeof b, " in at most %g ms", o.budgetMs);
        target += b;
    }
    if (!best) {
        std::fprintf(stderr,
                     "cullide: tune: no configuration measured meets the target (%s); the front above shows what "
                     "can be had\n",
                     target.c_str());
        return 1;
    }
    std::printf("cheapest meeting the target (%s): %.2f ms to exact pairs, %zu false prune(s)\n", target.c_str(),
                best->second.timeMs, best->second.falsePrunes);
    std::printf("recommended: %s\n", pruneCommand(o.scene, best->first).c_str());
    return 0;
}

}  // namespace

void addTuneCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<TuneOptions>();
    CLI::App* sub = app.add_subcommand(
        "tune",
        "Search method, resolution, depth, directions, views, leaf size and exact switch for the cheapest configuration "
        "that meets an accuracy target on a scene (docs/cullide.md#tune)");
    sub->add_option("scene", o->scene, "Scene file (FILE@K: frame K) or a study scene (bunny:N, cows:N, ...)")
        ->required();
    addNumber(sub, "--max-false-prunes", o->maxFalsePrunes,
              "Accuracy target: false prunes (triangles, from the exact oracle) at most K", 0L, 1'000'000'000L)
        ->capture_default_str();
    addNumber(sub, "--budget-ms", o->budgetMs, "Time budget: time to exact pairs at most T ms (default: none)", 1e-6,
              1e9);
    addThreadsOption(sub, o->threads);
    addNumber(sub, "--repeats", o->repeats, "Timed runs per configuration (median)", 1, 1000)->capture_default_str();
    sub->add_option("-o,--out", o->out,
                    "Keep the runs as a study output (.csv; .jsonl beside it); a second tune resumes from it");
    addProgressOption(sub, o->progress);
    sub->callback([o, &action] { action = [o] { return runTune(*o); }; });
}

}  // namespace cullide::cli
