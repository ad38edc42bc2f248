// What the GL backend (raster/gl/) and the Vulkan backend (raster/vulkan/) do alike, written once:
// the command-list checks before anything reaches the device, the exact viewport's size P, and
// the depth-format warning. Private to the two backends.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/error.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <set>
#include <string>

namespace cullide::raster::gpu {

// Refuses what a GPU backend cannot execute, as the CPU backend refuses it, before anything runs:
// a list before setView(), an open query, conservative commands, draws past the geometry. `api`
// ("GL", "Vulkan") names the backend in the message.
inline void checkCommandList(const CommandList& list, bool haveView, size_t triangleCount, const char* api) {
    if (!haveView) throw InputError("command list", "execute() before setView()");
    if (list.queryOpen()) throw InputError("command list", "a query is still open at the end of the list");
    if (list.conservativeCount() > 0)
        throw InputError("command list",
                         std::string("conservative commands need conservative rasterization, which this ") + api +
                             " backend does not provide (the reliable method is CPU-only)");
    for (const Command& c : list.commands())
        if (c.op == Command::Op::Draw && uint64_t(c.first) + c.count > triangleCount)
            throw InputError("command list",
                             "draw of triangles [" + std::to_string(c.first) + ", " +
                                 std::to_string(uint64_t(c.first) + c.count) + ") but the geometry has " +
                                 std::to_string(triangleCount) + " triangles");
}

struct ViewportSize {
    int P = 1;  // a power of two
    bool exact = false;  // (-P, -P, 2P, 2P) fits the device's viewport limits
};

// The exact viewport: (-P, -P, 2P, 2P) maps clip x in [-1, 1] to window [-P, P] with scale P and
// offset 0, so x_window = (xw / P) * P = xw exactly. P is at least the framebuffer's larger side
// and grows to twice the larger side of the view's grid where the device allows it, so that
// clipping against the viewport (at window -P and P) stays at least one viewport away from the
// framebuffer, also for a tile (OrthoView::tile), whose geometry spans its whole grid, up to a
// grid's side away from the framebuffer. `exact` is false when even that P exceeds the device's
// limits (the backend then uses the ordinary viewport, which rounds in float).
inline ViewportSize exactViewport(int width, int height, const OrthoView& view, int maxViewport, double boundsMin) {
    auto fits = [&](int q) { return 2 * q <= maxViewport && -q >= boundsMin; };
    int P = 1;
    while (P < std::max(width, height)) P *= 2;
    const int64_t reach = 2 * int64_t(std::max(view.fullWidth(), view.fullHeight()));
    while (P < reach && fits(2 * P)) P *= 2;
    return {P, fits(P)};
}

// A warning to the backend options' sink, or to stderr without one.
inline void warn(const std::function<void(const std::string&)>& sink, const std::string& msg) {
    if (sink) sink(msg);
    else std::fprintf(stderr, "cullide: warning: %s\n", msg.c_str());
}

// Warns, once per requested format (`warned` remembers them), that the device stores `used` for
// `requested`. `source` ("gl backend") starts the message, `api` ("GL") names the device's formats.
inline void warnFormatOnce(std::set<std::string>& warned, const DepthFormat& requested, const DepthFormat& used,
                           const char* source, const char* api, const std::function<void(const std::string&)>& sink) {
    if (!(used == requested) && warned.insert(requested.name()).second)
        warn(sink,
             std::string(source) + ": depth " + requested.name() + " is not available; using " + used.name() +
                 " (the nearest " + api + " depth format)");
}

}  // namespace cullide::raster::gpu
