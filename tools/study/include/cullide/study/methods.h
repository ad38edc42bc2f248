// The methods a study compares, by family: Cullide's image-space methods (original, modified,
// reliable and the others of CullMethod), the exact oracle alone ("exact") and the peers a user
// would pick instead ("fcl", "embree", "bullet", "cgal": cullide/peers/peer.h).
//
// Conventions
//   - Every family ends in the same measure: the time to a frame's intersecting pairs and how those
//     pairs differ from the oracle's (docs/studies.md#every-method). Image-space methods get there
//     through their PCS and the exact stage on it (time to exact pairs); the exact method is the
//     oracle; a peer reports pairs itself, judged by the audit (cullide/oracle/audit.h).
//   - Only image-space methods have resolutions, depths, directions, views, hierarchies, leaf
//     sizes, exact switches and backends: a study runs the other families once per scene frame and
//     thread count, those columns empty.
#pragma once

#include <string>

namespace cullide::study {

enum class MethodFamily { ImageSpace, Exact, Peer };
const char* toString(MethodFamily f);  // "image-space" | "exact" | "peer"

// The family of a method name; InputError(source, ...) listing the methods for an unknown one.
MethodFamily methodFamily(const std::string& method, const std::string& source);

// The study's default tolerance for the audit's causes (AuditOptions::tolerance), as a fraction of
// the scene's bounding-box diagonal at its first frame: pairs closer than this, or crossing less
// deep, are within what float tests can decide (a few float steps of coordinates near the
// diagonal's size).
inline constexpr double kDefaultTolerance = 1e-5;
inline constexpr double kMaxTolerance = 0.1;

}  // namespace cullide::study
