// `cullide prune SCENE`: the potentially colliding set of every frame of a scene, by Cullide or
// the seed paper's self-intersection variant, with per-pass statistics.
#include "commands.h"
#include "oracle.h"
#include "pictures.h"

#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/mesh_io.h"
#include "cullide/parallel.h"
#include "cullide/options.h"
#include "cullide/provenance.h"
#include "cullide/raster/backends.h"
#include "cullide/scene_io.h"
#include "cullide/study/study.h"

#include <nlohmann/json.hpp>
#include <oneapi/tbb/task_arena.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

namespace cullide::cli {
namespace {

// The smallest --max-viewport. Every tile draws the call's whole list again, every triangle set
// up each time, so a call costs about as many whole draws as it has tiles: below 64 pixels a
// 500x500 call has thousands and the bundled scenes take minutes. No GPU's limit is near it
// (Vulkan guarantees 4096 pixels).
constexpr int kMinMaxViewport = 64;

struct PruneOptions {
    std::string scene;
    OptionText cullide;  // method, resolution, depth, directions, hierarchy (cullide/options.h)
    std::string backend = "cpu";
    int threads = 0;
    int maxViewport = 0;  // > 0: draw as a backend with this largest viewport side would (tiles)
    long frame = -1;  // -1: every frame
    std::string json, out;
    std::string frames;  // folder for the Figure 12 pictures
    bool check = false, exact = false;  // against the exact oracle (oracle.h)
    bool rebuildHierarchy = false;  // build every frame's hierarchies, as the paper does
    ProgressMode progress = ProgressMode::Auto;
};

// The scene at one frame as one mesh, PCS triangles green and the rest grey (Figures 6 and 7).
void writePcsPly(const Scene& scene, const std::vector<PcsTriangle>& pcs, const std::string& path) {
    const FlatScene all = flatten(scene);
    std::vector<Rgb8> colours(all.mesh.triangles.size(), Rgb8{170, 170, 170});
    for (const PcsTriangle& p : pcs) colours[all.triangle(p.object, p.triangle)] = Rgb8{40, 200, 40};
    PlyWriteOptions w;
    w.faceColours = colours;
    writePly(all.mesh, path, w);
}

// The run's one line: the method and every option that shapes the PCS, and the backend.
void printRunLine(const PruneOptions& o, const CullideOptions& options, const DepthBackend& backend) {
    char viewport[80];
    if (options.autoCoverage > 0)
        std::snprintf(viewport, sizeof viewport, "auto:%g (at least %dx%d)", options.autoCoverage, options.width,
                      options.height);
    else std::snprintf(viewport, sizeof viewport, "%dx%d", options.width, options.height);
    // Chosen directions: pca chooses six per level; coherent chooses among the fixed list.
    char directions[64];
    if (options.directionMode == DirectionMode::Pca) std::snprintf(directions, sizeof directions, "pca directions");
    else
        std::snprintf(directions, sizeof directions, "%s%zu direction(s)",
                      options.directionMode == DirectionMode::Coherent ? "coherent over " : "",
                      options.directions.size());
    // The switch is named only when set: a default run prints what it always printed.
    std::string exactSwitch;
    if (options.exactSwitch.kind != ExactSwitchKind::Never) exactSwitch = ", exact switch " + o.cullide.exactSwitch;
    std::printf("%s: %s, %s, %s, %s, %s hierarchy (leaf %u, branching %u)%s, %s\n", o.scene.c_str(),
                toString(options.method), viewport, options.depth.name().c_str(), directions,
                toString(options.hierarchy.kind), options.hierarchy.leafSize, options.hierarchy.branching,
                exactSwitch.c_str(), backend.describe().c_str());
}

// A frame's lines: the PCS and the work that made it, and where the loop switched to exact.
void printFrameLines(size_t f, const CullideResult& r, size_t total, size_t objectCount, const CullideOptions& options) {
    size_t rendered = 0, queries = 0;
    for (const PassStats& p : r.passes) rendered += p.trianglesRendered, queries += p.queries;
    std::map<uint32_t, size_t> perObject;
    for (const PcsTriangle& p : r.pcs) ++perObject[p.object];
    std::printf(
        "frame %zu: PCS %zu of %zu triangles (%.2f%%) in %zu object(s); %u level(s), %zu reducePCS calls, "
        "%zu triangles rendered, %zu queries; hierarchy %.1f ms%s, total %.1f ms\n",
        f, r.pcs.size(), total, total ? 100.0 * double(r.pcs.size()) / double(total) : 0.0, perObject.size(), r.levels,
        r.passes.size(), rendered, queries, 1e3 * r.hierarchySeconds,
        r.hierarchiesReused == 0                 ? ""
            : r.hierarchiesReused == objectCount ? " (reused)"
                                                 : " (some reused)",
        1e3 * r.totalSeconds);
    if (r.switchedAtLevel >= 0 && options.exactSwitch.kind == ExactSwitchKind::Auto)
        std::printf(
            "  switched to exact at level %d with %zu PCS triangles (predicted: next level %.2f ms, "
            "exact stage %.2f ms)\n",
            r.switchedAtLevel, r.switchedAtTriangles, 1e3 * r.predictedLevelSeconds, 1e3 * r.predictedExactSeconds);
    else if (r.switchedAtLevel >= 0)
        std::printf("  switched to exact at level %d with %zu PCS triangles\n", r.switchedAtLevel,
                    r.switchedAtTriangles);
}

// A frame's entry of --json's "frames".
nlohmann::ordered_json frameJson(size_t f, size_t total, const CullideResult& r, const CullideOptions& options) {
    nlohmann::ordered_json pcs = nlohmann::ordered_json::array();
    for (const PcsTriangle& p : r.pcs) pcs.push_back({p.object, p.triangle});
    nlohmann::ordered_json passes = nlohmann::ordered_json::array();
    for (const PassStats& p : r.passes) passes.push_back(study::passJson(p, options));
    nlohmann::ordered_json j = {{"frame", f},
                                {"triangles", total},
                                {"pcs", pcs},
                                {"passes", passes},
                                {"levels", r.levels},
                                {"hierarchy_seconds", r.hierarchySeconds},
                                {"hierarchies_reused", r.hierarchiesReused},
                                {"total_seconds", r.totalSeconds}};
    if (options.exactSwitch.kind != ExactSwitchKind::Never)
        j["switched_at_level"] =
            r.switchedAtLevel >= 0 ? nlohmann::ordered_json(r.switchedAtLevel) : nlohmann::ordered_json();
    return j;
}

// The whole --json document: the options, the objects' names, the frames, the provenance.
nlohmann::ordered_json runJson(const PruneOptions& o, const CullideOptions& options, const DepthBackend& backend,
                               nlohmann::ordered_json objectNames, nlohmann::ordered_json frames) {
    nlohmann::ordered_json j = {{"scene", o.scene},
                                {"options",
                                 {{"method", toString(options.method)},
                                  {"width", options.width},
                                  {"height", options.height},
                                  {"depth", options.depth.name()},
                                  {"directions", nlohmann::ordered_json::array()},
                                  {"hierarchy", toString(options.hierarchy.kind)},
                                  {"leaf_size", options.hierarchy.leafSize},
                                  {"branching", options.hierarchy.branching},
                                  {"backend", backend.describe()}}},
                                {"objects", std::move(objectNames)},
                                {"frames", std::move(frames)}};
    for (const Vec3d& d : options.directions) j["options"]["directions"].push_back({d.x(), d.y(), d.z()});
    // Adaptive resolution: width x height is the smallest viewport; each pass has its own.
    if (options.autoCoverage > 0) j["options"]["auto_coverage"] = options.autoCoverage;
    // Clustered views (absent for fit): each pass records its views.
    if (options.views != ViewMode::Fit) j["options"]["views"] = toString(options.views);
    // Chosen directions: "directions" is the fixed list (coherent's, or the axes pca falls back
    // to); each pass records its own direction_vector.
    if (options.directionMode != DirectionMode::Fixed) j["options"]["direction_mode"] = toString(options.directionMode);
    if (options.exactSwitch.kind != ExactSwitchKind::Never) j["options"]["exact_switch"] = o.cullide.exactSwitch;
    // The GL and Vulkan backends' descriptions name their driver; the CPU reference rasterizer has none.
    std::vector<std::string> drivers;
    if (o.backend != "cpu") drivers.push_back(backend.describe());
    j["provenance"] = toJson(provenance(o.threads, drivers));
    return j;
}

// --frames: the paper's Figure 12, the PCS before and after each reducePCS call of frame `f`,
// from a fixed three-quarter view. Writes the first picture (everything) and returns the hook
// that writes one per call.
FrameHooks pictureHooks(const std::string& folder, const Scene& scene, size_t f,
                        std::unique_ptr<PcsPictures>& pictures) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) throw InputError(folder, "cannot create the folder: " + ec.message());
    pictures = std::make_unique<PcsPictures>(scene, Vec3d(-0.4, -0.5, -0.77), 512, 512);
    auto nameOf = [f](int pass) {
        char name[64];
        std::snprintf(name, sizeof name, "frame%04zu_pass%03d.png", f, pass);
        return std::filesystem::path(name);
    };
    std::vector<PcsTriangle> everything;
    for (uint32_t i = 0; i < scene.objects.size(); ++i)
        for (uint32_t t = 0; t < scene.objects[i].mesh.triangleCount(); ++t) everything.push_back({i, t});
    pictures->write(everything, std::filesystem::path(folder) / nameOf(0));
    FrameHooks hooks;
    hooks.onPass = [&pictures, folder, nameOf, pass = 0](const PassStats&, std::span<const PcsTriangle> pcs) mutable {
        pictures->write(pcs, std::filesystem::path(folder) / nameOf(++pass));
    };
    return hooks;
}

// The whole command in one process: every selected frame through one Pruner (pruner.h), each
// frame's lines, checks and outputs as it is done.
int runPruneFrames(const PruneOptions& o) {
    const CullideOptions options = parseCullideOptions(o.cullide);
    const std::unique_ptr<DepthBackend> made = raster::makeBackend(o.backend, o.threads);
    // --max-viewport: the backend as one with that limit would look; larger calls are drawn in tiles.
    std::unique_ptr<raster::ViewportLimit> limited;
    if (o.maxViewport > 0) limited = std::make_unique<raster::ViewportLimit>(*made, o.maxViewport);
    DepthBackend* const backend = limited ? static_cast<DepthBackend*>(limited.get()) : made.get();

    Animation animation = loadScene(o.scene);
    const auto [first, last] = selectFrames(animation, o.frame, o.scene);
    if (!o.out.empty() && o.frame < 0 && animation.frameCount() > 1)
        throw InputError("option --out",
                         "the scene has " + std::to_string(animation.frameCount()) +
                             " frames; choose one with --frame to write its PLY");
    printRunLine(o, options, *backend);

    PruneSettings settings;
    settings.cullide = options;
    settings.exactStage = o.exact;
    settings.reuseHierarchies = !o.rebuildHierarchy;
    Pruner pruner(settings, *backend, last - first);
    nlohmann::ordered_json objectNames = nlohmann::ordered_json::array();  // before a still scene moves
    for (const Object& obj : animation.scene.objects) objectNames.push_back(obj.name);
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    bool guaranteeBroken = false;  // --check found a false prune the method promises not to make
    Progress bar("prune", last - first, "frames", o.progress);
    for (size_t f = first; f < last; ++f) {
        const size_t done = f - first;
        std::string frameName = "frame ";  // built stepwise: GCC 12's -Wrestrict on "..." + std::string
        frameName += std::to_string(f);
        bar.update(done, frameName);
        // A still scene pruned once is moved, not copied, out of the file's (peak memory).
        Scene scene = last - first == 1 && animation.frames.empty() ? std::move(animation.scene) : animation.sceneAt(f);
        const size_t total = scene.triangleCount(), objectCount = scene.objects.size();
        // Within a frame, per reducePCS call: a large scene's frame can take minutes.
        FrameHooks hooks = passProgress(bar, frameName, done, options.directions.size());
        std::unique_ptr<PcsPictures> pictures;
        if (!o.frames.empty()) hooks.onPass = pictureHooks(o.frames, scene, f, pictures).onPass;
        // Given up to the run (emptied once uploaded) unless something below reads it.
        const bool sceneNeeded = o.check || !o.out.empty() || pictures;
        const FramePrune r = sceneNeeded ? pruner.prune(scene, hooks) : pruner.prune(std::move(scene), hooks);
        std::optional<Progress::Pause> pause;  // the lines below go to stdout
        pause.emplace(&bar);
        printFrameLines(f, r.cull, total, objectCount, options);
        if (!o.json.empty()) frames.push_back(frameJson(f, total, r.cull, options));
        if (o.check || o.exact) {
            pause.reset();
            if (o.check) bar.update(done, frameName + ": oracle check");
            pause.emplace(&bar);  // checkPcs prints its lines
            const PcsCheck c = checkPcs(scene, r.cull.pcs, options, o.check, r.exact ? &*r.exact : nullptr);
            guaranteeBroken = guaranteeBroken || c.guaranteeBroken;
            if (!o.json.empty()) frames.back().update(c.json);
            if (o.exact) {
                std::printf("  time to exact pairs: %.1f ms (prune %.1f + exact stage %.1f)\n",
                            1e3 * r.timeToExactSeconds(), 1e3 * r.cull.totalSeconds, 1e3 * r.exactSeconds());
                if (!o.json.empty()) {
                    frames.back()["exact_seconds"] = r.exactSeconds();
                    frames.back()["time_to_exact_pairs_seconds"] = r.timeToExactSeconds();
                }
            }
        }
        if (!o.out.empty()) writePcsPly(scene, r.cull.pcs, o.out);
        pause.reset();
        bar.update(done + 1);
    }
    bar.finish();
    if (!o.json.empty())
        writeFileAtomically(o.json, runJson(o, options, *backend, std::move(objectNames), std::move(frames)).dump(1) + "\n");
    return guaranteeBroken ? 1 : 0;
}

// --threads N: the whole run on N worker threads (the hierarchies, the view fits, the oracle of
// --check, and the CPU backend's own N), as the study runs each of its runs; before, only the
// backend was limited and `--threads 1` built the hierarchies on every core. The results are the
// same for any N.
int runPrune(const PruneOptions& o) {
    if (o.threads <= 0) return runPruneFrames(o);
    tbb::task_arena arena(o.threads);
    return executeIn(arena, [&] { return runPruneFrames(o); });
}

}  // namespace

void addPruneCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<PruneOptions>();
    CLI::App* sub =
        app.add_subcommand("prune", "Compute the potentially colliding set (PCS) of every frame of a scene");
    sub->add_option("scene", o->scene, "Scene file (.json) or mesh")->required();
    addCullideOptions(sub, o->cullide);
    sub->add_option(
           "--backend", o->backend,
           "cpu (the reference rasterizer) | gl (OpenGL 4.5 through headless EGL) | vulkan (Vulkan 1.1+, headless)")
        ->check(CLI::IsMember(raster::backendNames()))
        ->capture_default_str();
    addThreadsOption(sub, o->threads, "Worker threads of the whole run: hierarchies, view fits, the CPU backend");
    addNumber(sub, "--max-viewport", o->maxViewport,
              "Draw as a backend whose largest viewport side is N pixels: calls larger than that in tiles, "
              "the same PCS (" +
                  std::to_string(kMinMaxViewport) + ".." + std::to_string(kMaxViewportSide) +
                  ": each tile draws every triangle again; docs/cullide.md#adaptive-resolution)",
              kMinMaxViewport, kMaxViewportSide);
    addNumber(sub, "--frame", o->frame, "Prune only this frame (default: every frame)", 0L, std::numeric_limits<long>::max());
    sub->add_option("--json", o->json, "Write the PCS ([object, triangle] pairs), per-pass stats and times as JSON");
    sub->add_option("--out", o->out, "Write the frame as PLY with PCS triangles coloured green");
    sub->add_option("--frames", o->frames,
                    "Write PNG pictures of the PCS before and after each reducePCS call into this folder "
                    "(frameFFFF_passPPP.png; the paper's Figure 12)");
    sub->add_flag("--check", o->check,
                  "Measure the PCS against the exact oracle: false prunes by class, false positives, efficiency "
                  "(exit status 1 on a false prune the method promises not to make)");
    sub->add_flag("--rebuild-hierarchy", o->rebuildHierarchy,
                  "Build every frame's hierarchies, as the paper does (default: an object whose triangles are "
                  "unchanged since the last frame keeps its hierarchy; the PCS is the same either way)");
    sub->add_flag("--exact", o->exact,
                  "Run the exact stage on the PCS: the final intersecting pairs of the pipeline, and the time to them");
    sub->add_option("--exact-switch", o->cullide.exactSwitch,
                    "Stop image-space pruning early and leave the rest to the exact stage: never | auto (when the "
                    "next level is predicted to cost more than the exact stage on the PCS) | N (when the PCS holds "
                    "fewer than N triangles); docs/cullide.md#switch-to-exact")
        ->capture_default_str();
    addProgressOption(sub, o->progress);
    sub->callback([o, sub, &action] {
        checkCullideOptions(sub, o->cullide);
        if (sub->count("--threads") && o->backend != "cpu")
            throw CLI::ValidationError("--threads", "applies to --backend cpu only");
        action = [o] { return runPrune(*o); };
    });
}

}  // namespace cullide::cli
