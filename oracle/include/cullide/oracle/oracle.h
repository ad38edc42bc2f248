// The exact oracle: which triangles of a scene truly intersect, and how.
//
// References
//   - P. Guigue, O. Devillers: Fast and robust triangle-triangle overlap test using orientation
//     predicates. Journal of Graphics Tools 8(1), 2003 (the narrow phase; cullide/predicates.h).
//   - CGAL 5.5 Polygon_mesh_processing::self_intersections (the rules for faces that share
//     vertices, which we follow so that both can be compared pair for pair).
//   - The broad phase: a uniform grid of float boxes, one per triangle (docs/oracle.md); Embree 3
//     rtcCollide (user geometry) finds the same pairs and is kept beside it.
//   - docs/oracle.md: the full rules, and why these parts (docs/oracle.md#background).
//
// Conventions
//   - The oracle decides on exactly the coordinates the culler uses: Scene::worldMesh(i), in
//     float, converted to double (exact). No epsilon anywhere: every sign comes from an exact
//     orientation predicate (a float filter with Shewchuk's error bound, then CGAL's Epick).
//   - Pairs: self pairs (two triangles of one object) and pairs between objects. Each unordered
//     pair is reported once, as (objectA, triangleA) < (objectB, triangleB), the list sorted.
//   - Sharing (self pairs only) is by vertex index, as CGAL does by mesh connectivity:
//       3 shared indices (a duplicated face): intersecting, touching.
//       2 shared (an edge): intersecting iff the four corners are coplanar and the two
//         opposite corners lie strictly on the same side of the edge (a fold-over); touching.
//       1 shared (a vertex): intersecting iff either triangle meets the other's opposite edge.
//       0 shared, and every pair between objects: the exact triangle-triangle test.
//     OracleOptions::weldByPosition makes bit-identical positions one vertex first (soups).
//   - Degenerate triangles (a repeated index, or collinear/coincident corners, exactly) take part
//     in no pair; they are listed in Truth::degenerate (CGAL reports them as (f, f)).
//   - Classes (cullide/predicates.h): crossing when the two triangles are not coplanar and their
//     relative interiors meet (one passes through the other); touching otherwise (they meet
//     only on a boundary of one of them, or in the plane they share).
//   - Threads: TBB (the grid's construction and the narrow phase run on it); limit them with
//     tbb::global_control or a task_arena. The result does not depend on the thread count.
//   - Errors: InputError("scene", ...) for input the oracle cannot decide on (non-finite
//     coordinates, |coordinate| > 2^60, indices out of range); nothing else is thrown.
#pragma once

#include "cullide/scene.h"

#include <array>
#include <compare>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace cullide::oracle {

enum class PairClass : uint8_t {
    Crossing,  // one triangle passes through the other (what the modified method must keep)
    Touching,  // they meet only on a boundary, or coplanar (only the original method keeps these)
};
const char* toString(PairClass c);  // "crossing" | "touching"

// A triangle of the scene: object index, triangle index in that object's mesh (scene.h).
using TriangleRef = cullide::TriangleRef;

struct IntersectingPair {
    uint32_t objectA = 0, triangleA = 0, objectB = 0, triangleB = 0;  // (A) < (B)
    PairClass cls = PairClass::Crossing;

    TriangleRef a() const { return {objectA, triangleA}; }
    TriangleRef b() const { return {objectB, triangleB}; }
    bool selfPair() const { return objectA == objectB; }
    friend auto operator<=>(const IntersectingPair&, const IntersectingPair&) = default;
};

// Which broad phase finds the candidate pairs. Both give the same candidate set, hence the same
// truth (tested): the uniform grid is ours and about 4x faster to build on bunny75k; Embree 3's
// rtcCollide on user geometry is the well-kept library's, kept selectable as a cross-check.
enum class BroadPhase : uint8_t { Grid, Embree };

const char* toString(BroadPhase b);
BroadPhase parseBroadPhase(const std::string& text);  // "grid" | "embree"; InputError

struct OracleOptions {
    BroadPhase broadPhase = BroadPhase::Grid;
    // Treat vertices of one object with bit-identical world positions as one vertex for the
    // sharing rules (for soups whose vertices are duplicated). Off: sharing is by index only,
    // as CGAL does, and triangles that meet at duplicated vertices are touching pairs.
    bool weldByPosition = false;
};

struct Truth {
    std::vector<IntersectingPair> pairs;  // sorted, each unordered pair once
    std::vector<TriangleRef> degenerate;  // sorted; in no pair
    size_t trianglesTested = 0;  // non-degenerate triangles given to the broad phase
    size_t candidatePairs = 0;  // broad-phase pairs given to the narrow phase
    double setupSeconds = 0;  // validation, world positions, degeneracy, boxes
    double buildSeconds = 0;  // broad phase: building the grid
    double collideSeconds = 0;  // pair tests in the cells, narrow phase inside
    double sortSeconds = 0;  // merging the per-thread results
    double totalSeconds = 0;

    size_t count(PairClass c) const;
};

// Memory that calls of the oracle share: given the same workspace, findIntersections and
// exactStage reuse the previous call's arrays (primitive records, boxes, planes, world
// positions, the grid's entries) instead of allocating them again. Fresh memory is paid for in
// page faults when first written (about 13 us per 4 KiB page on a virtual machine): between two
// calls whose memory went back to the system, a third of a call on 23k triangles. A call without
// one takes its arrays from transparent huge pages where the system offers them (a PageArena,
// cullide/unwritten.h: one fault per 2 MiB, and a few chunks pooled for the next call), which
// brings it close; a caller that runs the oracle frame after frame still keeps one. It holds the
// largest call's arrays until release() or its end, and serves one call at a time. Results are
// the same with or without.
class Workspace {
public:
    Workspace();
    ~Workspace();
    Workspace(Workspace&&) noexcept;
    Workspace& operator=(Workspace&&) noexcept;
    void release();  // gives the memory back (the workspace stays usable, as after a move)

    struct Impl;  // oracle.cpp's
    Impl& impl();  // made on first use

private:
    std::unique_ptr<Impl> impl_;
};

// All intersecting pairs of `scene` (self pairs and pairs between objects); `workspace`: see
// Workspace (null: the call's own memory).
Truth findIntersections(const Scene& scene, const OracleOptions& options = {}, Workspace* workspace = nullptr);

// The exact stage of the pipeline (CULLIDE runs it after the GPU stage): the same narrow phase,
// on the triangles of `pcs` only (pairs with both triangles in the PCS). Entries of `pcs` must
// name triangles of `scene` (InputError("pcs", ...) otherwise); duplicates are ignored.
Truth exactStage(const Scene& scene, std::span<const TriangleRef> pcs, const OracleOptions& options = {},
                 Workspace* workspace = nullptr);

}  // namespace cullide::oracle
