// Cullide and its self-intersection variant: the potentially colliding set (PCS) of triangles
// among the objects of a scene, by occlusion queries on any DepthBackend.
//
// References
//   - N. Govindaraju, S. Redon, M. Lin, D. Manocha: CULLIDE: Interactive collision detection
//     between complex models in large environments using graphics hardware. Graphics Hardware
//     2003. ("original": Figure 2 of the seed paper.)
//   - The seed paper (summarised in docs/paper.md#figure-1 ff.): Figures 1 (the loop), 2
//     (original reducePCS) and 3 (modified reducePCS, which keeps self-intersecting objects).
//
// Conventions
//   - The scene is taken as it is (world positions from Scene::worldMesh). All objects' triangles
//     go to the backend once per call as one geometry, each object's triangles permuted by its
//     hierarchy so that every node is one contiguous draw.
//   - A view direction d looks along +d; for each reducePCS call the orthographic view is fitted
//     tightly to the triangles of the current PCS: x/y to their projected bounds with square
//     pixels (the longer side fills the viewport, the box centred), near/far to their depth
//     extent (plus two depth units at each end). A PCS that is flat along d, or a point, gets a
//     tiny box around it so the view stays valid.
//   - A node is pruned by one reducePCS call (one direction) when it is fully visible in both the
//     forward and the reverse pass (the paper's Lemma 3.2): its queries passed no fragment.
//   - The loop (Figure 1): start from the objects' roots; for each level, run reducePCS once per
//     direction (in the given order) on the current PCS; stop when the PCS is empty or holds only
//     leaves (the leaves have then been tested too); otherwise replace every node by its children.
//     An exact switch (ExactSwitch) may stop it earlier, the PCS as it stands.
//   - Deterministic: same scene, options and backend results, same PCS.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/hierarchy.h"
#include "cullide/scene.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace cullide {

enum class CullMethod : uint8_t {
    // Figure 2: inter-object only. Query with GEQUAL against the objects drawn before (forward)
    // or after (reverse), so touching counts as colliding and contacts are kept. Below the object
    // level a node is tested against the nodes of other objects only, never its own siblings.
    Original,
    // Figure 3: draw with LESS, then re-draw under GREATER with a query (forward pass); plain
    // GREATER queries then LESS draws in the reverse pass. Self-intersections stay in the PCS;
    // contacts (equal depth) are lost, as the paper says.
    Modified,
    // Never prunes an intersecting triangle (touching contacts and self-intersections included),
    // at any resolution and depth format (docs/reliable.md). Needs a backend with conservative
    // rasterization (DepthBackend::supportsConservative; the CPU reference). Works on the
    // hierarchy's leaves (units): each unit is tested, in conservative interval mode, against
    // every PCS unit that shares no vertex with it, by forward and reverse passes per class of a
    // distance-2 colouring of the units; pairs inside a unit and between units that share a
    // vertex are checked exactly instead. A unit is pruned when no conservative fragment of it
    // conflicts (its depth interval is strictly in front of or strictly behind everything stored
    // at that pixel) and no exactly checked pair may intersect.
    Reliable,
};

const char* toString(CullMethod m);
CullMethod parseCullMethod(const std::string& text);  // "original" | "modified" | "reliable"; InputError

// Whether `method` promises never to prune an intersecting pair of triangles: a crossing pair
// (one passes through the other) or a touching one, of one object or of two. Reliable keeps every
// pair, in the image too; modified every crossing pair (a contact at equal depth may be lost);
// original every pair between two objects (it never tests an object against itself). For
// modified and original that is the continuous promise (exact depths, an infinitely fine image):
// in the image they also lose promised pairs to the fill rule, sampling, depth rounding and
// edge-on triangles (docs/cullide.md; e.g. the original on cubes that only touch). A false prune
// of a promised pair is such a loss or a bug, any other one a limit of the method itself
// (`prune --check` exits 1 on the former).
bool promisesToKeep(CullMethod method, bool crossing, bool sameObject);

// Directions: the six axis directions +x, -x, +y, -y, +z, -z (the default).
std::vector<Vec3d> axisDirections();
// N directions spread over the sphere (a Fibonacci lattice, deterministic). N >= 1.
std::vector<Vec3d> spreadDirections(uint32_t n);
// Option text (viewports, direction lists, the whole CullideOptions): cullide/options.h.

// One reducePCS call: the data behind the paper's Figures 9-11.
struct PassStats {
    uint32_t level = 0;  // hierarchy depth of the PCS nodes' level (0: objects)
    uint32_t direction = 0;  // index into CullideOptions::directions
    size_t nodesIn = 0, nodesOut = 0;
    size_t trianglesIn = 0, trianglesOut = 0;
    size_t trianglesRendered = 0;  // triangles drawn, both passes together
    size_t queries = 0;
    int width = 0, height = 0;  // the call's viewport (with --resolution auto, chosen per call)
    uint32_t round = 0;  // reliable with --resolution auto: the round of calls (0, 1, ...); else 0
    double seconds = 0;  // wall time of the call, command building and backend included
};

// Adaptive resolution's default K (`--resolution auto` is auto:1: measured on the 270k bunny and
// two cows, docs/cullide.md#adaptive-resolution) and largest K.
inline constexpr double kDefaultAutoCoverage = 1;
inline constexpr double kMaxAutoCoverage = 1024;
// Pixels per call at most: 4096 x 4096 (a D24 buffer of 64 MiB).
inline constexpr int64_t kDefaultAutoBudget = int64_t(4096) * 4096;

// A PCS entry: a triangle of the scene (scene.h).
using PcsTriangle = TriangleRef;

// Switch to exact (`--exact-switch`, docs/cullide.md#switch-to-exact): when to stop image-space
// pruning and leave the rest to the exact stage. Stopping early only keeps nodes that later calls
// might have pruned, so the PCS is still a superset of the PCS the whole loop would keep (and as
// sound: the same promise, promisesToKeep); the exact stage's pairs on it are the same or more
// true pairs, never fewer.
enum class ExactSwitchKind : uint8_t {
    Never,  // the whole loop (the default; bit-identical to a run without the switch)
    Below,  // before each reducePCS call: stop when the PCS holds fewer than `triangles` triangles
    Auto,  // before each level after the first (each round of reliable's): the cost model below
    AtLevel,  // before level `level` (reliable: round `level`): replays an auto run's decision exactly
};
// The exact stage's cost in seconds per PCS triangle that `auto` assumes when no exactCost is
// given (the tools give a model calibrated on the scene): the oracle's exact stage
// (oracle::exactStage) on the whole 70k bunny and 70k two cows, 1.3-1.6 us per triangle on a
// shared two-core machine (docs/cullide.md#switch-to-exact). A fallback: the cost per triangle
// varies with the scene (12 us on data/scenes/two_cows_and_bunny.json).
inline constexpr double kExactSecondsPerTriangle = 1.5e-6;
struct ExactSwitch {
    ExactSwitchKind kind = ExactSwitchKind::Never;
    size_t triangles = 0;  // Below: the threshold N (at least 1)
    uint32_t level = 0;  // AtLevel
    // Auto: the predicted seconds of the exact stage on a PCS of n triangles (the caller's model:
    // core cannot run the oracle). Empty: n * kExactSecondsPerTriangle. Auto stops when the next
    // level's predicted time, all directions, exceeds the exact-stage time it is predicted to save,
    // exactCost(n) - exactCost(r n), n the PCS triangles and r the fraction of them the last level
    // kept (docs/cullide.md#switch-to-exact: with a PCS that keeps shrinking by r per level, no
    // later stop beats stopping now when this holds, and none is worse when it does not). The next
    // level's time is the last level's measured time (PassStats::seconds) scaled by how much
    // smaller the PCS is now than when that level began. Depends on timings: the PCS may differ
    // between runs (CullideResult records where it stopped; AtLevel replays it).
    std::function<double(size_t)> exactCost;
};

struct CullideOptions {
    CullMethod method = CullMethod::Modified;
    std::vector<Vec3d> directions = axisDirections();
    // The viewport of every reducePCS call; with adaptive resolution, the smallest one.
    int width = 500, height = 500;
    // Adaptive resolution (`--resolution auto[:K]`): 0 means fixed width x height. Otherwise K,
    // and each call chooses its own viewport (adaptiveViewport) so that the PCS it draws covers
    // about K times width x height pixels, never with coarser pixels than width x height would
    // give, at most autoBudget pixels; and the reliable method repeats its rounds of calls on the
    // shrinking PCS until one prunes nothing.
    double autoCoverage = 0;
    int64_t autoBudget = kDefaultAutoBudget;
    DepthFormat depth = DepthFormat::unorm(24);
    HierarchyOptions hierarchy;
    // Called after every reducePCS call with its statistics and the PCS it left (sorted by
    // object, then triangle), e.g. to draw the paper's Figure 12. Costs a PCS expansion per
    // call when set; nothing when empty.
    std::function<void(const PassStats&, std::span<const PcsTriangle>)> onPass;
    // Called after every reducePCS call (after onPass) with its statistics only: no PCS
    // expansion, so it costs nothing measurable, e.g. for a progress display.
    std::function<void(const PassStats&)> onPassStats;
    // Keeps each object's hierarchy across runs (frames) and reuses it while the object's
    // triangles are unchanged (hierarchy.h): the same PCS, bit for bit, without the per-frame
    // build. Empty: every run builds its hierarchies, as the paper does.
    std::shared_ptr<HierarchyCache> hierarchyCache;
    ExactSwitch exactSwitch;
    // Throws InputError naming the option on absurd values (no directions, a zero or non-finite
    // direction, a viewport outside 1..kMaxViewportSide, an adaptive K outside (0, kMaxAutoCoverage]
    // or a budget smaller than width x height, an exact switch below 1 triangle).
    void validate() const;
};

struct CullideResult {
    std::vector<PcsTriangle> pcs;  // sorted by (object, triangle)
    std::vector<PassStats> passes;
    double hierarchySeconds = 0;  // building (or reusing) every object's hierarchy
    uint32_t hierarchiesReused = 0;  // objects whose hierarchy came from options.hierarchyCache
    double totalSeconds = 0;  // everything, hierarchy and geometry upload included
    uint32_t levels = 0;  // hierarchy levels visited
    // Switch to exact: the level at which the loop stopped early (-1: it did not), the PCS
    // triangles then, and (auto) the two predictions that decided it.
    int32_t switchedAtLevel = -1;
    size_t switchedAtTriangles = 0;
    double predictedLevelSeconds = 0, predictedExactSeconds = 0;
};

// Computes the PCS of `scene` with `backend`. Throws InputError on bad options, and
// InputError("option --method", ...) for the reliable method on a backend without conservative
// rasterization.
CullideResult runCullide(const Scene& scene, DepthBackend& backend, const CullideOptions& options);
// The same for a scene the caller gives up (a frame made by Animation::sceneAt): it is emptied as
// soon as the geometry is uploaded, so that it is not in memory beside the run's own copy.
CullideResult runCullide(Scene&& scene, DepthBackend& backend, const CullideOptions& options);

// A run of triangles [first, first + count) in a geometry's triangle list.
struct TriangleRange {
    uint32_t first = 0, count = 0;
};

// The commands of one modified reducePCS call (the seed paper's Figure 3), both passes, appended
// to `list`: forward, each range in order is drawn with LESS, then queried with GREATER against
// everything drawn so far (itself included); reverse, each range from the last is queried with
// GREATER against the ranges after it, then drawn with LESS. forwardQuery[i] and reverseQuery[i]
// receive the query numbers of ranges[i] (both spans as long as `ranges`).
void appendModifiedReducePcs(CommandList& list, std::span<const TriangleRange> ranges, std::span<uint32_t> forwardQuery,
                             std::span<uint32_t> reverseQuery);

// Fits the orthographic view of direction `dir` tightly to the triangles in `ranges` (see the
// conventions above). Near and far are widened by two depth units of `depth` each, so that no
// fragment lands exactly on the cleared far value (which would make GEQUAL pass and LESS fail
// there). Exposed for tests and for the GL backend's validation.
OrthoView fitView(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                  std::span<const TriangleRange> ranges, const Vec3d& dir, int width, int height,
                  const DepthFormat& depth);

// Adaptive resolution: the viewport of one reducePCS call in direction `dir` on the triangles in
// `ranges`, a pure function of them (the same for any thread count). In the frame
// OrthoView::looking(dir), A is the sum of the triangles' projected areas: the pixels a draw of
// them covers, counted with multiplicity, is A / p^2 at pixel size p. The call wants the pixel at
// which that is `coverage` base viewports (coverage * baseWidth * baseHeight): a large PCS gets
// the base viewport, a small one finer pixels (the cost of a draw stays about that of the base's;
// the pixel count shrinks as the PCS shrinks). Never coarser than the base's pixel (fitView's at
// baseWidth x baseHeight): then the base viewport itself. Otherwise the viewport covering the
// PCS's projected bounds at the wanted pixel (the PCS's aspect, not the base's), shrunk evenly to
// at most `budget` pixels and `maxSide` per side; if that leaves it no finer than the base, the
// base viewport.
std::pair<int, int> adaptiveViewport(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                     std::span<const TriangleRange> ranges, const Vec3d& dir, double coverage,
                                     int baseWidth, int baseHeight, int64_t budget, int maxSide);

}  // namespace cullide
