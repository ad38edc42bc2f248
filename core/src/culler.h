// The Culler: one run of Cullide (the seed paper's Figure 1 loop, with the original or modified
// reducePCS of Figures 2 and 3) or of the reliable method, on one scene and one DepthBackend.
// runCullide (cullide.h) makes one per run. Private to core/.
//
// Its files: culler.cpp (the run: hierarchies and upload, the levels, the PCS's triangles, the
// exact switch, directions), culler_call.cpp (one reducePCS call: views, tiles, command lists,
// statistics), culler_reliable.cpp (the reliable method's leaves, rounds and calls).
#pragma once

#include "cullide/cullide.h"

#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

namespace cullide::detail {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

class Culler {
public:
    // One node of the PCS: an object's hierarchy node, and its triangles in the uploaded geometry.
    struct Item {
        uint32_t object = 0, node = 0;
        TriangleRange range;
    };

    // `consumed`: the scene (the same object) may be emptied once the geometry is uploaded.
    Culler(const Scene& scene, DepthBackend& backend, const CullideOptions& opt, Scene* consumed = nullptr)
        : scene_(scene), backend_(backend), opt_(opt), consumed_(consumed) {}
    ~Culler() {
        if (lent_) backend_.borrowGeometry({}, {});  // the arrays die with this run
    }
    Culler(const Culler&) = delete;
    Culler& operator=(const Culler&) = delete;

    CullideResult run();

private:
    // The run (culler.cpp).
    void build(CullideResult& result);
    std::vector<Mesh> buildHierarchies(CullideResult& result);
    void upload(std::vector<Mesh>& world);
    void startRecordingPrunes(CullideResult& result);
    void runLevels(CullideResult& result);
    std::vector<Item> roots() const;
    std::vector<Item> children(const std::vector<Item>& pcs) const;
    std::vector<std::pair<uint32_t, Vec3d>> callDirections(const std::vector<Item>& pcs, uint32_t step);
    void recordHistory(const CullideResult&);
    std::vector<PcsTriangle> expand(const std::vector<Item>& items) const;
    bool switchNow(const std::vector<Item>& pcs, uint32_t level, bool groupStart, CullideResult& result) const;

    const HierarchyNode& node(const Item& it) const { return hierarchies_[it.object]->nodes[it.node]; }

    Item item(uint32_t object, uint32_t nodeIndex) const {
        const HierarchyNode& n = hierarchies_[object]->nodes[nodeIndex];
        return {object, nodeIndex, {triangleOffset_[object] + n.first, n.count}};
    }

    // The reliable method (culler_reliable.cpp).
    void runReliable(CullideResult& result);
    std::vector<Item> leafUnits(uint32_t& depth) const;
    void markExactHits(const std::vector<Item>& pcs);
    std::vector<Item> reduceReliable(const std::vector<Item>& pcs, uint32_t level, uint32_t d,
                                     std::vector<PassStats>& passes);
    std::vector<uint8_t> testUnits(const std::vector<Item>& pcs);

    // One reducePCS call (culler_call.cpp).
    std::vector<Item> reduce(const std::vector<Item>& pcs, uint32_t level, uint32_t d, std::vector<PassStats>& passes);
    std::vector<uint8_t> testNodes(const std::vector<Item>& pcs);
    template <typename Test, typename Undrawn>
    std::vector<Item> byViews(const std::vector<Item>& pcs, Test&& test, Undrawn&& undrawn);
    // ranges_: the triangles of each node of `pcs`.
    void setRanges(const std::vector<Item>& pcs) {
        ranges_.clear();
        for (const Item& it : pcs) ranges_.push_back(it.range);
    }
    void setView();
    OrthoView wholeFit(int w, int h);
    std::vector<uint64_t> execute();
    void countView(Command::Op drawOp);
    void recordPrunes(const std::vector<Item>& pcs, const std::vector<Item>& kept, uint32_t call);
    std::vector<Item> finishCall(const std::vector<Item>& pcs, std::vector<Item> kept, uint32_t level, uint32_t d,
                                 Clock::time_point start, std::vector<PassStats>& passes);

    // options.recordPrunes: result.prunedAtCall, each object's first triangle in it, and a mark
    // per node (all clear between calls).
    std::vector<uint32_t>* prunedAt_ = nullptr;
    std::vector<size_t> sceneOffset_;
    std::vector<std::vector<uint8_t>> keptMark_;

    const Scene& scene_;
    DepthBackend& backend_;
    const CullideOptions& opt_;
    Scene* consumed_;
    bool lent_ = false;  // the backend reads positions_ and triangles_ in place
    std::vector<Hierarchy> built_;  // without a cache: this run's hierarchies
    std::vector<const Hierarchy*> hierarchies_;  // per object: in built_ or in the cache
    std::vector<uint32_t> triangleOffset_;
    std::vector<Vec3f> positions_;
    std::vector<Triangle> triangles_;
    std::vector<TriangleRange> ranges_;
    CommandList list_;
    OrthoView view_;  // the current view's
    // The current call's views so far: triangles rendered, queries, the largest viewport, count.
    struct ViewTotals {
        size_t rendered = 0, queries = 0;
        int width = 0, height = 0;
        uint32_t count = 0, tiles = 0;
    } views_;
    std::vector<OrthoView> tiles_;  // the current view's tiles (empty: drawn whole)
    Vec3d dir_ = Vec3d::Zero();  // the current call's direction
    static constexpr size_t kWholeFits = 64;
    std::vector<std::pair<Vec3d, OrthoView>> wholeFits_;  // wholeFit's: (direction, view)
    uint32_t step_ = 0;  // the current level (reliable: round), for the coherent history
    std::vector<std::vector<size_t>> stepPruned_;  // coherent: [step][direction] triangles pruned
    uint32_t round_ = 0;  // reliable with adaptive resolution: the current round of calls
    std::vector<std::vector<uint8_t>> exactHit_;  // reliable: per object and node, an exact pair may intersect
    std::vector<uint32_t> objects_;  // the original method's view: the object of each of ranges_
};

// The nodes of `pcs` that stay after a call in direction dir_, in `pcs` order. With one view
// (ViewMode::Fit, or a single group) `test(pcs)` draws them all, as the paper does. Otherwise
// each group of viewGroups is drawn on its own by `test(group)`, with its own fitted view and
// command list, unless `undrawn(group)` already says which of its nodes stay (non-empty).
// Why that keeps every method's promise: the triangles of nodes in different groups have
// disjoint projections in the call's frame, so no two of them cross or touch; whatever a
// method promises is about such pairs, and each group's call is a call of the method on a PCS
// of its own (any view will do: docs/cullide.md#views-per-cluster).
template <typename Test, typename Undrawn>
std::vector<Culler::Item> Culler::byViews(const std::vector<Item>& pcs, Test&& test, Undrawn&& undrawn) {
    views_ = {};
    std::vector<std::vector<uint32_t>> groups;
    if (opt_.views == ViewMode::Clustered && pcs.size() > 1) {
        setRanges(pcs);
        groups = viewGroups(positions_, triangles_, ranges_, dir_);
    }
    std::vector<uint8_t> stays;
    if (groups.size() <= 1) {
        stays = test(pcs);
    } else {
        stays.assign(pcs.size(), 0);
        std::vector<Item> group;
        for (const std::vector<uint32_t>& members : groups) {
            group.clear();
            for (uint32_t i : members) group.push_back(pcs[i]);
            std::vector<uint8_t> s = undrawn(group);
            if (s.empty()) s = test(group);
            for (size_t k = 0; k < members.size(); ++k) stays[members[k]] = s[k];
        }
    }
    std::vector<Item> kept;
    for (size_t i = 0; i < pcs.size(); ++i)
        if (stays[i]) kept.push_back(pcs[i]);
    return kept;
}

}  // namespace cullide::detail
