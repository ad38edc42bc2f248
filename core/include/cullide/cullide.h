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
//     tiny box around it so the view stays valid. With ViewMode::Clustered, one such view per
//     group of nodes whose projections overlap (viewGroups), each with its own command list.
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

// A run of triangles [first, first + count) in a geometry's triangle list.
struct TriangleRange {
    uint32_t first = 0, count = 0;
};

struct PassStats;

// Chosen directions (docs/cullide.md#chosen-directions): where each reducePCS call looks.
enum class DirectionMode : uint8_t {
    // CullideOptions::directions, in the given order, at every level (the paper's way; the default).
    Fixed,
    // Per level, six directions chosen from the current PCS: the principal axes of its triangles'
    // area-weighted orientation tensor (pcaFrame), turned to the frame that faces the PCS best
    // (pcaDirections), both signs of each. CullideOptions::directions is not used.
    Pca,
    // Across frames (CullideOptions::directionHistory), per level: the directions of
    // CullideOptions::directions that pruned anything at that level in the previous frame, in the
    // given order (DirectionHistory::plan), with the full list on the first frame and every
    // DirectionHistory::period-th frame.
    Coherent,
};
const char* toString(DirectionMode m);  // "fixed" | "pca" | "coherent"

// The principal axes of the orientations of the triangles in `ranges`: the eigenvectors of
// T = sum over triangles of area * n n^T (n the unit normal), by Eigen's SelfAdjointEigenSolver,
// largest eigenvalue first, each with its largest-magnitude component positive (the first such on
// a tie). Summed per piece of at most 4096 triangles and then in piece order: the same for any
// thread count. Empty when the triangles have no area (or T is not finite).
std::vector<Vec3d> pcaFrame(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                            std::span<const TriangleRange> ranges);
// The six directions of DirectionMode::Pca for these triangles: the orthonormal frame that faces
// them best, as +v1, -v1, +v2, -v2, +v3, -v3 (each v sign-fixed as in pcaFrame). Candidates are
// the pcaFrame itself and 512 fixed turns of it (64 first axes, the upper half of a 128-direction
// Fibonacci lattice, x 8 turns about each over a quarter turn), defined in pcaFrame's coordinates
// so that the choice turns with the geometry. The score of a frame is the area-weighted sum over
// the triangles of min(1/3, min over its three axes of |n . v|), the normals binned (folded to one
// sign, a cube map of 3 x 16 x 16 cells, summed per piece as in pcaFrame): a triangle seen nearly
// edge-on from any axis costs, one faced by at least 1/3 from every axis does not (the most a frame
// can promise all three principal orientations). The first best candidate wins. The principal
// axes themselves are no good views: on axis-aligned geometry they are the axes, and for two
// sheets crossing along a line one axis is that line, seen edge-on by both. No area: the axes.
std::vector<Vec3d> pcaDirections(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                 std::span<const TriangleRange> ranges);

// Coherent directions' default period: a full check of the whole list every 8th frame (frames 0,
// 8, 16, ... of a run of `prune`), so that a direction dropped while it pruned nothing is tried
// again within 8 frames.
inline constexpr uint32_t kDefaultCoherentPeriod = 8;

// What DirectionMode::Coherent carries from frame to frame (like HierarchyCache: shared by the
// frames' options, changed by every run that has it).
struct DirectionHistory {
    uint32_t period = kDefaultCoherentPeriod;  // >= 1; 1: every frame is a full check
    uint64_t frames = 0;  // runs recorded so far
    size_t count = 0;  // the length of the last run's fixed list
    // pruned[level][d]: the triangles that direction d of the fixed list pruned at that level of
    // the last run (the reliable method: in that round).
    std::vector<std::vector<size_t>> pruned;
    // The directions (indices into a fixed list of `count`) of this run's calls at `level`, in
    // order: the full list 0..count-1 on a full check (the first run, every period-th, a list of
    // another length) or at a level the last run did not reach; otherwise those with pruned > 0
    // at that level, in the given order: none when nothing pruned there (the level then makes no
    // call).
    std::vector<uint32_t> plan(uint32_t level, size_t count) const;
    // Records a run with a fixed list of `count` directions and what each pruned per level.
    void record(size_t count, std::vector<std::vector<size_t>> prunedPerLevel);
};

// One reducePCS call: the data behind the paper's Figures 9-11.
struct PassStats {
    uint32_t level = 0;  // hierarchy depth of the PCS nodes' level (0: objects)
    // Index into the level's list of directions: CullideOptions::directions (Fixed, Coherent) or
    // the level's pcaDirections (Pca).
    uint32_t direction = 0;
    Vec3d dirVector = Vec3d::Zero();  // the direction itself (unit)
    size_t nodesIn = 0, nodesOut = 0;
    size_t trianglesIn = 0, trianglesOut = 0;
    size_t trianglesRendered = 0;  // triangles drawn, both passes together
    size_t queries = 0;
    int width = 0, height = 0;  // the call's viewport (with --resolution auto, chosen per call)
    uint32_t round = 0;  // reliable with --resolution auto: the round of calls (0, 1, ...); else 0
    // Views drawn (ViewMode::Clustered: the groups drawn, each with its own view and command list;
    // else 1). width x height is then the largest of their viewports (by pixel count); the
    // triangles rendered and queries are the sums over them.
    uint32_t views = 1;
    // Executions of the call's command lists: its views, each counted once per tile it was drawn
    // in (a viewport larger than DepthBackend::maxViewportSide() is drawn in tiles; else = views).
    uint32_t tiles = 1;
    double seconds = 0;  // wall time of the call, command building and backend included
};

// Adaptive resolution's default K (`--resolution auto` is auto:1: measured on the 270k bunny and
// two cows, docs/cullide.md#adaptive-resolution) and largest K.
inline constexpr double kDefaultAutoCoverage = 1;
inline constexpr double kMaxAutoCoverage = 1024;
// Pixels per call at most: 4096 x 4096 (a D24 buffer of 64 MiB).
inline constexpr int64_t kDefaultAutoBudget = int64_t(4096) * 4096;

// How each reducePCS call views the PCS (`--views`, docs/cullide.md#views-per-cluster).
enum class ViewMode : uint8_t {
    // One view fitted to the whole PCS (the paper's).
    Fit,
    // The PCS nodes are grouped by their projected rectangles in the call's frame (connected
    // components of overlap, touching included); each group gets its own fitted view and command
    // list. Nodes of different groups have disjoint projections, so their triangles can neither
    // cross nor touch: no method's promise depends on testing them against each other.
    Clustered,
};
const char* toString(ViewMode m);
ViewMode parseViewMode(const std::string& text);  // "fit" | "clustered"; InputError("option --views", ...)

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
    DirectionMode directionMode = DirectionMode::Fixed;
    // Coherent: the history across frames (runs); empty: every run is a full check (first frame).
    std::shared_ptr<DirectionHistory> directionHistory;
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
    ViewMode views = ViewMode::Fit;
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
    // Fills CullideResult::prunedAtCall: which call pruned each triangle. Costs a write per pruned
    // triangle over the run (not a PCS expansion per call, as onPass does).
    bool recordPrunes = false;
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
    // With options.recordPrunes: per triangle of the scene (objects in order, each object's
    // triangles in order), the index in `passes` of the call that pruned it, or kNotPruned (still
    // in the PCS). Empty otherwise.
    static constexpr uint32_t kNotPruned = UINT32_MAX;
    std::vector<uint32_t> prunedAtCall;
};

// Computes the PCS of `scene` with `backend`. Throws InputError on bad options, and
// InputError("option --method", ...) for the reliable method on a backend without conservative
// rasterization.
CullideResult runCullide(const Scene& scene, DepthBackend& backend, const CullideOptions& options);
// The same for a scene the caller gives up (a frame made by Animation::sceneAt): it is emptied as
// soon as the geometry is uploaded, so that it is not in memory beside the run's own copy.
CullideResult runCullide(Scene&& scene, DepthBackend& backend, const CullideOptions& options);

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

// ViewMode::Clustered's groups: the items of `ranges` (PCS nodes) whose projected rectangles in the
// frame OrthoView::looking(dir) overlap or touch, transitively (closed rectangles, each widened by
// a relative 1e-9 of its vertices' magnitude so that rounding in the projection can never
// separate two nodes that share a point). Each group lists its items' indices in increasing
// order; the groups are ordered by their first item. Deterministic, the same for any thread count.
std::vector<std::vector<uint32_t>> viewGroups(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                              std::span<const TriangleRange> ranges, const Vec3d& dir);

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
// base viewport. (runCullide passes kMaxViewportSide: a backend that draws less per side gets the
// call in tiles, docs/cullide.md#adaptive-resolution.)
std::pair<int, int> adaptiveViewport(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                     std::span<const TriangleRange> ranges, const Vec3d& dir, double coverage,
                                     int baseWidth, int baseHeight, int64_t budget, int maxSide);

}  // namespace cullide
