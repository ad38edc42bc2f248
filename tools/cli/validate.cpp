// `cullide validate SCENE [--backend gl|vulkan]`: the same Cullide workload on the CPU reference and
// on a GPU backend (GL by default, or Vulkan), every query compared: record a trace on the
// reference (with the intervals [certain, certain + ambiguous] of cullide/raster/validate.h),
// replay it on the GPU backend, compare (docs/trace-format.md, docs/gl-backend.md,
// docs/vulkan-backend.md) - `trace record`, `trace replay --backend gl|vulkan` and `trace compare`
// in one process - and then the final PCS of Cullide run on that backend against the reference's.
// Exit status 1 when any query falls outside its interval.
#include "commands.h"
#include "trace.h"

#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/options.h"
#include "cullide/provenance.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/trace.h"
#include "cullide/scene_io.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace cullide::cli {
namespace {

struct ValidateOptions {
    std::string scene;
    OptionText cullide;  // method, resolution, depth, directions, hierarchy (cullide/options.h)
    long frame = -1;
    std::string png, json, trace;
    std::string backend = "gl";
    size_t worst = 10;
    double depthLsb = 2.0;
    ProgressMode progress = ProgressMode::Auto;
};

// The recorded trace: kept at --trace, or a scratch file removed when validation ends.
struct ScratchTrace {
    std::string path;
    bool keep = false;
    ~ScratchTrace() {
        std::error_code ec;
        if (!keep && !path.empty()) std::filesystem::remove(path, ec);
    }
};

int runValidate(const ValidateOptions& o) {
    CullideOptions options = parseCullideOptions(o.cullide);
    const Animation animation = loadScene(o.scene);
    const auto [first, last] = selectFrames(animation, o.frame, o.scene);

    const std::unique_ptr<raster::GpuBackend> gpu = raster::makeGpuBackend(o.backend);
    // "GL" or "Vulkan" in messages; the backend's name ("gl", "vulkan") in the PCS lines and keys.
    const std::string api = o.backend == "gl" ? "GL" : "Vulkan", name = gpu->apiName();
    const DepthFormat effective = gpu->effectiveFormat(options.depth);
    if (!(effective == options.depth)) {
        std::fprintf(stderr, "cullide: warning: %s has no %s; both backends use %s\n", api.c_str(),
                     options.depth.name().c_str(), effective.name().c_str());
        options.depth = effective;
    }
    // The reference configured like the GPU backend: its subpixel bits (llvmpipe and lavapipe: 8)
    // and llvmpipe's bottom-left fill rule (lavapipe's too, as framebuffer rows are GL's window
    // rows: docs/vulkan-backend.md); the intervals allow for the backend's own subpixel bits.
    raster::TraceRules rules;
    rules.subpixelBits = std::clamp(gpu->subpixelBits(), raster::kMinSubpixelBits, raster::kMaxSubpixelBits);
    rules.fillRule = raster::FillRule::BottomLeft;
    rules.otherSubpixelBits = std::max(1, gpu->subpixelBits());
    rules.depthLsb = o.depthLsb;

    std::printf(
        "%s: %s, %dx%d, %s, %zu direction(s)\n  reference: cpu reference (%d subpixel bits, %s)\n"
        "  other:     %s\n",
        o.scene.c_str(), toString(options.method), options.width, options.height, options.depth.name().c_str(),
        options.directions.size(), rules.subpixelBits, raster::toString(rules.fillRule), gpu->describe().c_str());

    // 1. Record on the reference.
    ScratchTrace scratch;
    scratch.keep = !o.trace.empty();
    scratch.path = scratch.keep
        ? o.trace
        : (std::filesystem::temp_directory_path() / ("cullide-validate-" + std::to_string(::getpid()) + ".trace"))
              .string();
    // One bar per stage, each left on its own line: record, replay, the final PCS.
    std::optional<Progress> bar;
    bar.emplace("validate: record", last - first, "frames", o.progress);
    const Recording recording =
        recordTrace(animation, first, last, options, rules, 0, scratch.path, workloadJson(o.scene, options), &*bar);
    bar->finish();
    const raster::TraceReader trace(scratch.path);
    if (scratch.keep) std::printf("trace: %s (%.2f MB)\n", scratch.path.c_str(), double(recording.bytes) / 1e6);

    // 2. Replay on the GPU backend; 3. compare.
    raster::TraceResults results;
    results.backend = gpu->describe();
    bar.emplace("validate: replay", trace.listCount(), "command lists", o.progress);
    std::function<void(size_t, size_t)> onList;  // empty when hidden: the replay as it was
    if (bar->shown()) onList = [&bar](size_t done, size_t) { bar->update(done); };
    results.results = raster::replayTrace(trace, *gpu, onList);
    bar->finish();
    const raster::TraceComparison comparison = raster::compareTrace(trace, results, name + " results");
    nlohmann::ordered_json report = reportComparison(trace, comparison, results.backend, o.worst,
                                                     toJson(provenance(0, {gpu->describe()})), "replayed on " + api);
    std::printf("reference self-check: %llu of %llu reference counts outside their own intervals\n",
                (unsigned long long)recording.referenceOutside, (unsigned long long)recording.queries);

    // 4. The PCS of Cullide run on the GPU backend itself, against the reference's.
    size_t pcsDiffering = 0;
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    std::string stage = "validate: ";  // built stepwise: GCC 12's -Wrestrict on "..." + std::string
    stage += name;
    stage += " PCS";
    bar.emplace(stage, last - first, "frames", o.progress);
    // Coherent directions: the GPU run learns from its own frames, as the recording did from its;
    // each frame builds its hierarchies, as the recording did.
    PruneSettings gpuSettings;
    gpuSettings.cullide = options;
    gpuSettings.reuseHierarchies = false;
    Pruner gpuPruner(gpuSettings, *gpu, last - first);
    for (size_t f = first; f < last; ++f) {
        const std::vector<PcsTriangle>& ref = recording.pcs[f - first];
        const CullideResult oth = gpuPruner.prune(animation.sceneAt(f)).cull;
        bar->update(f - first + 1);
        const Progress::Pause pause(&*bar);  // the frame's line on stdout
        std::vector<PcsTriangle> onlyRef, onlyGl;
        std::set_difference(ref.begin(), ref.end(), oth.pcs.begin(), oth.pcs.end(), std::back_inserter(onlyRef));
        std::set_difference(oth.pcs.begin(), oth.pcs.end(), ref.begin(), ref.end(), std::back_inserter(onlyGl));
        const bool same = onlyRef.empty() && onlyGl.empty();
        std::printf("frame %zu: PCS reference %zu, %s %zu triangles; %s (%zu only in the reference, %zu only in %s)\n",
                    f, ref.size(), name.c_str(), oth.pcs.size(), same ? "identical" : "DIFFERENT", onlyRef.size(),
                    onlyGl.size(), name.c_str());
        pcsDiffering += same ? 0 : 1;
        frames.push_back({{"frame", f},
                          {"pcs_reference", ref.size()},
                          {"pcs_" + name, oth.pcs.size()},
                          {"only_reference", onlyRef.size()},
                          {"only_" + name, onlyGl.size()}});
    }
    bar->finish();
    std::printf("frames with a different final PCS: %zu of %zu\n", pcsDiffering, last - first);

    if (!o.png.empty()) {
        const size_t n =
            writeComparisonPictures(trace, comparison, raster::worstQueries(comparison.queries, o.worst), o.png);
        std::printf(
            "wrote %zu picture(s) to %s (white: certain, green: ambiguous and passing in the reference, "
            "yellow: ambiguous, red: reference outside its own interval)\n",
            n, o.png.c_str());
    }
    if (!o.json.empty()) {
        report["scene"] = o.scene;
        report["workload"] = workloadJson(o.scene, options);
        report["reference_outside_own_interval"] = recording.referenceOutside;
        report["pcs"] = frames;
        report["frames_with_different_pcs"] = pcsDiffering;
        if (scratch.keep) report["trace"] = scratch.path;
        else report.erase("trace");
        writeFileAtomically(o.json, report.dump(1) + "\n");
    }
    return comparison.passed() ? 0 : 1;
}

}  // namespace

void addValidateCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<ValidateOptions>();
    CLI::App* sub = app.add_subcommand(
        "validate", "Run the same Cullide workload on the CPU reference and on GL or Vulkan and compare every query");
    sub->add_option("scene", o->scene, "Scene file (.json) or mesh")->required();
    addCullideOptions(sub, o->cullide);
    sub->add_option("--backend", o->backend,
                    "The backend validated: gl (OpenGL 4.5 through headless EGL) | vulkan (Vulkan 1.1+, headless)")
        ->check(CLI::IsMember(raster::gpuBackendNames()))
        ->capture_default_str();
    addNumber(sub, "--frame", o->frame, "Validate only this frame (default: every frame)", 0L, std::numeric_limits<long>::max());
    sub->add_option("--png", o->png, "Write difference pictures of the worst queries' coverage into this folder");
    sub->add_option("--json", o->json,
                    "Write the verdict (rates, per frame and depth format, worst queries, PCS) as JSON");
    sub->add_option("--trace", o->trace, "Keep the recorded trace in this file (replayable with `cullide trace`)");
    addNumber(sub, "--worst", o->worst, "How many worst queries to list")->capture_default_str();
    addNumber(sub, "--depth-margin", o->depthLsb,
              "Constant depth margin of the intervals, in LSB (unorm) or 2^-24 (float)", 0.0, 1e6)
        ->capture_default_str();
    addProgressOption(sub, o->progress);
    sub->callback([o, sub, &action] {
        checkCullideOptions(sub, o->cullide);
        action = [o] { return runValidate(*o); };
    });
}

}  // namespace cullide::cli
