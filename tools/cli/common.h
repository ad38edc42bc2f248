// What every subcommand of `cullide` shares: the frames a --frame value selects, Cullide's options
// and --progress with the same help everywhere, and the progress text of a frame's reducePCS calls.
#pragma once

#include "cullide/error.h"
#include "cullide/options.h"
#include "cullide/parse_number.h"
#include "cullide/pipeline/progress.h"
#include "cullide/pipeline/pruner.h"
#include "cullide/scene.h"

#include <CLI/CLI.hpp>

#include <cstddef>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

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

// A numeric option, read by the one strict parser (cullide/parse_number.h) into `value`: anything
// but a number in [min, max] (a wrapped or clamped integer, NaN, trailing characters) is
// InputError("option --NAME", cause) while parsing (exit status 2). `flags` as for add_option
// ("-o,--out"); the type column of --help reads as CLI11's own for a CLI::Range check ("FLOAT:FLOAT in
// [0 - 59]", "INT:NONNEGATIVE", "UINT"), and capture_default_str() shows the default.
template <typename T>
CLI::Option* addNumber(CLI::App* sub, const std::string& flags, T& value, const std::string& help,
                       T min = std::numeric_limits<T>::lowest(), T max = std::numeric_limits<T>::max());
// The same for an option that takes a list of numbers, each in [min, max].
template <typename T>
CLI::Option* addNumbers(CLI::App* sub, const std::string& flags, std::vector<T>& values, const std::string& help,
                        T min = std::numeric_limits<T>::lowest(), T max = std::numeric_limits<T>::max());

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

namespace detail {

// "option --NAME" for flags "-o,--out" or "--tilt": the name errors give.
inline std::string optionName(const std::string& flags) {
    return "option " + flags.substr(flags.rfind(',') + 1);
}

// The type column CLI11 writes for T checked by CLI::Range(min, max).
template <typename T>
std::string numberType(T min, T max) {
    const std::string type = std::is_floating_point_v<T> ? "FLOAT" : std::is_signed_v<T> ? "INT" : "UINT";
    if (min == std::numeric_limits<T>::lowest() && max == std::numeric_limits<T>::max()) return type;
    if (std::is_signed_v<T> && min == 0 && max == std::numeric_limits<T>::max()) return type + ":NONNEGATIVE";
    std::ostringstream range;
    range << type << ":" << type << " in [" << min << " - " << max << "]";
    return range.str();
}

}  // namespace detail

template <typename T>
CLI::Option* addNumber(CLI::App* sub, const std::string& flags, T& value, const std::string& help, T min, T max) {
    const std::string name = detail::optionName(flags);
    return sub
        ->add_option_function<std::string>(
            flags, [&value, name, min, max](const std::string& text) { value = parseNumber(text, name, min, max); },
            help)
        ->type_name(detail::numberType(min, max))
        ->default_function([&value] { return numberText(value); });
}

template <typename T>
CLI::Option* addNumbers(CLI::App* sub, const std::string& flags, std::vector<T>& values, const std::string& help,
                        T min, T max) {
    const std::string name = detail::optionName(flags);
    return sub
        ->add_option_function<std::vector<std::string>>(
            flags,
            [&values, name, min, max](const std::vector<std::string>& texts) {
                values.clear();
                for (const std::string& text : texts) values.push_back(parseNumber(text, name, min, max));
            },
            help)
        ->type_name(detail::numberType(min, max));
}

}  // namespace cullide::cli
