// The audit: any list of intersecting pairs (a peer's, a library's cullide does not wrap, the
// exact stage's) judged against the oracle's truth, every disagreement with its cause
// (docs/oracle.md#audit).
//
// Conventions
//   - A reported pair is found when the truth holds it, spurious when it does not; a pair of the
//     truth the list lacks is missed. Pairs are unordered (TrianglePair, a < b); a list may hold a
//     pair twice (counted once).
//   - Causes, decided in exact arithmetic (the oracle's predicates) where they are signs, in double
//     where they are distances; the first that holds, in this order:
//       missed:   Untested (a pair within one object, for a list that tests none: AuditOptions);
//                 SharedEdge, SharedVertex (the two triangles share an edge or a vertex by index,
//                 so a detector that skips neighbours misses it); Coplanar (a touching pair in one
//                 plane); Touching (they meet only on a boundary); WithinTolerance (a crossing pair
//                 whose penetration depth, the shortest translation that parts them, is at most the
//                 tolerance); Unexplained otherwise.
//       spurious: Degenerate (either triangle is degenerate: the oracle pairs it with nothing);
//                 SharedEdge, SharedVertex (neighbours that do not intersect under the sharing
//                 rules, oracle.h); Coplanar (in one plane, and at most the tolerance apart);
//                 WithinTolerance (at most the tolerance apart); BehindFace (each has a part inside
//                 the prism over the other and behind its plane, the side its normal, by the
//                 corners' winding, points away from: a detector that takes each triangle for
//                 the face of a solid, as Bullet's GImpact does, counts that as penetration,
//                 however far apart they are); Unexplained otherwise.
//     Unexplained is a bug of the list's maker, or of the oracle: 0 for every peer we wrap.
//   - Errors: InputError(source, ...) for a pair naming a triangle the scene does not have, or a
//     triangle paired with itself.
#pragma once

#include "cullide/oracle/oracle.h"
#include "cullide/scene.h"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cullide::oracle {

enum class AuditCause : uint8_t {
    Untested,
    Degenerate,
    SharedEdge,
    SharedVertex,
    Coplanar,
    Touching,
    WithinTolerance,
    BehindFace,
    Unexplained,
};
inline constexpr int kAuditCauseCount = 9;
// "untested" | "degenerate" | "shared_edge" | "shared_vertex" | "coplanar" | "touching" |
// "within_tolerance" | "behind_face" | "unexplained"
const char* toString(AuditCause c);
// The causes a missed pair can have, and a spurious one, in the order above (the study's columns
// missed_<cause> and spurious_<cause>).
const std::vector<AuditCause>& missedCauses();
const std::vector<AuditCause>& spuriousCauses();

struct AuditOptions {
    double tolerance = 0;  // world units (>= 0): see WithinTolerance and Coplanar
    bool selfPairsTested = true;  // false: missed pairs within one object are Untested
    std::string source = "pairs";  // what errors name
};

struct AuditedPair {
    TrianglePair pair;
    PairClass cls = PairClass::Crossing;  // missed: the truth's class; spurious: unused
    AuditCause cause = AuditCause::Unexplained;
    // Missed crossing pairs: the penetration depth (the shortest translation that parts them, by
    // the separating-axis theorem); spurious pairs: the distance between the two triangles
    // (double; 0 when they touch in float but not exactly, and for a degenerate triangle).
    // Otherwise 0.
    double distance = 0;
};

struct Audit {
    size_t reported = 0;  // distinct pairs in the list
    size_t found = 0;  // reported and in the truth
    std::vector<AuditedPair> missed;  // sorted by pair
    std::vector<AuditedPair> spurious;  // sorted by pair
    std::array<size_t, kAuditCauseCount> missedBy{}, spuriousBy{};  // counts by cause
    std::array<size_t, 2> missedByClass{};  // indexed by PairClass

    bool agrees() const { return missed.empty() && spurious.empty(); }
};

// Judges `reported` (pairs of `scene`'s triangles, any order, duplicates allowed) against `truth`
// (findIntersections of the same scene, default OracleOptions).
Audit audit(const Scene& scene, const Truth& truth, std::span<const TrianglePair> reported,
            const AuditOptions& options = {});

}  // namespace cullide::oracle
