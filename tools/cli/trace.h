// Recording a Cullide run as a trace and reporting a comparison: shared by `cullide trace` and
// `cullide validate` (which is record + replay + compare in one process).
#pragma once

#include "cullide/cullide.h"
#include "cullide/raster/trace.h"
#include "cullide/scene.h"
#include "cullide/pipeline/progress.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace cullide::cli {

// What a recording run produced.
struct Recording {
    uint64_t bytes = 0;  // of the trace file
    uint64_t queries = 0;
    uint64_t referenceOutside = 0;  // reference counts outside their own intervals (a bug)
    std::vector<std::vector<PcsTriangle>> pcs;  // per recorded frame, the reference's PCS
};

// Runs Cullide on the CPU reference (configured by `rules`, `threads` workers) over frames
// [first, last) of `animation`, recording every command list into `path`. `workload` describes
// the run for the header. `bar` (optional) counts frames: frame k of the range is step k.
Recording recordTrace(const Animation& animation, size_t first, size_t last, const CullideOptions& options,
                      const raster::TraceRules& rules, int threads, const std::string& path,
                      const nlohmann::ordered_json& workload, Progress* bar = nullptr);

// The run's options as the trace header's "workload".
nlohmann::ordered_json workloadJson(const std::string& scene, const CullideOptions& options);

// Prints the comparison (totals, per frame and per depth format, the worst queries with their
// draws) under the title `title` and returns it as JSON (with `provenance`).
nlohmann::ordered_json reportComparison(const raster::TraceReader& trace, const raster::TraceComparison& c,
                                        const std::string& backend, size_t worst, nlohmann::ordered_json provenance,
                                        const std::string& title);

// Difference pictures of the worst queries (one per list) into `folder`; returns how many.
size_t writeComparisonPictures(const raster::TraceReader& trace, const raster::TraceComparison& c,
                               const std::vector<size_t>& worst, const std::string& folder);

// --subpixel-bits, --other-subpixel-bits and --depth-margin: the rules of a recording.
void addTraceRuleOptions(CLI::App* sub, raster::TraceRules& rules);

}  // namespace cullide::cli
