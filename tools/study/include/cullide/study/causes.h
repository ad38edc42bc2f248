// Why a false prune happened: every colliding triangle Cullide dropped, attributed to one of the
// causes of the seed paper's Section 5 (docs/paper.md#section-5), decided per
// pair in the view of the very reducePCS call that dropped it.
//
// Conventions (full rules and their derivation: docs/studies.md)
//   - A pair (T, X) of the oracle's truth is missed when T or X is not in the final PCS. Its
//     deciding call is the first reducePCS call after which one of them is gone; the view is that
//     call's (fitted, as runCullide fits it, to the PCS it started from). The triangle(s) dropped
//     there are judged against the partner, which was still drawn in that call.
//   - Judging T against X renders each alone in that view on the run's own backend: the covered
//     pixel centres, the stored depths, and in double the depths of the planes through the
//     unsnapped window vertices (raster rule 6) at the shared centres and over the exact overlap of
//     the two projections. One "step" is DepthFormat::resolution() in window depth: the stored
//     unorm step 1/(2^n-1), or 2^-24 for float (the largest float spacing below 1).
//   - Causes, in this order:
//       EdgeOn: T or X covers no pixel centre in that view (no fragments) although it is large
//         enough to cover one face-on (PairSample::largeT/largeX); a small one is Sampling.
//       Sampling / DepthRounding / Unexplained: see decide().
//       Untested: the original method and a pair within one object (Cullide never tests an object
//         against itself; by design).
//   - A false-pruned triangle's cause combines the causes of all its pairs, the first in the
//     order Unexplained, EdgeOn, Sampling, DepthRounding, Untested.
#pragma once

#include "cullide/cullide.h"
#include "cullide/oracle/oracle.h"

#include <array>
#include <cstdint>
#include <vector>

namespace cullide::study {

enum class Cause : uint8_t { DepthRounding, Sampling, EdgeOn, Untested, Unexplained };
inline constexpr int kCauseCount = 5;
const char* toString(Cause c);  // "depth_rounding", "sampling", "edge_on", "untested", "unexplained"

// What a depth test can see of triangle T against triangle X in one view (each rendered alone).
struct PairSample {
    size_t coveredT = 0, coveredX = 0, shared = 0;  // covered pixel centres; shared: by both
    // Whether the triangle's inscribed circle (in 3D) is at least a pixel diagonal wide, so that
    // seen face-on it would hold a pixel centre wherever it lay: a miss of such a triangle for
    // want of fragments is due to its tilt (edge-on), not to its size (sampling).
    bool largeT = false, largeX = false;
    // Max over shared centres of stored(T) - stored(X): unorm integers, or float bit patterns
    // (which order non-negative floats); INT64_MIN when nothing is shared.
    int64_t maxStoredDiff = INT64_MIN;
    // Max over shared centres of (zT - zX) / step, zT and zX the double plane depths; -inf if none.
    double maxDiffSteps = 0;
    // Max over the exact overlap polygon of the two projections of (zT - zX) / step: how far T
    // reaches behind X anywhere (the paper's penetration along the view). NaN: empty overlap or a
    // triangle of zero projected area.
    double reachSteps = 0;
};

// The images samplePair reads, kept by a caller that samples many pairs so that their buffers
// are reused (DepthBackend::readDepthInto).
struct PairSampleScratch {
    DepthImage t, x, blank;
};

// Renders t and x alone in `view` on `backend` (which gets new geometry and view) and measures.
PairSample samplePair(DepthBackend& backend, const std::array<Vec3f, 3>& t, const std::array<Vec3f, 3>& x,
                      const OrthoView& view);
PairSample samplePair(DepthBackend& backend, const std::array<Vec3f, 3>& t, const std::array<Vec3f, 3>& x,
                      const OrthoView& view, PairSampleScratch& scratch);

// The cause of a miss of T against X (T dropped while X was drawn), given their sample:
//   EdgeOn when either covers no centre although large enough to cover one face-on; Sampling
//   when one without fragments is smaller than that, or when no centre is shared. Otherwise, with
//   theta = the stored steps by which T must lie behind X to be seen (1 for GREATER: modified and
//   any other method; 0 for GEQUAL: original):
//   Unexplained when maxStoredDiff >= theta (the pair alone is seen, yet T was pruned: a culling
//     bug) or maxDiffSteps >= theta + 1e-6 (a depth gap that rounding must keep was lost: a
//     rasterizer bug);
//   DepthRounding when maxDiffSteps > theta - 1 (at a shared centre the gap is under one step and
//     rounding decided), or, for theta = 1, when T reaches less than one step behind X anywhere
//     (reachSteps < 1: a contact or a penetration shallower than the depth unit);
//   Sampling otherwise (T reaches a full step behind X, but not at any shared centre).
Cause decide(CullMethod method, const PairSample& s);

struct MissedPairCause {
    oracle::IntersectingPair pair;
    Cause cause = Cause::Unexplained;
    uint32_t call = 0;  // index of the deciding reducePCS call in CullideResult::passes
    uint32_t direction = 0;  // its direction (PassStats::direction: index into the call's list)
};

struct Attribution {
    std::array<size_t, kCauseCount> triangles{};  // false-pruned triangles by cause
    std::array<size_t, kCauseCount> pairs{};  // missed pairs by cause
    std::vector<MissedPairCause> missed;  // sorted by pair
    CullideResult result;  // the run explained (with its prunedAtCall)
};

// Runs Cullide once with CullideOptions::recordPrunes (which call pruned each triangle), then
// judges every missed pair of `truth` (findIntersections of `scene`) in the view of the call that
// pruned it. `backend` is used for the run and for the pair renders.
Attribution attributeFalsePrunes(const Scene& scene, const oracle::Truth& truth, DepthBackend& backend,
                                 const CullideOptions& options);
// The same for a run already made (with `options` and recordPrunes: its prunedAtCall is read), so
// that a study explains the run it timed without running again.
Attribution attributeFalsePrunes(const Scene& scene, const oracle::Truth& truth, DepthBackend& backend,
                                 const CullideOptions& options, CullideResult run);

}  // namespace cullide::study
