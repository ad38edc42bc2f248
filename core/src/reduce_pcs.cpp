// The command lists of the reducePCS calls: modified (the seed paper's Figure 3), original
// (Figure 2) and reliable (docs/reliable.md). See cullide.h and reduce_pcs.h.
#include "reduce_pcs.h"

#include "cullide/error.h"

#include <algorithm>

namespace cullide {

void appendModifiedReducePcs(CommandList& list, std::span<const TriangleRange> ranges, std::span<uint32_t> forwardQuery,
                             std::span<uint32_t> reverseQuery) {
    CULLIDE_CHECK(forwardQuery.size() == ranges.size() && reverseQuery.size() == ranges.size(),
                  "appendModifiedReducePcs: one query slot per range");
    // Forward: write the object, then test it against everything so far, itself included, with
    // GREATER (anything in front of one of its fragments fails it).
    list.clear(1.0);
    for (size_t i = 0; i < ranges.size(); ++i) {
        list.depthMask(true);
        list.depthFunc(DepthFunc::Less);
        list.draw(ranges[i].first, ranges[i].count);
        list.depthMask(false);
        list.depthFunc(DepthFunc::Greater);
        forwardQuery[i] = list.beginQuery(QueryKind::SamplesPassed);
        list.draw(ranges[i].first, ranges[i].count);
        list.endQuery();
    }
    // Reverse: test against the objects after it, then write it.
    list.clear(1.0);
    for (size_t i = ranges.size(); i-- > 0;) {
        list.depthMask(false);
        list.depthFunc(DepthFunc::Greater);
        reverseQuery[i] = list.beginQuery(QueryKind::SamplesPassed);
        list.draw(ranges[i].first, ranges[i].count);
        list.endQuery();
        list.depthMask(true);
        list.depthFunc(DepthFunc::Less);
        list.draw(ranges[i].first, ranges[i].count);
    }
}

namespace detail {

void appendOriginalReducePcs(CommandList& list, std::span<const TriangleRange> ranges, std::span<const uint32_t> objects,
                             std::span<uint32_t> forwardQuery, std::span<uint32_t> reverseQuery) {
    CULLIDE_CHECK(objects.size() == ranges.size() && forwardQuery.size() == ranges.size() &&
                      reverseQuery.size() == ranges.size(),
                  "appendOriginalReducePcs: one object and one query slot per range");
    std::vector<std::pair<size_t, size_t>> groups;  // [begin, end) of each object's ranges
    for (size_t g = 0; g < ranges.size();) {
        size_t e = g;
        while (e < ranges.size() && objects[e] == objects[g]) ++e;
        groups.push_back({g, e});
        g = e;
    }
    auto group = [&](const std::pair<size_t, size_t>& grp, std::span<uint32_t> query) {
        list.depthMask(false);
        list.depthFunc(DepthFunc::GEqual);
        for (size_t i = grp.first; i < grp.second; ++i) {
            query[i] = list.beginQuery(QueryKind::SamplesPassed);
            list.draw(ranges[i].first, ranges[i].count);
            list.endQuery();
        }
        list.depthMask(true);
        list.depthFunc(DepthFunc::Less);
        for (size_t i = grp.first; i < grp.second; ++i) list.draw(ranges[i].first, ranges[i].count);
    };
    list.clear(1.0);
    for (const auto& grp : groups) group(grp, forwardQuery);
    list.clear(1.0);
    for (size_t g = groups.size(); g-- > 0;) group(groups[g], reverseQuery);
}

std::vector<std::pair<uint32_t, uint32_t>> appendReliableReducePcs(CommandList& list,
                                                                   std::span<const TriangleRange> units,
                                                                   const UnitGraph& g,
                                                                   std::span<const uint32_t> colour) {
    const uint32_t n = uint32_t(units.size());
    const uint32_t classes = n == 0 ? 0 : *std::max_element(colour.begin(), colour.end()) + 1;
    std::vector<std::vector<uint32_t>> members(classes);
    for (uint32_t u = 0; u < n; ++u) members[colour[u]].push_back(u);

    std::vector<std::pair<uint32_t, uint32_t>> queries;  // (unit, query)
    auto test = [&](uint32_t u) {
        queries.push_back({u, list.beginQuery(QueryKind::AnySamplesPassed)});
        list.drawConservative(units[u].first, units[u].count, true, false);
        list.endQuery();
    };
    std::vector<int64_t> matched(n);
    std::vector<std::vector<uint32_t>> matchedTo;
    for (uint32_t b = 0; b < classes; ++b) {
        // matched[x]: x's neighbour of class b (at most one, by the colouring), or -1.
        std::fill(matched.begin(), matched.end(), -1);
        matchedTo.assign(n, {});
        for (uint32_t x = 0; x < n; ++x) {
            if (colour[x] == b) continue;
            for (uint32_t y : g.neighbours(x))
                if (colour[y] == b) {
                    CULLIDE_CHECK(matched[x] < 0, "distance-2 colouring gave a unit two neighbours of one class");
                    matched[x] = y;
                    matchedTo[y].push_back(x);
                }
        }
        list.clearIntervals();
        for (uint32_t y : members[b]) {
            for (uint32_t x : matchedTo[y]) test(x);
            test(y);
            list.drawConservative(units[y].first, units[y].count, false, true);
        }
        for (uint32_t x = 0; x < n; ++x)
            if (colour[x] != b && matched[x] < 0) test(x);
        list.clearIntervals();
        for (size_t k = members[b].size(); k-- > 0;) {
            const uint32_t y = members[b][k];
            for (uint32_t x : matchedTo[y]) test(x);
            test(y);
            list.drawConservative(units[y].first, units[y].count, false, true);
        }
    }
    return queries;
}

}  // namespace detail

}  // namespace cullide
