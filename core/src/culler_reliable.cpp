// The reliable method in the Culler (culler.h, docs/reliable.md): straight to the hierarchy's
// leaves (the units), their exact checks once, then rounds of reliable reducePCS calls.
#include "culler.h"

#include "reduce_pcs.h"
#include "reliable.h"

#include <algorithm>

namespace cullide::detail {

// The reliable method (docs/reliable.md): straight to the leaves, whose internal and adjacent
// pairs only an exact check can clear (a node above them can never be pruned soundly without
// knowing its own pairs); then one reliable reducePCS per direction.
void Culler::runReliable(CullideResult& result) {
    uint32_t depth = 0;
    std::vector<Item> pcs = leafUnits(depth);
    result.levels = pcs.empty() ? 0 : 1;
    markExactHits(pcs);
    // With adaptive resolution, rounds of calls until one prunes nothing: each round's views are
    // refitted to the smaller PCS, so its pixels are finer. Every call is sound on its own
    // (docs/reliable.md), so any number of them is.
    bool switched = false;  // to the exact stage: before a call, or (auto) before a round after the first
    for (round_ = 0; !switched; ++round_) {
        const size_t before = pcs.size();
        const std::vector<std::pair<uint32_t, Vec3d>> dirs = callDirections(pcs, round_);
        for (size_t k = 0; k < dirs.size() && !pcs.empty(); ++k) {
            if ((switched = switchNow(pcs, depth, k == 0 && round_ > 0, result))) break;
            dir_ = dirs[k].second;
            pcs = reduceReliable(pcs, depth, dirs[k].first, result.passes);
        }
        if (switched || opt_.autoCoverage <= 0 || pcs.empty() || pcs.size() == before) break;
    }
    result.pcs = expand(pcs);
}

// The units: every object's leaves that hold triangles, each object's in geometry order; `depth`
// becomes the deepest one's depth.
std::vector<Culler::Item> Culler::leafUnits(uint32_t& depth) const {
    std::vector<Item> pcs;
    for (uint32_t i = 0; i < hierarchies_.size(); ++i) {
        const Hierarchy& h = *hierarchies_[i];
        std::vector<Item> leaves;
        for (uint32_t k = 0; k < h.nodes.size(); ++k)
            if (h.nodes[k].isLeaf() && h.nodes[k].count > 0) {
                leaves.push_back(item(i, k));
                depth = std::max(depth, h.nodes[k].depth);
            }
        std::sort(leaves.begin(), leaves.end(),
                  [](const Item& a, const Item& b) { return a.range.first < b.range.first; });
        pcs.insert(pcs.end(), leaves.begin(), leaves.end());
    }
    return pcs;
}

// exactHit_: per object and node, whether an exact check found a pair that may intersect. Pairs
// inside a leaf and between leaves sharing a vertex are checked once, here.
void Culler::markExactHits(const std::vector<Item>& pcs) {
    setRanges(pcs);
    const UnitGraph all = unitAdjacency(triangles_, ranges_);
    const std::vector<uint8_t> hits = exactHits(positions_, triangles_, ranges_, all);
    exactHit_.assign(hierarchies_.size(), {});
    for (uint32_t i = 0; i < hierarchies_.size(); ++i) exactHit_[i].assign(hierarchies_[i]->nodes.size(), 0);
    for (size_t u = 0; u < pcs.size(); ++u) exactHit_[pcs[u].object][pcs[u].node] = hits[u];
}

// One reliable reducePCS call in direction d (docs/reliable.md). Units are the PCS leaves; each
// view's command list is appendReliableReducePcs's.
std::vector<Culler::Item> Culler::reduceReliable(const std::vector<Item>& pcs, uint32_t level, uint32_t d,
                                                  std::vector<PassStats>& passes) {
    const auto start = Clock::now();
    // A unit alone in its view has no unit to be tested against: it stays for its exact pairs only.
    std::vector<Item> kept = byViews(
        pcs, [&](const std::vector<Item>& units) { return testUnits(units); },
        [&](const std::vector<Item>& units) {
            return units.size() == 1 ? std::vector<uint8_t>{exactHit_[units[0].object][units[0].node]}
                                     : std::vector<uint8_t>{};
        });
    return finishCall(pcs, std::move(kept), level, d, start, passes);
}

// One reliable view: which of `pcs` stay (a conflict or an exact pair).
std::vector<uint8_t> Culler::testUnits(const std::vector<Item>& pcs) {
    setRanges(pcs);
    setView();
    const uint32_t n = uint32_t(pcs.size());
    const UnitGraph g = unitAdjacency(triangles_, ranges_);
    const std::vector<uint32_t> colour = distanceTwoColouring(g);
    list_.reset();
    const std::vector<std::pair<uint32_t, uint32_t>> queries = appendReliableReducePcs(list_, ranges_, g, colour);
    const std::vector<uint64_t> results = execute();
    std::vector<uint8_t> conflict(n, 0);
    for (const auto& [u, q] : queries) conflict[u] |= results[q] > 0 ? 1 : 0;

    std::vector<uint8_t> stays(n);
    for (uint32_t u = 0; u < n; ++u) stays[u] = conflict[u] || exactHit_[pcs[u].object][pcs[u].node];
    countView(Command::Op::DrawConservative);
    return stays;
}

}  // namespace cullide::detail
