// `cullide validate SCENE`: the same Cullide workload on the CPU reference and on GL, every query
// compared: exact agreement, and whether GL's count lies in the interval [certain, certain +
// ambiguous] the reference computes (cullide/raster/validate.h, docs/gl-backend.md). Exit status 1
// when any query falls outside its interval.
#include "commands.h"

#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/options.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gl_backend.h"
#include "cullide/raster/png.h"
#include "cullide/raster/validate.h"
#include "cullide/scene_io.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>

namespace cullide::cli {
namespace {

struct ValidateOptions {
    std::string scene;
    OptionText cullide;  // method, resolution, depth, directions (cullide/options.h)
    long frame = -1;
    std::string png;
    size_t worst = 10;
    double depthLsb = 2.0;
};

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

int runValidate(const ValidateOptions& o) {
    CullideOptions options = parseCullideOptions(o.cullide);

    const Animation animation = loadScene(o.scene);
    const auto [first, last] = selectFrames(animation, o.frame, o.scene);

    const std::unique_ptr<raster::GlBackend> gl = raster::makeGlBackend();
    const DepthFormat effective = gl->effectiveFormat(options.depth);
    if (!(effective == options.depth)) {
        std::fprintf(stderr, "cullide: warning: GL has no %s; both backends use %s\n", options.depth.name().c_str(),
                     effective.name().c_str());
        options.depth = effective;
    }
    // The reference configured like the GL: its subpixel bits (llvmpipe: 8) and llvmpipe's
    // bottom-left fill rule.
    raster::CpuBackendOptions cpuOptions;
    cpuOptions.subpixelBits = std::clamp(gl->info().subpixelBits, raster::kMinSubpixelBits, raster::kMaxSubpixelBits);
    const std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend(cpuOptions);
    raster::IntervalOptions iv;
    iv.subpixelBits = cpuOptions.subpixelBits;
    iv.fillRule = cpuOptions.fillRule;
    iv.otherSubpixelBits = std::max(1, gl->info().subpixelBits);
    iv.depthLsb = o.depthLsb;

    std::printf("%s: %s, %dx%d, %s, %zu direction(s)\n  reference: %s\n  other:     %s\n", o.scene.c_str(),
                toString(options.method), options.width, options.height, options.depth.name().c_str(),
                options.directions.size(), cpu->describe().c_str(), gl->describe().c_str());

    raster::TeeBackend tee(*cpu, *gl, iv);
    size_t pcsDiffering = 0;
    for (size_t f = first; f < last; ++f) {
        const Scene scene = animation.sceneAt(f);
        tee.setFrame(uint32_t(f));
        const CullideResult ref = runCullide(scene, tee, options);
        const CullideResult oth = runCullide(scene, *gl, options);
        std::vector<PcsTriangle> onlyRef, onlyGl;
        std::set_difference(ref.pcs.begin(), ref.pcs.end(), oth.pcs.begin(), oth.pcs.end(),
                            std::back_inserter(onlyRef));
        std::set_difference(oth.pcs.begin(), oth.pcs.end(), ref.pcs.begin(), ref.pcs.end(), std::back_inserter(onlyGl));
        std::printf("frame %zu: PCS reference %zu, gl %zu triangles; %s (%zu only in the reference, %zu only in gl)\n",
                    f, ref.pcs.size(), oth.pcs.size(), onlyRef.empty() && onlyGl.empty() ? "identical" : "DIFFERENT",
                    onlyRef.size(), onlyGl.size());
        if (!onlyRef.empty() || !onlyGl.empty()) ++pcsDiffering;
    }

    const auto& all = tee.comparisons();
    size_t exact = 0, inside = 0, ambiguous = 0;
    uint64_t width = 0;
    for (const raster::QueryComparison& c : all) {
        exact += c.exact() ? 1 : 0;
        inside += c.inInterval() ? 1 : 0;
        ambiguous += c.interval.possible > c.interval.certain ? 1 : 0;
        width += c.interval.possible - c.interval.certain;
    }
    const double n = double(std::max<size_t>(all.size(), 1));
    std::printf("queries: %zu; exact %zu (%.4f%%), in interval %zu (%.4f%%), outside %zu\n", all.size(), exact,
                100.0 * double(exact) / n, inside, 100.0 * double(inside) / n, all.size() - inside);
    std::printf("intervals: %zu queries with ambiguous fragments (%.2f%%), mean width %.2f fragments\n", ambiguous,
                100.0 * double(ambiguous) / n, double(width) / n);
    std::printf(
        "reference self-check (the interval code's exact track vs the CPU backend): %llu of %llu queries "
        "differ\n",
        (unsigned long long)tee.selfCheckMismatches(), (unsigned long long)tee.selfCheckedQueries());
    std::printf("frames with a different final PCS: %zu of %zu\n", pcsDiffering, last - first);

    // The worst queries: outside the interval first (by distance), then by |gl - reference|.
    std::vector<size_t> order;
    for (size_t i = 0; i < all.size(); ++i)
        if (!all[i].exact() || !all[i].inInterval()) order.push_back(i);
    auto diff = [](const raster::QueryComparison& c) {
        return c.other > c.reference ? c.other - c.reference : c.reference - c.other;
    };
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (all[a].outside() != all[b].outside()) return all[a].outside() > all[b].outside();
        return diff(all[a]) > diff(all[b]);
    });
    order.resize(std::min(order.size(), o.worst));
    if (!order.empty()) std::printf("worst queries (frame/list/query kind: reference gl [certain, possible]):\n");
    for (size_t i : order) {
        const raster::QueryComparison& c = all[i];
        std::printf("  %u/%u/%u %s: %llu %llu [%llu, %llu]%s\n", c.frame, c.list, c.query,
                    c.kind == QueryKind::SamplesPassed ? "samples" : "any", (unsigned long long)c.reference,
                    (unsigned long long)c.other, (unsigned long long)c.interval.certain,
                    (unsigned long long)c.interval.possible, c.inInterval() ? "" : "  OUTSIDE");
    }

    if (!o.png.empty() && !order.empty()) {
        // Replay the reference side (deterministic: same lists) capturing the worst queries.
        std::error_code ec;
        std::filesystem::create_directories(o.png, ec);
        if (ec) throw InputError(o.png, "cannot create the folder: " + ec.message());
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> wanted;
        for (size_t i : order) wanted[{all[i].frame, all[i].list}] = all[i].query;  // one per list
        const std::unique_ptr<raster::CpuBackend> cpu2 = raster::makeCpuBackend(cpuOptions);
        raster::TeeBackend replay(*cpu2, *gl, iv);
        replay.onCapture = [&](uint32_t f, uint32_t l) -> int64_t {
            const auto it = wanted.find({f, l});
            return it == wanted.end() ? -1 : int64_t(it->second);
        };
        size_t written = 0;
        replay.captured = [&](const raster::QueryComparison& c, const raster::CoverageCapture& cap,
                              const OrthoView& view) {
            char name[96];
            std::snprintf(name, sizeof name, "query_f%u_l%u_q%u.png", c.frame, c.list, c.query);
            writeQueryPng(cap, view, std::filesystem::path(o.png) / name);
            ++written;
        };
        for (size_t f = first; f < last; ++f) {
            replay.setFrame(uint32_t(f));
            runCullide(animation.sceneAt(f), replay, options);
        }
        std::printf(
            "wrote %zu picture(s) to %s (white: certain, green: ambiguous and passing in the reference, "
            "yellow: ambiguous, red: reference outside its own interval)\n",
            written, o.png.c_str());
    }
    return inside == all.size() ? 0 : 1;
}

}  // namespace

void addValidateCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<ValidateOptions>();
    CLI::App* sub = app.add_subcommand(
        "validate", "Run the same Cullide workload on the CPU reference and on GL and compare every query");
    sub->add_option("scene", o->scene, "Scene file (.json) or mesh")->required();
    sub->add_option("--method", o->cullide.method, "original | modified")->capture_default_str();
    sub->add_option("--resolution", o->cullide.resolution, "Viewport: N or WxH pixels")->capture_default_str();
    sub->add_option("--depth", o->cullide.depth, "Depth format: unorm bits (mapped to GL's D16/D24/D32) or float")
        ->capture_default_str();
    sub->add_option("--directions", o->cullide.directions, "View directions: 'axes', a count N, or a list")
        ->capture_default_str();
    sub->add_option("--frame", o->frame, "Validate only this frame (default: every frame)")
        ->check(CLI::NonNegativeNumber);
    sub->add_option("--png", o->png, "Write difference pictures of the worst queries' coverage into this folder");
    sub->add_option("--worst", o->worst, "How many worst queries to list")->capture_default_str();
    sub->add_option("--depth-margin", o->depthLsb,
                    "Constant depth margin of the intervals, in LSB (unorm) or 2^-24 (float)")
        ->check(CLI::Range(0.0, 1e6))
        ->capture_default_str();
    sub->callback([o, &action] { action = [o] { return runValidate(*o); }; });
}

}  // namespace cullide::cli
