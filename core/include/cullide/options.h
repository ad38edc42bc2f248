// Option text -> CullideOptions: the one parser behind every command that takes Cullide's
// options (`cullide prune`, `cullide validate`, `cullide study` from its command line or a JSON
// spec, and the stability sweeps).
//
// Conventions
//   - Values arrive as the user typed them: text for the method, viewport, depth format,
//     directions, hierarchy kind and view mode; numbers for the hierarchy's sizes and seed.
//   - Every number in a text is read by parseNumber (parse_number.h): no wrap, no clamp, no
//     trailing characters, ranges checked after reading.
//   - Every error is InputError(name, cause). `name` is what the user typed the value as
//     (OptionNames: "option --depth" by default, "option --depths" or "spec.json: field 'depths'"
//     in a study); `cause` is the same words for the same bad value whichever command it came
//     through.
#pragma once

#include "cullide/cullide.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace cullide {

// The hierarchy sizes the parser accepts (leaf size 1..kMaxLeafSize, branching
// kMinBranching..kMaxBranching).
inline constexpr uint32_t kMaxLeafSize = 1'000'000;
inline constexpr uint32_t kMinBranching = 2, kMaxBranching = 64;
// Worker threads every command, the study and the Python module accept: 0 (all cores) to kMaxThreads.
inline constexpr int kMaxThreads = 1024;
// Spread directions a count N may ask for (parseDirections: 1..kMaxSpreadDirections).
inline constexpr uint32_t kMaxSpreadDirections = 10'000;

// CullideOptions as typed; the defaults give CullideOptions' defaults.
struct OptionText {
    std::string method = "modified";  // original | modified | reliable
    std::string resolution = "500";  // N or WxH, each side 1..kMaxViewportSide; or auto, auto:K
    std::string depth = "24";  // unorm bits 8..32 (24, d24, unorm24) or float (float, f32, d32f)
    // axes | N (spread) | a list x,-y,z or '1 0 0;0 1 1' | pca | coherent, coherent:LIST (any of the
    // fixed ones; coherent is coherent:axes). docs/cullide.md#chosen-directions.
    std::string directions = "axes";
    std::string hierarchy = "connectivity";  // connectivity | random
    std::string views = "fit";  // fit | clustered (ViewMode)
    uint32_t leafSize = 16;
    uint32_t branching = 4;
    uint64_t seed = 1;  // of the random hierarchy
    std::string exactSwitch = "never";  // never | auto | N (parseExactSwitch)
};

// What each value is called in error messages: the source part of InputError.
struct OptionNames {
    std::string method = "option --method";
    std::string resolution = "option --resolution";
    std::string depth = "option --depth";
    std::string directions = "option --directions";
    std::string hierarchy = "option --hierarchy";
    std::string views = "option --views";
    std::string leafSize = "option --leaf-size";
    std::string branching = "option --branching";
    std::string exactSwitch = "option --exact-switch";
};

// The whole set; throws InputError naming the first bad value (in the order of OptionText).
CullideOptions parseCullideOptions(const OptionText& text, const OptionNames& names = {});

// A viewport "N" (N x N) or "WxH", each side 1..kMaxViewportSide.
std::pair<int, int> parseResolution(const std::string& text, const std::string& name = "option --resolution");
// A resolution setting: a fixed viewport (parseResolution; autoCoverage 0), or adaptive
// resolution, "auto" (K = kDefaultAutoCoverage) or "auto:K" (0 < K <= kMaxAutoCoverage, a decimal
// number: the drawn PCS covers about K base viewports' pixels), with the default 500x500 as its
// base viewport (CullideOptions::autoCoverage).
struct ResolutionSetting {
    int width = 500, height = 500;
    double autoCoverage = 0;
};
ResolutionSetting parseResolutionSetting(const std::string& text, const std::string& name = "option --resolution");
// "axes", "N" (N spread directions, 1..kMaxSpreadDirections), or a list "x,-y,z" / "1 0 0;0 1 1" of non-zero
// directions (normalized): CullideOptions::directions. "pca" and "coherent" give the axes,
// "coherent:LIST" the fixed list LIST (axes, N or a list; the order and set that coherent chooses
// from).
std::vector<Vec3d> parseDirections(const std::string& text, const std::string& name = "option --directions");
// The mode of a directions text: Pca for "pca", Coherent for "coherent" and "coherent:LIST", else
// Fixed (parseDirections judges the text).
DirectionMode parseDirectionMode(const std::string& text);

// Switch to exact: "never", "auto" (with the default cost model: ExactSwitch::exactCost empty), or
// N, a triangle count 1..10^12 (stop when the PCS holds fewer than N triangles).
ExactSwitch parseExactSwitch(const std::string& text, const std::string& name = "option --exact-switch");

// A worker-thread count, 0 (all cores) to kMaxThreads; InputError(name, ...) otherwise.
int checkThreads(long long threads, const std::string& name = "option --threads");

// A depth function by its GL name: never, less, equal, lequal, greater, notequal, gequal, always.
DepthFunc parseDepthFunc(const std::string& text, const std::string& name = "depth function");
// An occlusion query's kind: "samples" (SamplesPassed) or "any" (AnySamplesPassed).
QueryKind parseQueryKind(const std::string& text, const std::string& name = "query kind");

}  // namespace cullide
