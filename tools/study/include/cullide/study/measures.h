// How wrong a PCS is: a potentially colliding set measured against the oracle's truth (analysis
// of a result, not truth: it lives with the studies, not in the oracle).
//
// Conventions
//   - A triangle is "colliding" when it belongs to at least one intersecting pair of the truth.
//     A false prune is a colliding triangle missing from the PCS; a false positive is a PCS
//     triangle in no intersecting pair (degenerate triangles included); efficiency is the share
//     of the PCS that is colliding (1 for an empty PCS).
//   - Per class: a false-pruned triangle counts as crossing when it belongs to at least one
//     crossing pair, else as touching. A missed pair is an intersecting pair with at least one
//     triangle missing from the PCS.
//   - For every missed pair, per view direction of the options, measured in double (these are
//     explanations, not decisions) in the frame OrthoView::looking(d) and the view fitView fits
//     to ALL the scene's triangles for d. Cullide fits each pass's view to the current PCS, which
//     shrinks; the whole-scene view is the coarsest, so its depth unit and pixel grid are an
//     upper bound of the ones a pass saw (documented approximation):
//       penetration: over the overlap of the two triangles' projections (a convex polygon),
//         with zA, zB the depths of each triangle's plane, min(max(zA - zB), max(zB - zA)):
//         how far each triangle reaches behind the other along d. Positive for a crossing seen
//         from d; a depth test can only see the crossing where this exceeds the depth unit.
//         <= 0: the two do not interleave in depth from d. NaN: the overlap is empty or a
//         triangle is edge-on (zero projected area).
//       depthUnit: (zfar - znear) * depth.resolution() of the whole-scene view, world units.
//       pixelCentre: whether the closed overlap polygon holds a pixel centre (i + 1/2, j + 1/2)
//         of that view (no fill rule: a centre exactly on an edge counts).
//     and per triangle, edgeOn = min over directions of |n . d| (unit normal and direction):
//     0 is edge-on in some direction (no fragments), 1 face-on.
#pragma once

#include "cullide/cullide.h"
#include "cullide/oracle/near_contacts.h"
#include "cullide/oracle/oracle.h"

#include <span>
#include <vector>

namespace cullide::study {

struct DirectionMeasure {
    double penetration = 0;
    double depthUnit = 0;
    bool pixelCentre = false;
};

struct MissedPair {
    oracle::IntersectingPair pair;
    bool missingA = false, missingB = false;  // which of the two triangles the PCS lacks
    std::vector<DirectionMeasure> directions;  // one per CullideOptions::directions
    double edgeOnA = 0, edgeOnB = 0;
};

struct PcsReport {
    size_t pcsTriangles = 0;  // distinct PCS entries
    size_t collidingTriangles = 0;  // triangles in some intersecting pair
    size_t collidingInPcs = 0;
    size_t falsePrunes[2] = {0, 0};  // false-pruned triangles, indexed by PairClass
    size_t missedPairs[2] = {0, 0};  // indexed by PairClass
    size_t missedSelfPairs[2] = {0, 0};  // of which within one object
    size_t falsePositives = 0;
    double efficiency = 1;  // collidingInPcs / pcsTriangles
    std::vector<MissedPair> missed;  // sorted by pair

    size_t falsePruneCount() const { return falsePrunes[0] + falsePrunes[1]; }
};

// Measures `pcs` (entries must name triangles of `scene`: InputError("pcs", ...) otherwise) against
// `truth` (findIntersections of the same scene), with the options of the run that produced it.
PcsReport measurePcs(const Scene& scene, const oracle::Truth& truth, std::span<const PcsTriangle> pcs,
                     const CullideOptions& options);

// The near contacts of a scene (cullide/oracle/near_contacts.h) within `distance` (world units);
// `truth` is the oracle's for the scene. A study's distance is a fraction of sceneDiagonal, the
// diagonal of the scene's world bounding box, at its first frame (one distance for every frame).
struct NearMeasure {
    double distance = 0;
    oracle::NearContacts contacts;
};
NearMeasure measureNear(const Scene& scene, const oracle::Truth& truth, double distance);
double sceneDiagonal(const Scene& scene);

}  // namespace cullide::study
