// One reducePCS call of the Culler (culler.h): the original or modified method's view of the PCS
// (its fitted view, tiles, command list and results), and the call's statistics and recorded
// prunes. docs/paper.md#figure-2, #figure-3; see cullide.h.
#include "culler.h"

#include "reduce_pcs.h"
#include "view_fit.h"

#include "cullide/error.h"

#include <algorithm>
#include <tuple>

namespace cullide::detail {

// One reducePCS call in direction d: returns the nodes that stay.
std::vector<Culler::Item> Culler::reduce(const std::vector<Item>& pcs, uint32_t level, uint32_t d,
                                          std::vector<PassStats>& passes) {
    const auto start = Clock::now();
    // The original method tests a node against the other objects only: in a view of one
    // object's nodes every node is fully visible, pruned without drawing. The modified method
    // tests a node against itself too, so even a lone node is drawn.
    std::vector<Item> kept = byViews(
        pcs, [&](const std::vector<Item>& nodes) { return testNodes(nodes); },
        [&](const std::vector<Item>& nodes) {
            const bool oneObject = std::all_of(nodes.begin(), nodes.end(),
                                               [&](const Item& it) { return it.object == nodes[0].object; });
            return opt_.method == CullMethod::Original && oneObject ? std::vector<uint8_t>(nodes.size(), 0)
                                                                    : std::vector<uint8_t>{};
        });
    return finishCall(pcs, std::move(kept), level, d, start, passes);
}

// One view of a modified or original call: which of `pcs` stay (not fully visible).
std::vector<uint8_t> Culler::testNodes(const std::vector<Item>& pcs) {
    setRanges(pcs);
    setView();

    list_.reset();
    // forwardQuery[i] / reverseQuery[i]: the query numbers of PCS item i in each pass.
    std::vector<uint32_t> forwardQuery(pcs.size()), reverseQuery(pcs.size());
    if (opt_.method == CullMethod::Modified) {
        appendModifiedReducePcs(list_, ranges_, forwardQuery, reverseQuery);  // Figure 3
    } else {
        objects_.clear();
        for (const Item& it : pcs) objects_.push_back(it.object);
        appendOriginalReducePcs(list_, ranges_, objects_, forwardQuery, reverseQuery);  // Figure 2
    }

    const std::vector<uint64_t> results = execute();
    std::vector<uint8_t> stays(pcs.size());
    for (size_t i = 0; i < pcs.size(); ++i) {
        const bool fullyVisible = results[forwardQuery[i]] == 0 && results[reverseQuery[i]] == 0;
        stays[i] = !fullyVisible;
    }
    countView(Command::Op::Draw);
    return stays;
}

// The view of a call in direction dir_ on ranges_: fitted at the fixed viewport, or at the one
// adaptive resolution chooses for these triangles. A viewport larger than the backend draws is
// cut into tiles_ of its largest side (row by row from the bottom-left), which execute() runs
// one after the other; else tiles_ is empty and the backend gets the whole view here.
void Culler::setView() {
    int w = opt_.width, h = opt_.height;
    if (opt_.autoCoverage > 0)
        std::tie(w, h) = adaptiveViewport(positions_, triangles_, ranges_, dir_, opt_.autoCoverage, opt_.width,
                                          opt_.height, opt_.autoBudget, kMaxViewportSide);
    size_t drawn = 0;
    for (const TriangleRange& r : ranges_) drawn += r.count;
    // Every triangle drawn (the first levels): positions_ holds only used vertices (build()
    // drops the others), so their bounds are the triangles'.
    view_ = drawn == triangles_.size() ? wholeFit(w, h)
                                       : fitView(positions_, triangles_, ranges_, dir_, w, h, opt_.depth);
    tiles_.clear();
    const int side = std::clamp(backend_.maxViewportSide(), 1, kMaxViewportSide);
    if (w <= side && h <= side) {
        backend_.setView(view_);
        return;
    }
    for (int y = 0; y < h; y += side)
        for (int x = 0; x < w; x += side)
            tiles_.push_back(view_.tile(x, y, std::min(side, w - x), std::min(side, h - y)));
}

// fitViewToPoints in direction dir_ at w x h, computed once per run: it depends on the
// direction and viewport only (positions_ is fixed after build()), and the first levels draw
// every triangle in the same directions level after level (the bunny's levels 0-2: 18 fits of
// 6 views, 3-4% of a prune on one thread). At most kWholeFits are kept (per-level PCA
// directions make new ones); later ones are computed every time.
OrthoView Culler::wholeFit(int w, int h) {
    for (const auto& [d, v] : wholeFits_)
        if (d == dir_ && v.width == w && v.height == h) return v;
    const OrthoView v = fitViewToPoints(positions_, dir_, w, h, opt_.depth);
    if (wholeFits_.size() < kWholeFits) wholeFits_.push_back({dir_, v});
    return v;
}

// Runs list_ under the current view: once, or once per tile. A tile holds exactly the
// fragments the whole view has at its pixels (OrthoView::tile), and every list of a call starts
// from a clear with the depth mask set (each list leaves it set), so a query's result over the
// whole view is the sum of its tiles' (SAMPLES_PASSED) or their maximum (ANY_SAMPLES_PASSED).
std::vector<uint64_t> Culler::execute() {
    if (tiles_.empty()) return backend_.execute(list_);
    std::vector<uint8_t> any;  // per query: ANY_SAMPLES_PASSED
    for (const Command& c : list_.commands())
        if (c.op == Command::Op::BeginQuery) any.push_back(c.queryKind == QueryKind::AnySamplesPassed);
    std::vector<uint64_t> total(any.size(), 0);
    for (const OrthoView& tile : tiles_) {
        backend_.setView(tile);
        const std::vector<uint64_t> r = backend_.execute(list_);
        CULLIDE_CHECK(r.size() == total.size(), "a backend returned the wrong number of query results");
        for (size_t q = 0; q < r.size(); ++q) total[q] = any[q] ? std::max(total[q], r[q]) : total[q] + r[q];
    }
    return total;
}

// Adds the view just executed (view_, list_) to the call's totals.
void Culler::countView(Command::Op drawOp) {
    for (const Command& c : list_.commands())
        if (c.op == drawOp) views_.rendered += c.count;
    views_.queries += list_.queryCount();
    views_.tiles += std::max<uint32_t>(1, uint32_t(tiles_.size()));
    if (views_.count == 0 || int64_t(view_.width) * view_.height > int64_t(views_.width) * views_.height)
        views_.width = view_.width, views_.height = view_.height;
    ++views_.count;
}

// options.recordPrunes: the triangles of the nodes in `pcs` but not in `kept` (a subset of
// its nodes) were pruned by call `call`.
void Culler::recordPrunes(const std::vector<Item>& pcs, const std::vector<Item>& kept, uint32_t call) {
    for (const Item& it : kept) keptMark_[it.object][it.node] = 1;
    for (const Item& it : pcs) {
        if (keptMark_[it.object][it.node]) continue;
        const Hierarchy& h = *hierarchies_[it.object];
        const HierarchyNode& n = node(it);
        uint32_t* const at = prunedAt_->data() + sceneOffset_[it.object];
        for (uint32_t k = n.first; k < n.first + n.count; ++k) at[h.order[k]] = call;
    }
    for (const Item& it : kept) keptMark_[it.object][it.node] = 0;  // clear for the next call
}

// The statistics of one reducePCS call from `pcs` to `kept` (its views' totals, views_),
// appended to `passes` and reported to onPass and onPassStats. Returns `kept`.
std::vector<Culler::Item> Culler::finishCall(const std::vector<Item>& pcs, std::vector<Item> kept, uint32_t level,
                                              uint32_t d, Clock::time_point start, std::vector<PassStats>& passes) {
    PassStats st;
    st.level = level;
    st.direction = d;
    st.dirVector = dir_;
    st.nodesIn = pcs.size();
    for (const Item& it : pcs) st.trianglesIn += it.range.count;
    st.nodesOut = kept.size();
    for (const Item& it : kept) st.trianglesOut += it.range.count;
    if (opt_.directionMode == DirectionMode::Coherent) {
        if (stepPruned_.size() <= step_) stepPruned_.resize(step_ + 1);
        std::vector<size_t>& p = stepPruned_[step_];
        p.resize(opt_.directions.size(), 0);
        p[d] += st.trianglesIn - st.trianglesOut;
    }
    st.trianglesRendered = views_.rendered;
    st.queries = views_.queries;
    // No view drawn (every group was decided undrawn): the base viewport.
    st.width = views_.count ? views_.width : opt_.width, st.height = views_.count ? views_.height : opt_.height;
    st.views = views_.count;
    st.tiles = views_.tiles;
    st.round = round_;
    st.seconds = secondsSince(start);
    if (prunedAt_) recordPrunes(pcs, kept, uint32_t(passes.size()));
    passes.push_back(st);
    if (opt_.onPass) opt_.onPass(st, expand(kept));
    if (opt_.onPassStats) opt_.onPassStats(st);
    return kept;
}

}  // namespace cullide::detail
