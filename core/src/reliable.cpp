// The non-image-space pieces of the reliable reducePCS (reliable.h; the argument is in
// docs/reliable.md).
//
// References
//   - N. Govindaraju, I. Kabul, M. Lin, D. Manocha: Fast continuous collision detection among
//     deformable models using graphics processors (CDCD, chromatic decomposition; Computers &
//     Graphics 2007 / SIGGRAPH 2005 sketch): adjacent primitives always touch, so they are kept
//     out of each other's image-space tests and handled by exact tests of their other features.
//   - CGAL 5.5 Polygon_mesh_processing::self_intersections: the rules for faces that share
//     vertices, which the oracle follows (mayIntersect applies the same code: faceContact,
//     cullide/predicates.h).
#include "reliable.h"

#include "cullide/parallel.h"
#include "cullide/predicates.h"

#include <algorithm>

namespace cullide::detail {

namespace {

TrianglePoints points(std::span<const Vec3f> positions, const Triangle& t) {
    return {positions[t[0]].cast<double>(), positions[t[1]].cast<double>(), positions[t[2]].cast<double>()};
}

struct Box {
    float lo[3], hi[3];
};

Box boxOf(std::span<const Vec3f> positions, const Triangle& t) {
    Box b;
    for (int k = 0; k < 3; ++k) {
        b.lo[k] = std::min({positions[t[0]][k], positions[t[1]][k], positions[t[2]][k]});
        b.hi[k] = std::max({positions[t[0]][k], positions[t[1]][k], positions[t[2]][k]});
    }
    return b;
}

bool overlap(const Box& a, const Box& b) {
    for (int k = 0; k < 3; ++k)
        if (a.hi[k] < b.lo[k] || b.hi[k] < a.lo[k]) return false;  // closed boxes: touching overlaps
    return true;
}

}  // namespace

UnitGraph unitAdjacency(std::span<const Triangle> triangles, std::span<const TriangleRange> units) {
    std::vector<std::pair<uint32_t, uint32_t>> vu;  // (vertex, unit)
    for (uint32_t u = 0; u < units.size(); ++u)
        for (uint32_t t = units[u].first; t < units[u].first + units[u].count; ++t)
            for (uint32_t v : triangles[t]) vu.push_back({v, u});
    std::sort(vu.begin(), vu.end());
    vu.erase(std::unique(vu.begin(), vu.end()), vu.end());
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    for (size_t g = 0; g < vu.size();) {
        size_t e = g;
        while (e < vu.size() && vu[e].first == vu[g].first) ++e;
        for (size_t a = g; a < e; ++a)
            for (size_t b = g; b < e; ++b)
                if (a != b) edges.push_back({vu[a].second, vu[b].second});
        g = e;
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    UnitGraph g;
    g.start.assign(units.size() + 1, 0);
    for (const auto& e : edges) ++g.start[e.first + 1];
    for (size_t u = 0; u < units.size(); ++u) g.start[u + 1] += g.start[u];
    g.adj.reserve(edges.size());
    for (const auto& e : edges) g.adj.push_back(e.second);  // edges sorted by (u, v): CSR order
    return g;
}

std::vector<uint32_t> distanceTwoColouring(const UnitGraph& g) {
    const uint32_t n = uint32_t(g.start.size() - 1);
    constexpr uint32_t none = UINT32_MAX;
    std::vector<uint32_t> colour(n, none);
    std::vector<uint32_t> mark;  // mark[c] == u + 1: colour c is taken near u
    for (uint32_t u = 0; u < n; ++u) {
        auto take = [&](uint32_t w) {
            const uint32_t c = colour[w];
            if (c == none) return;
            if (mark.size() <= c) mark.resize(c + 1, 0);
            mark[c] = u + 1;
        };
        for (uint32_t v : g.neighbours(u)) {
            take(v);
            for (uint32_t w : g.neighbours(v))
                if (w != u) take(w);
        }
        uint32_t c = 0;
        while (c < mark.size() && mark[c] == u + 1) ++c;
        colour[u] = c;
    }
    return colour;
}

bool mayIntersect(std::span<const Vec3f> positions, const Triangle& a, const Triangle& b) {
    const TrianglePoints pa = points(positions, a), pb = points(positions, b);
    if (collinear(pa[0], pa[1], pa[2]) || collinear(pb[0], pb[1], pb[2])) return false;  // in no pair
    return faceContact(pa, a, pb, b, true) != Contact::None;
}

std::vector<uint8_t> exactHits(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                               std::span<const TriangleRange> units, const UnitGraph& g) {
    std::vector<uint8_t> hit(units.size(), 0);
    parallelForEach(0, units.size(), [&](size_t u) {
        const TriangleRange& r = units[u];
        std::vector<uint32_t> partners;  // triangles of u and of its neighbours
        for (uint32_t t = r.first; t < r.first + r.count; ++t) partners.push_back(t);
        for (uint32_t v : g.neighbours(uint32_t(u)))
            for (uint32_t t = units[v].first; t < units[v].first + units[v].count; ++t) partners.push_back(t);
        std::vector<Box> boxes(partners.size());
        for (size_t k = 0; k < partners.size(); ++k) boxes[k] = boxOf(positions, triangles[partners[k]]);
        for (uint32_t i = 0; i < r.count && !hit[u]; ++i)
            for (size_t k = 0; k < partners.size(); ++k) {
                if (k == i || !overlap(boxes[i], boxes[k])) continue;
                if (mayIntersect(positions, triangles[partners[i]], triangles[partners[k]])) {
                    hit[u] = 1;
                    break;
                }
            }
    });
    return hit;
}

}  // namespace cullide::detail
