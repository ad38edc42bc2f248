// What every subcommand shares (common.h).
#include "common.h"

#include <cstdio>

namespace cullide::cli {

void addCullideOptions(CLI::App* sub, OptionText& o) {
    sub->add_option("--method", o.method,
                    "original (Cullide: between objects; contacts only where both cover a pixel centre) | modified "
                    "(self-intersections kept, contacts lost) | reliable (no "
                    "intersecting triangle is ever pruned; CPU backend only; docs/reliable.md)")
        ->capture_default_str();
    sub->add_option("--resolution", o.resolution,
                    "Viewport: N or WxH pixels (1 to " + std::to_string(kMaxViewportSide) +
                        " per side), or auto / auto:K: per reducePCS call, pixels sized so that the PCS covers about K "
                        "500x500 viewports (default 1; docs/cullide.md#adaptive-resolution)")
        ->capture_default_str();
    sub->add_option("--depth", o.depth, "Depth format: unorm bits 8..32 (e.g. 24, d16) or float")
        ->capture_default_str();
    sub->add_option(
           "--directions", o.directions,
           "View directions: 'axes' (+x -x +y -y +z -z), a count N (spread), a list 'x,-y,z' / '1 0 0;0 1 1', "
           "'pca' (per level, the PCS's principal orientations) or 'coherent' / 'coherent:LIST' (across frames, the "
           "directions that pruned in the last frame; docs/cullide.md#chosen-directions)")
        ->capture_default_str();
    sub->add_option("--hierarchy", o.hierarchy, "connectivity | random")->capture_default_str();
    sub->add_option("--views", o.views,
                    "fit (one view per reducePCS call, fitted to the PCS) | clustered (one fitted view per group of "
                    "nodes whose projections overlap; docs/cullide.md#views-per-cluster)")
        ->capture_default_str();
    addNumber(sub, "--leaf-size", o.leafSize, "Triangles per hierarchy leaf (1 to 1,000,000)", 1u, kMaxLeafSize)
        ->capture_default_str();
    addNumber(sub, "--branching", o.branching, "Children per hierarchy node (2 to 64)", kMinBranching, kMaxBranching)
        ->capture_default_str();
    addNumber(sub, "--seed", o.seed, "Seed of the random hierarchy");
}

void checkCullideOptions(const CLI::App* sub, const OptionText& o) {
    // An option that does not apply is refused, not ignored.
    if (sub->count("--seed") && o.hierarchy != "random")
        throw CLI::ValidationError("--seed", "applies to --hierarchy random only");
}

void addProgressOption(CLI::App* sub, ProgressMode& mode) {
    sub->add_option_function<std::string>(
           "--progress", [&mode](const std::string& text) { mode = parseProgressMode(text); },
           "Progress bar on stderr: auto (when stderr is a terminal; the default) | always | never")
        ->type_name("MODE");
}

CLI::Option* addThreadsOption(CLI::App* sub, int& threads, const std::string& what) {
    return addNumber(sub, "--threads", threads, what + " (0: all cores; 1 to " + std::to_string(kMaxThreads) + ")", 0,
                     kMaxThreads);
}

FrameHooks passProgress(Progress& bar, const std::string& frameName, size_t done, size_t directions) {
    FrameHooks hooks;
    if (!bar.shown()) return hooks;
    hooks.onPassStats = [&bar, &frameName, done, directions](const PassStats& st) {
        if (!bar.due()) return;
        char text[160];
        std::snprintf(text, sizeof text, "%s: level %u, direction %u/%zu, PCS %zu triangles", frameName.c_str(),
                      st.level, st.direction + 1, directions, st.trianglesOut);
        bar.update(done, text);
    };
    return hooks;
}

}  // namespace cullide::cli
