// What the trace writer and reader share: the preamble, the op codes of the command rows, and the
// refusal of conservative commands (docs/trace-format.md). Private to the verification harness.
#pragma once

#include "cullide/error.h"
#include "cullide/mesh.h"

#include <nlohmann/json.hpp>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>

namespace cullide::raster::trace_format {

// The blobs are the host's arrays written as they are: the format says little-endian.
static_assert(std::endian::native == std::endian::little, "trace blobs are written in host order");
static_assert(sizeof(Vec3f) == 3 * sizeof(float) && sizeof(Triangle) == 3 * sizeof(uint32_t));

using Json = nlohmann::ordered_json;

inline constexpr char kMagic[8] = {'C', 'U', 'L', 'T', 'R', 'A', 'C', 'E'};
inline constexpr size_t kPreamble = 16;  // magic + header length
// Op codes of the command rows (the format's table; Command::Op order for 0-5).
enum TraceOp : uint32_t { OpClear = 0, OpDepthFunc, OpDepthMask, OpBeginQuery, OpEndQuery, OpDraw, OpCount };

// The reliable method's commands: refused by the writer and the recorder alike.
[[noreturn]] inline void refuseConservative() {
    throw InputError("trace",
                     "conservative commands (the reliable method) have no GL or Vulkan counterpart and "
                     "cannot be recorded; record the original or modified method");
}

inline std::string fileSize(uint64_t n) {
    return std::to_string(n) + " byte" + (n == 1 ? "" : "s");
}

}  // namespace cullide::raster::trace_format
