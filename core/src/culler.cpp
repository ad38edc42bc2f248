// The Culler's run (culler.h): the hierarchies and the geometry upload, the loop over the levels
// (the seed paper's Figure 1), each call's directions, the exact switch and the PCS's triangles;
// and runCullide. docs/paper.md#figure-1; see cullide.h.
#include "culler.h"

#include "cullide/error.h"
#include "cullide/parallel.h"

#include <algorithm>
#include <limits>
#include <numeric>

namespace cullide {

namespace detail {

CullideResult Culler::run() {
    const auto start = Clock::now();
    CullideResult result;
    build(result);
    if (opt_.recordPrunes) startRecordingPrunes(result);
    if (opt_.method == CullMethod::Reliable) runReliable(result);
    else runLevels(result);
    recordHistory(result);
    result.totalSeconds = secondsSince(start);
    return result;
}

// World meshes, hierarchies, and the geometry upload (each object's triangles in hierarchy order).
void Culler::build(CullideResult& result) {
    std::vector<Mesh> world = buildHierarchies(result);
    upload(world);
}

// Each object's world mesh (returned) and hierarchy (built, or from the cache).
std::vector<Mesh> Culler::buildHierarchies(CullideResult& result) {
    const size_t n = scene_.objects.size();
    const auto start = Clock::now();
    std::vector<Mesh> world(n);
    hierarchies_.resize(n);
    HierarchyCache* cache = opt_.hierarchyCache.get();
    if (cache) cache->resize(n);
    else built_.resize(n);
    parallelForEach(0, n, [&](size_t i) {
        world[i] = scene_.worldMesh(i);
        if (cache) {
            hierarchies_[i] = &cache->get(i, world[i], opt_.hierarchy);
        } else {
            built_[i] = buildHierarchy(world[i], opt_.hierarchy);
            hierarchies_[i] = &built_[i];
        }
    });
    result.hierarchySeconds = secondsSince(start);
    if (cache)
        for (size_t i = 0; i < n; ++i) result.hierarchiesReused += cache->reused(i) ? 1 : 0;
    return world;
}

// The geometry the backend draws: every object's triangles in hierarchy order, after the
// objects before it. Empties `world` (and the consumed scene).
void Culler::upload(std::vector<Mesh>& world) {
    const size_t n = world.size();
    triangleOffset_.assign(n, 0);
    size_t vertices = 0, triangles = 0;
    for (size_t i = 0; i < n; ++i) {
        triangleOffset_[i] = uint32_t(triangles);
        vertices += world[i].positions.size();
        triangles += world[i].triangles.size();
    }
    if (vertices > std::numeric_limits<uint32_t>::max() || triangles > std::numeric_limits<uint32_t>::max())
        throw InputError("scene", "more than 2^32 vertices or triangles");
    positions_.clear();
    positions_.reserve(vertices);
    triangles_.clear();
    triangles_.reserve(triangles);
    // Each object's vertices are renumbered in the order its triangles, in hierarchy order,
    // first use them (unused ones dropped): a node's triangles then read nearby vertices, so
    // every pass over a draw (its view's fit, setup's gathers) stays in cache. Only indices
    // change, and which triangles share a vertex does not: the same images and PCS.
    std::vector<uint32_t> renumber;
    for (size_t i = 0; i < n; ++i) {
        renumber.assign(world[i].positions.size(), UINT32_MAX);
        for (uint32_t t : hierarchies_[i]->order) {
            const Triangle& tri = world[i].triangles[t];
            Triangle out;
            for (int k = 0; k < 3; ++k) {
                uint32_t& v = renumber[tri[k]];
                if (v == UINT32_MAX) {
                    v = uint32_t(positions_.size());
                    positions_.push_back(world[i].positions[tri[k]]);
                }
                out[k] = v;
            }
            triangles_.push_back(out);
        }
    }
    world = {};
    if (consumed_) *consumed_ = Scene{};  // scene_ is not read after build()
    // Lent, not copied, where the backend can read it in place: positions_ and triangles_
    // live and stay unchanged until the destructor takes them back.
    lent_ = backend_.borrowGeometry(positions_, triangles_);
}

// options.recordPrunes: result.prunedAtCall, all kNotPruned, and the marks recordPrunes uses.
void Culler::startRecordingPrunes(CullideResult& result) {
    sceneOffset_.assign(hierarchies_.size() + 1, 0);
    keptMark_.resize(hierarchies_.size());
    for (size_t i = 0; i < hierarchies_.size(); ++i) {
        sceneOffset_[i + 1] = sceneOffset_[i] + hierarchies_[i]->order.size();
        keptMark_[i].assign(hierarchies_[i]->nodes.size(), 0);
    }
    result.prunedAtCall.assign(sceneOffset_.back(), CullideResult::kNotPruned);
    prunedAt_ = &result.prunedAtCall;
}

// The loop (Figure 1): per level, one reducePCS call per direction on the current PCS, then
// the children replace their parents, until the PCS is empty, holds only leaves, or the exact
// switch stops it.
void Culler::runLevels(CullideResult& result) {
    std::vector<Item> pcs = roots();
    bool switched = false;  // to the exact stage (CullideOptions::exactSwitch)
    for (uint32_t level = 0; !pcs.empty(); ++level) {
        const std::vector<std::pair<uint32_t, Vec3d>> dirs = callDirections(pcs, level);
        for (size_t k = 0; k < dirs.size() && !pcs.empty(); ++k) {
            if ((switched = switchNow(pcs, level, k == 0, result))) break;
            result.levels = level + 1;
            dir_ = dirs[k].second;
            pcs = reduce(pcs, level, dirs[k].first, result.passes);
        }
        if (switched) break;
        if (dirs.empty()) result.levels = level + 1;  // coherent: a level with no call is still visited
        bool allLeaves = true;
        for (const Item& it : pcs) allLeaves = allLeaves && node(it).isLeaf();
        if (pcs.empty() || allLeaves) break;
        pcs = children(pcs);
    }
    result.pcs = expand(pcs);
}

// Level 0: every object's root that holds triangles.
std::vector<Culler::Item> Culler::roots() const {
    std::vector<Item> pcs;
    for (uint32_t i = 0; i < hierarchies_.size(); ++i)
        if (!hierarchies_[i]->nodes.empty() && hierarchies_[i]->nodes[0].count > 0) pcs.push_back(item(i, 0));
    return pcs;
}

// The next level's PCS: children replace their parent in place, so objects stay contiguous;
// leaves stay as they are.
std::vector<Culler::Item> Culler::children(const std::vector<Item>& pcs) const {
    std::vector<Item> next;
    for (const Item& it : pcs) {
        const HierarchyNode& n = node(it);
        if (n.isLeaf()) next.push_back(it);
        else
            for (uint32_t c = 0; c < n.childCount; ++c) next.push_back(item(it.object, n.firstChild + c));
    }
    return next;
}

// The directions of this run's calls on `pcs` at `step` (the level, or a reliable round): (the
// index PassStats::direction records, the direction). Fixed: the given list; Coherent: the
// history's plan for the step; Pca: pcaDirections of the PCS.
std::vector<std::pair<uint32_t, Vec3d>> Culler::callDirections(const std::vector<Item>& pcs, uint32_t step) {
    step_ = step;
    std::vector<std::pair<uint32_t, Vec3d>> out;
    if (opt_.directionMode == DirectionMode::Pca) {
        setRanges(pcs);
        const std::vector<Vec3d> dirs = pcaDirections(positions_, triangles_, ranges_);
        for (uint32_t k = 0; k < dirs.size(); ++k) out.push_back({k, dirs[k]});
        return out;
    }
    const size_t n = opt_.directions.size();
    if (opt_.directionMode == DirectionMode::Coherent && opt_.directionHistory) {
        for (uint32_t d : opt_.directionHistory->plan(step, n)) out.push_back({d, opt_.directions[d]});
    } else {
        for (uint32_t d = 0; d < n; ++d) out.push_back({d, opt_.directions[d]});
    }
    return out;
}

void Culler::recordHistory(const CullideResult&) {
    if (opt_.directionMode == DirectionMode::Coherent && opt_.directionHistory)
        opt_.directionHistory->record(opt_.directions.size(), std::move(stepPruned_));
}

// The triangles of the given nodes (disjoint), as (object, triangle) sorted. Where many of an
// object's triangles are asked for (onPass after the first levels: most of the mesh), they are
// marked and read back in order, linear in the object's size; a few are sorted.
std::vector<PcsTriangle> Culler::expand(const std::vector<Item>& items) const {
    const size_t objects = hierarchies_.size();
    std::vector<size_t> start(objects + 1, 0), triangles(objects, 0);  // items by object (counting sort)
    for (const Item& it : items) ++start[it.object + 1], triangles[it.object] += node(it).count;
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<uint32_t> byObject(items.size());
    std::vector<size_t> fill(start.begin(), start.end() - 1);
    for (uint32_t i = 0; i < items.size(); ++i) byObject[fill[items[i].object]++] = i;

    std::vector<PcsTriangle> out;
    out.reserve(std::accumulate(triangles.begin(), triangles.end(), size_t(0)));
    std::vector<uint8_t> marks;
    for (uint32_t o = 0; o < objects; ++o) {
        if (triangles[o] == 0) continue;
        const std::vector<uint32_t>& order = hierarchies_[o]->order;
        const bool dense = triangles[o] * 8 >= order.size();
        const size_t from = out.size();
        if (dense) marks.assign(order.size(), 0);
        for (size_t b = start[o]; b < start[o + 1]; ++b) {
            const HierarchyNode& n = node(items[byObject[b]]);
            for (uint32_t k = n.first; k < n.first + n.count; ++k) {
                if (dense) marks[order[k]] = 1;
                else out.push_back({o, order[k]});
            }
        }
        if (dense) {
            for (uint32_t t = 0; t < marks.size(); ++t)
                if (marks[t]) out.push_back({o, t});
        } else {
            std::sort(out.begin() + ptrdiff_t(from), out.end());
        }
    }
    return out;
}

// Switch to exact (ExactSwitch): whether to stop before the next reducePCS call on `pcs`, at
// `level`; `groupStart`: the call begins a level (a round for reliable) after the first, where
// auto predicts. Records the switch in `result`.
bool Culler::switchNow(const std::vector<Item>& pcs, uint32_t level, bool groupStart, CullideResult& result) const {
    const ExactSwitch& sw = opt_.exactSwitch;
    if (sw.kind == ExactSwitchKind::Never) return false;
    size_t triangles = 0;
    for (const Item& it : pcs) triangles += it.range.count;
    bool stop = false;
    if (sw.kind == ExactSwitchKind::Below) {
        stop = triangles < sw.triangles;
    } else if (sw.kind == ExactSwitchKind::AtLevel) {
        stop = groupStart && (opt_.method == CullMethod::Reliable ? round_ : level) == sw.level;
    } else if (groupStart && !result.passes.empty()) {
        // The last level's (round's) calls: their time, scaled by the PCS's shrinking since,
        // and the fraction of the PCS they kept.
        const PassStats& last = result.passes.back();
        double seconds = 0;
        size_t first = result.passes.size();
        while (first > 0 && result.passes[first - 1].level == last.level &&
               result.passes[first - 1].round == last.round)
            seconds += result.passes[--first].seconds;
        const size_t began = result.passes[first].trianglesIn;
        const double kept = began ? double(last.trianglesOut) / double(began) : 1;
        auto exact = [&](size_t n) {
            return sw.exactCost ? sw.exactCost(n) : double(n) * kExactSecondsPerTriangle;
        };
        result.predictedLevelSeconds = began ? seconds * double(triangles) / double(began) : 0;
        result.predictedExactSeconds = exact(triangles);
        const double saved = result.predictedExactSeconds - exact(size_t(std::llround(kept * double(triangles))));
        stop = result.predictedLevelSeconds > saved;  // false when saved is NaN (an infinite model)
    }
    if (stop) result.switchedAtLevel = int32_t(level), result.switchedAtTriangles = triangles;
    return stop;
}

}  // namespace detail

namespace {
void checkRunnable(DepthBackend& backend, const CullideOptions& options) {
    options.validate();
    if (options.method == CullMethod::Reliable && !backend.supportsConservative())
        throw InputError(
            "option --method",
            "reliable is CPU-only: this backend (" + backend.describe() + ") has no conservative rasterization");
}
}  // namespace

CullideResult runCullide(const Scene& scene, DepthBackend& backend, const CullideOptions& options) {
    checkRunnable(backend, options);
    return detail::Culler(scene, backend, options).run();
}

CullideResult runCullide(Scene&& scene, DepthBackend& backend, const CullideOptions& options) {
    checkRunnable(backend, options);
    return detail::Culler(scene, backend, options, &scene).run();
}

}  // namespace cullide
