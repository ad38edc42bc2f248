// The scalar reference path of the CPU backend (see cpu_backend.h). Private to raster/.
#pragma once

#include "cullide/raster/cpu_options.h"
#include "command_state.h"
#include "setup/conservative.h"
#include "setup/triangle_setup.h"

#include <span>
#include <vector>

namespace cullide::raster::detail {

// The conservative mode's state: the interval buffer and the view's window error bound.
struct IntervalState {
    std::vector<uint32_t>* lo;
    std::vector<uint32_t>* hi;
    WindowError error;
};

// Executes a validated command list the obvious way: commands in order, triangles in order, every
// pixel centre of the viewport tested against every sub-triangle with edge functions computed
// from scratch. `depth` is the width x height buffer (row 0 at the bottom).
std::vector<uint64_t> executeReference(const CommandList& list, std::span<const WinVertex> window,
                                       std::span<const Triangle> triangles, const SetupParams& params,
                                       const DepthFormat& format, PipelineState& state, std::vector<uint32_t>& depth,
                                       RasterStats& stats, const IntervalState& intervals);

}  // namespace cullide::raster::detail
