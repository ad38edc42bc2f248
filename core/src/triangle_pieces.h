// The triangles of a list of ranges cut into pieces: the unit of core's parallel loops over the
// triangles of a draw (pcaFrame, pcaDirections, fitView, adaptiveViewport). Private to core/.
#pragma once

#include "cullide/cullide.h"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace cullide::detail {

// The ranges cut into pieces of at most kPiece triangles. The pieces depend on the ranges only, so
// a reduction over them in piece order (per-piece sums added in piece order) does not depend on
// the thread count.
inline constexpr uint32_t kPiece = 4096;
inline std::vector<TriangleRange> piecesOf(std::span<const TriangleRange> ranges) {
    std::vector<TriangleRange> pieces;
    for (const TriangleRange& r : ranges)
        for (uint32_t k = 0; k < r.count; k += kPiece) pieces.push_back({r.first + k, std::min(kPiece, r.count - k)});
    return pieces;
}

}  // namespace cullide::detail
