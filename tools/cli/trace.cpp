// `cullide trace record | replay | compare | info`: the reference made reachable by any backend
// (docs/trace-format.md). record writes the command lists of a prune run with the CPU
// reference's answers; replay runs a trace on a backend and writes its answers; compare judges
// answers against the trace's intervals (exit 0 when every query lies in its interval, 1 when
// one does not, 2 on bad input).
#include "trace.h"

#include "commands.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/options.h"
#include "cullide/provenance.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gpu_backend.h"
#include "cullide/raster/png.h"
#include "cullide/scene_io.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace cullide::cli {

using Json = nlohmann::ordered_json;

Json workloadJson(const std::string& scene, const CullideOptions& options) {
    Json directions = Json::array();
    for (const Vec3d& d : options.directions) directions.push_back({d.x(), d.y(), d.z()});
    Json j = {{"scene", scene},
              {"method", toString(options.method)},
              {"resolution", {options.width, options.height}},
              {"depth", options.depth.name()},
              {"directions", directions},
              {"hierarchy", toString(options.hierarchy.kind)},
              {"leaf_size", options.hierarchy.leafSize},
              {"branching", options.hierarchy.branching}};
    if (options.autoCoverage > 0) j["auto_coverage"] = options.autoCoverage;  // each list's view has its own size
    // Clustered views: a call is one list per group drawn, each with its own view.
    if (options.views != ViewMode::Fit) j["views"] = toString(options.views);
    // Chosen directions: each list's view has its own direction (recorded with the list).
    if (options.directionMode != DirectionMode::Fixed) j["direction_mode"] = toString(options.directionMode);
    return j;
}

Recording recordTrace(const Animation& animation, size_t first, size_t last, const CullideOptions& options,
                      const raster::TraceRules& rules, int threads, const std::string& path, const Json& workload,
                      Progress* bar) {
    if (options.method == CullMethod::Reliable)
        throw InputError("option --method",
                         "the reliable method's conservative commands have no GL or Vulkan counterpart; trace the "
                         "original or the modified method");
    raster::CpuBackendOptions cpuOptions;
    cpuOptions.subpixelBits = rules.subpixelBits;
    cpuOptions.fillRule = rules.fillRule;
    cpuOptions.threads = threads;
    const std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend(cpuOptions);
    // No date: the same input and options give the same bytes.
    raster::TraceWriter writer(path, rules, workload, toJson(provenance(threads, {}, false)));
    raster::TraceRecorder recorder(*cpu, writer, rules, threads);
    Recording out;
    const bool shown = bar && bar->shown();
    // Coherent directions learn from frame to frame, as in prune; each frame builds its hierarchies.
    PruneSettings settings;
    settings.cullide = options;
    settings.reuseHierarchies = false;
    Pruner pruner(settings, recorder, last - first);
    for (size_t f = first; f < last; ++f) {
        std::string frameName = "frame ";
        frameName += std::to_string(f);
        if (shown) bar->update(f - first, frameName);
        // Within a frame, per reducePCS call (nothing else changes).
        const FrameHooks hooks = bar ? passProgress(*bar, frameName, f - first, options.directions.size()) : FrameHooks{};
        recorder.setFrame(uint32_t(f));
        out.pcs.push_back(pruner.prune(animation.sceneAt(f), hooks).cull.pcs);
        if (shown) {
            frameName += ": intervals";
            bar->update(f - first, frameName);
        }
        recorder.endFrame();
        if (shown) bar->update(f - first + 1);
    }
    out.bytes = recorder.finish();
    out.queries = recorder.queries();
    out.referenceOutside = recorder.referenceOutside();
    return out;
}

namespace {

std::string percent(uint64_t part, uint64_t whole) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4f%%", whole ? 100.0 * double(part) / double(whole) : 100.0);
    return buf;
}

Json ratesJson(const raster::TraceComparison::Rates& r) {
    return {{"queries", r.queries},
            {"exact", r.exact},
            {"in_interval", r.inside},
            {"outside", r.queries - r.inside},
            {"exact_rate", r.queries ? double(r.exact) / double(r.queries) : 1.0},
            {"in_interval_rate", r.queries ? double(r.inside) / double(r.queries) : 1.0}};
}

std::string drawsText(const std::vector<std::pair<uint32_t, uint32_t>>& draws) {
    std::string s;
    for (size_t i = 0; i < draws.size() && i < 4; ++i)
        s += (i ? ", " : "") + std::string("[") + std::to_string(draws[i].first) + ", " +
            std::to_string(uint64_t(draws[i].first) + draws[i].second) + ")";
    if (draws.size() > 4) s += ", ... (" + std::to_string(draws.size()) + " draws)";
    return s.empty() ? "no draws" : "triangles " + s;
}

// Difference picture of one query (reference side): white = certainly passes, green = ambiguous
// and passes in the reference, yellow = ambiguous, red = passes in the reference but outside the
// possible set (a bug), black = nothing.
void writeQueryPng(const raster::CoverageCapture& c, const OrthoView& view, const std::filesystem::path& path) {
    std::vector<uint8_t> rgb(size_t(view.width) * size_t(view.height) * 3, 0);
    for (size_t i = 0; i < c.classes.size(); ++i) {
        const uint8_t k = c.classes[i];
        uint8_t r = 0, g = 0, b = 0;
        if (k & 1) r = g = b = 255;
        else if ((k & 2) && (k & 4)) g = 200;
        else if (k & 2) r = g = 220;
        else if (k & 4) r = 255;
        rgb[3 * i] = r, rgb[3 * i + 1] = g, rgb[3 * i + 2] = b;
    }
    raster::writeRgbPng(view.width, view.height, rgb, path);
}

}  // namespace

Json reportComparison(const raster::TraceReader& trace, const raster::TraceComparison& c, const std::string& backend,
                      size_t worst, Json provenance, const std::string& title) {
    const auto& all = c.all;
    std::printf("%s: %zu frame(s), %zu command list(s)\n  backend: %s\n", title.c_str(), trace.frameCount(),
                trace.listCount(), backend.c_str());
    std::printf("queries: %llu; exact %llu (%s), in interval %llu (%s), outside %llu\n",
                (unsigned long long)all.queries, (unsigned long long)all.exact, percent(all.exact, all.queries).c_str(),
                (unsigned long long)all.inside, percent(all.inside, all.queries).c_str(),
                (unsigned long long)(all.queries - all.inside));
    uint64_t ambiguous = 0, width = 0;
    for (const raster::QueryComparison& q : c.queries) {
        ambiguous += q.interval.possible > q.interval.certain ? 1 : 0;
        width += q.interval.possible - q.interval.certain;
    }
    const double n = double(std::max<uint64_t>(all.queries, 1));
    std::printf("intervals: %llu queries with ambiguous fragments (%.2f%%), mean width %.2f fragments\n",
                (unsigned long long)ambiguous, 100.0 * double(ambiguous) / n, double(width) / n);
    Json perFrame = Json::array(), perFormat = Json::array();
    for (const auto& [frame, r] : c.perFrame) {
        if (c.perFrame.size() > 1)
            std::printf("  frame %u: %llu queries, exact %s, in interval %s\n", frame, (unsigned long long)r.queries,
                        percent(r.exact, r.queries).c_str(), percent(r.inside, r.queries).c_str());
        Json j = {{"frame", frame}};
        j.update(ratesJson(r));
        perFrame.push_back(j);
    }
    for (const auto& [format, r] : c.perFormat) {
        if (c.perFormat.size() > 1)
            std::printf("  %s: %llu queries, exact %s, in interval %s\n", format.c_str(), (unsigned long long)r.queries,
                        percent(r.exact, r.queries).c_str(), percent(r.inside, r.queries).c_str());
        Json j = {{"depth", format}};
        j.update(ratesJson(r));
        perFormat.push_back(j);
    }

    const std::vector<size_t> order = raster::worstQueries(c.queries, worst);
    if (!order.empty()) std::printf("worst queries (reference, other [certain, possible]):\n");
    Json worstJson = Json::array();
    for (size_t i : order) {
        const raster::QueryComparison& q = c.queries[i];
        const raster::TraceList list = trace.readList(q.list);
        const auto draws = raster::queryDraws(list.commands, q.query);
        std::printf("  list %u query %u (frame %u, %s, %s): %llu, %llu [%llu, %llu]%s; %s\n", q.list, q.query, q.frame,
                    q.kind == QueryKind::SamplesPassed ? "samples" : "any samples", list.view.depth.name().c_str(),
                    (unsigned long long)q.reference, (unsigned long long)q.other,
                    (unsigned long long)q.interval.certain, (unsigned long long)q.interval.possible,
                    q.inInterval() ? "" : ("  OUTSIDE by " + std::to_string(q.outside())).c_str(),
                    drawsText(draws).c_str());
        Json d = Json::array();
        for (const auto& [first, count] : draws) d.push_back({first, count});
        worstJson.push_back({{"list", q.list},
                             {"query", q.query},
                             {"frame", q.frame},
                             {"kind", q.kind == QueryKind::SamplesPassed ? "samples" : "any_samples"},
                             {"depth", list.view.depth.name()},
                             {"reference", q.reference},
                             {"other", q.other},
                             {"certain", q.interval.certain},
                             {"possible", q.interval.possible},
                             {"outside", q.outside()},
                             {"draws", d}});
    }
    Json j = {{"provenance", std::move(provenance)}, {"trace", trace.path()}, {"backend", backend}};
    j.update(ratesJson(all));
    j["passed"] = c.passed();
    j["ambiguous_queries"] = ambiguous;
    j["mean_interval_width"] = double(width) / n;
    j["per_frame"] = perFrame;
    j["per_depth_format"] = perFormat;
    j["worst"] = worstJson;
    return j;
}

size_t writeComparisonPictures(const raster::TraceReader& trace, const raster::TraceComparison& c,
                               const std::vector<size_t>& worst, const std::string& folder) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) throw InputError(folder, "cannot create the folder: " + ec.message());
    std::map<size_t, uint32_t> wanted;  // list -> query, one per list
    for (size_t i : worst) wanted.emplace(c.queries[i].list, c.queries[i].query);
    size_t written = 0;
    raster::captureTraceQueries(
        trace, wanted, [&](const raster::TraceList& list, uint32_t q, const raster::CoverageCapture& cap) {
            char name[96];
            std::snprintf(name, sizeof name, "query_f%u_l%zu_q%u.png", list.frame, list.index, q);
            writeQueryPng(cap, list.view, std::filesystem::path(folder) / name);
            ++written;
        });
    return written;
}

namespace {

struct RecordOptions {
    std::string scene, out;
    OptionText cullide;
    int threads = 0;
    long frame = -1;
    raster::TraceRules rules;
    ProgressMode progress = ProgressMode::Auto;
};

int runRecord(const RecordOptions& o) {
    preferSmallFootprint();  // its peak memory is a promise (commands.h)
    const CullideOptions options = parseCullideOptions(o.cullide);
    const Animation animation = loadScene(o.scene);
    const auto [first, last] = selectFrames(animation, o.frame, o.scene);
    const auto start = std::chrono::steady_clock::now();
    Progress bar("trace record", last - first, "frames", o.progress);
    const Recording r =
        recordTrace(animation, first, last, options, o.rules, o.threads, o.out, workloadJson(o.scene, options), &bar);
    bar.finish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const raster::TraceReader trace(o.out);
    const Json& s = trace.header()["summary"];
    std::printf(
        "%s: %zu frame(s), %llu command list(s), %llu commands, %llu queries, %llu triangles drawn; "
        "%.2f MB in %.2f s\n",
        o.out.c_str(), trace.frameCount(), (unsigned long long)s["lists"].get<uint64_t>(),
        (unsigned long long)s["commands"].get<uint64_t>(), (unsigned long long)s["queries"].get<uint64_t>(),
        (unsigned long long)s["triangles_drawn"].get<uint64_t>(), double(r.bytes) / 1e6, seconds);
    if (r.referenceOutside > 0) {
        std::fprintf(stderr,
                     "cullide: warning: %llu of %llu reference counts lie outside their own intervals (a bug in "
                     "the reference or the intervals; please report it)\n",
                     (unsigned long long)r.referenceOutside, (unsigned long long)r.queries);
        return 1;
    }
    return 0;
}

struct ReplayOptions {
    std::string trace, backend = "cpu", out;
    int threads = 0;
    ProgressMode progress = ProgressMode::Auto;
};

int runReplay(const ReplayOptions& o) {
    preferSmallFootprint();  // its peak memory is a promise (commands.h)
    const raster::TraceReader trace(o.trace);
    std::unique_ptr<DepthBackend> backend;
    std::vector<std::string> drivers;
    if (o.backend == "cpu") {
        // The reference under the trace's own rules: its answers are the trace's.
        raster::CpuBackendOptions cpu;
        cpu.subpixelBits = trace.rules().subpixelBits;
        cpu.fillRule = trace.rules().fillRule;
        cpu.threads = o.threads;
        backend = raster::makeCpuBackend(cpu);
    } else {
        backend = raster::makeBackend(o.backend, o.threads);
        drivers.push_back(backend->describe());
        if (const auto* gpu = dynamic_cast<const raster::GpuBackend*>(backend.get());
            gpu && gpu->subpixelBits() < trace.rules().otherSubpixelBits)
            std::fprintf(stderr,
                         "cullide: warning: the %s backend has %d subpixel bits; the trace's intervals allow for %d or "
                         "more (record with --other-subpixel-bits %d)\n",
                         gpu->apiName().c_str(), gpu->subpixelBits(), trace.rules().otherSubpixelBits,
                         gpu->subpixelBits());
    }
    const auto start = std::chrono::steady_clock::now();
    raster::TraceResults results;
    results.backend = backend->describe();
    {
        Progress bar("trace replay", trace.listCount(), "command lists", o.progress);
        std::function<void(size_t, size_t)> onList;  // empty when hidden: the replay as it was
        if (bar.shown()) onList = [&bar](size_t done, size_t) { bar.update(done); };
        results.results = raster::replayTrace(trace, *backend, onList);
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    raster::writeTraceResults(o.out, results, o.trace, toJson(provenance(o.threads, drivers)));
    size_t queries = 0;
    for (const auto& l : results.results) queries += l.size();
    std::printf("%s: replayed %zu command list(s), %zu queries on %s in %.2f s; wrote %s\n", o.trace.c_str(),
                results.results.size(), queries, results.backend.c_str(), seconds, o.out.c_str());
    return 0;
}

struct CompareOptions {
    std::string trace, results, json, png;
    size_t worst = 10;
};

int runCompare(const CompareOptions& o) {
    const raster::TraceReader trace(o.trace);
    const raster::TraceResults results = raster::readTraceResults(o.results);
    const raster::TraceComparison c = raster::compareTrace(trace, results, o.results);
    Json j = reportComparison(trace, c, results.backend, o.worst, toJson(provenance(0)), o.trace);
    j["results"] = o.results;
    if (!o.png.empty()) {
        const size_t n = writeComparisonPictures(trace, c, raster::worstQueries(c.queries, o.worst), o.png);
        std::printf(
            "wrote %zu picture(s) to %s (white: certain, green: ambiguous and passing in the reference, "
            "yellow: ambiguous, red: reference outside its own interval)\n",
            n, o.png.c_str());
    }
    if (!o.json.empty()) writeFileAtomically(o.json, j.dump(1) + "\n");
    std::printf("%s\n", c.passed() ? "every query lies in its interval" : "FAILED: queries outside their interval");
    return c.passed() ? 0 : 1;
}

struct InfoOptions {
    std::string trace;
};

int runInfo(const InfoOptions& o) {
    const raster::TraceReader trace(o.trace);
    // Every list read, so that a trace that passes `info` is a trace every command can use.
    std::map<std::string, size_t> formats;
    size_t queries = 0;
    for (size_t l = 0; l < trace.listCount(); ++l) {
        const raster::TraceList list = trace.readList(l);
        ++formats[list.view.depth.name() + " " + std::to_string(list.view.width) + "x" +
                  std::to_string(list.view.height)];
        queries += list.queries.size();
    }
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    for (size_t f = 0; f < trace.frameCount(); ++f) trace.readGeometry(f, positions, triangles);
    const Json& h = trace.header();
    std::printf("%s: cullide trace version %d (%llu bytes), recorded by cullide %s\n", o.trace.c_str(),
                raster::kTraceFormatVersion, (unsigned long long)trace.fileBytes(),
                h.value("cullide_version", std::string("unknown")).c_str());
    std::printf("  %zu frame(s), %zu command list(s), %zu queries\n", trace.frameCount(), trace.listCount(), queries);
    for (const auto& [name, n] : formats) std::printf("  %zu list(s) at %s\n", n, name.c_str());
    std::printf("  rules: %s\n  workload: %s\n", h["rules"].dump().c_str(),
                h.contains("workload") ? h["workload"].dump().c_str() : "{}");
    return 0;
}

}  // namespace

void addTraceRuleOptions(CLI::App* sub, raster::TraceRules& rules) {
    addNumber(sub, "--subpixel-bits", rules.subpixelBits, "The reference's subpixel bits", raster::kMinSubpixelBits,
              raster::kMaxSubpixelBits)
        ->capture_default_str();
    addNumber(sub, "--other-subpixel-bits", rules.otherSubpixelBits,
              "Subpixel bits the intervals allow the replaying implementation (GL requires >= 4)", 1, 24)
        ->capture_default_str();
    addNumber(sub, "--depth-margin", rules.depthLsb,
              "Constant depth margin of the intervals, in LSB (unorm) or 2^-24 (float)", 0.0, 1e6)
        ->capture_default_str();
}

void addTraceCommand(CLI::App& app, Action& action) {
    CLI::App* trace = app.add_subcommand(
        "trace", "Record a run's command lists with the reference's answers, replay them on a backend, compare");
    trace->require_subcommand(1);

    auto r = std::make_shared<RecordOptions>();
    CLI::App* rec = trace->add_subcommand(
        "record", "Record the command lists a prune run issues, with the CPU reference's answers and intervals");
    rec->add_option("scene", r->scene, "Scene file (.json) or mesh")->required();
    rec->add_option("-o,--out", r->out, "The trace file to write")->required();
    addCullideOptions(rec, r->cullide);
    addThreadsOption(rec, r->threads);
    addNumber(rec, "--frame", r->frame, "Record only this frame (default: every frame)", 0L, std::numeric_limits<long>::max());
    addTraceRuleOptions(rec, r->rules);
    addProgressOption(rec, r->progress);
    rec->callback([r, rec, &action] {
        checkCullideOptions(rec, r->cullide);
        action = [r] { return runRecord(*r); };
    });

    auto p = std::make_shared<ReplayOptions>();
    CLI::App* rep =
        trace->add_subcommand("replay", "Execute a trace's command lists on a backend and write its answers");
    rep->add_option("trace", p->trace, "The trace file")->required();
    rep->add_option("--backend", p->backend,
                    "cpu (the reference, under the trace's rules) | gl (OpenGL 4.5 through headless EGL) | vulkan "
                    "(Vulkan 1.1+, headless)")
        ->check(CLI::IsMember(raster::backendNames()))
        ->capture_default_str();
    rep->add_option("-o,--out", p->out, "The results file to write (JSON)")->required();
    addThreadsOption(rep, p->threads, "Worker threads of the CPU backend");
    addProgressOption(rep, p->progress);
    rep->callback([p, rep, &action] {
        if (rep->count("--threads") && p->backend != "cpu")
            throw CLI::ValidationError("--threads", "applies to --backend cpu only");
        action = [p] { return runReplay(*p); };
    });

    auto c = std::make_shared<CompareOptions>();
    CLI::App* cmp = trace->add_subcommand(
        "compare",
        "Judge a results file against a trace: exact, in interval or outside, per query (exit 1 if outside)");
    cmp->add_option("trace", c->trace, "The trace file")->required();
    cmp->add_option("results", c->results, "The results file (JSON: {\"backend\", \"results\"})")->required();
    cmp->add_option("--json", c->json, "Write the verdict as JSON");
    cmp->add_option("--png", c->png, "Write difference pictures of the worst queries' coverage into this folder");
    addNumber(cmp, "--worst", c->worst, "How many worst queries to list")->capture_default_str();
    cmp->callback([c, &action] { action = [c] { return runCompare(*c); }; });

    auto i = std::make_shared<InfoOptions>();
    CLI::App* inf = trace->add_subcommand("info", "Check a trace completely and summarize it");
    inf->add_option("trace", i->trace, "The trace file")->required();
    inf->callback([i, &action] { action = [i] { return runInfo(*i); }; });
}

}  // namespace cullide::cli
