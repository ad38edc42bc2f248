// The view fitting that the Culler uses besides the public fitView (cullide.h). Private to core/.
#pragma once

#include "cullide/depth_backend.h"

#include <span>

namespace cullide::detail {

// fitView of every point: for a draw of every triangle of a geometry whose every vertex some
// triangle uses, the same view (min and max are exact), from each vertex once instead of each
// triangle corner (a vertex is the corner of about six triangles).
OrthoView fitViewToPoints(std::span<const Vec3f> positions, const Vec3d& dir, int width, int height,
                          const DepthFormat& depth);

}  // namespace cullide::detail
