// What every subcommand of `cullide` shares: the frames a --frame value selects, Cullide's options
// and --progress with the same help everywhere, and the progress text of a frame's reducePCS calls.
#pragma once

#include "cullide/error.h"
#include "cullide/options.h"
#include "cullide/pipeline/progress.h"
#include "cullide/pipeline/pruner.h"
#include "cullide/scene.h"

#include <CLI/CLI.hpp>

#include <cstddef>
#include <string>

namespace cullide::cli {

// The frames [first, last) a --frame value selects (frame < 0: every frame). Throws
// InputError("option --frame") when `animation`, read from `path`, has no such frame.
struct FrameRange {
    size_t first = 0, last = 0;
};
inline FrameRange selectFrames(const Animation& animation, long frame, const std::string& path) {
    if (frame < 0) return {0, animation.frameCount()};
    if (size_t(frame) >= animation.frameCount())
        throw InputError("option --frame",
                         "frame " + std::to_string(frame) + " requested, but " + path + " has " +
                             std::to_string(animation.frameCount()) + " frame(s)");
    return {size_t(frame), size_t(frame) + 1};
}

// Cullide's options (method, resolution, depth, directions, hierarchy, leaf size, branching,
// seed) on a subcommand, with the same help everywhere; checkCullideOptions() in its callback
// refuses an option that does not apply (--seed without --hierarchy random).
void addCullideOptions(CLI::App* sub, OptionText& text);
void checkCullideOptions(const CLI::App* sub, const OptionText& text);

// --progress auto|always|never on a subcommand that can run long: the progress bar on stderr
// (cullide/pipeline/progress.h), with the same help everywhere. A bad value is an
// InputError("option --progress") while parsing (exit status 2).
void addProgressOption(CLI::App* sub, ProgressMode& mode);

// --threads on a subcommand: "<what> (0: all cores; 1 to kMaxThreads)", checked while parsing.
CLI::Option* addThreadsOption(CLI::App* sub, int& threads, const std::string& what = "Worker threads");

// The frame's reducePCS calls on the bar: "frame F: level L, direction D/N, PCS P triangles" as
// step `done`, redrawn when due. No hooks when the bar is hidden, so that the run is exactly as
// without one. `bar` and `frameName` must outlive the frame's run.
FrameHooks passProgress(Progress& bar, const std::string& frameName, size_t done, size_t directions);

}  // namespace cullide::cli
