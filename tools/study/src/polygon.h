// Convex polygons in the plane, in plain double: the overlap of two projected triangles, for the
// measures of a PCS (measures.cpp) and the causes of false prunes (causes.cpp). These numbers
// explain false prunes; they decide nothing.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace cullide::study {

struct P2 {
    double x, y;
};

// Twice the signed area of (o, a, b): positive when counterclockwise.
inline double cross(const P2& o, const P2& a, const P2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Sutherland-Hodgman: the convex polygon `poly` clipped to the triangle t (either orientation;
// closed half-planes, so a polygon touching t keeps the touching points).
inline std::vector<P2> clipToTriangle(std::vector<P2> poly, const P2 t[3]) {
    const double orient = cross(t[0], t[1], t[2]) > 0 ? 1.0 : -1.0;
    for (int e = 0; e < 3 && !poly.empty(); ++e) {
        const P2 &a = t[e], &b = t[(e + 1) % 3];
        std::vector<P2> out;
        for (size_t i = 0; i < poly.size(); ++i) {
            const P2 &p = poly[i], &q = poly[(i + 1) % poly.size()];
            const double sp = orient * cross(a, b, p), sq = orient * cross(a, b, q);
            if (sp >= 0) out.push_back(p);
            if ((sp >= 0) != (sq >= 0)) {
                const double s = sp / (sp - sq);
                out.push_back({p.x + s * (q.x - p.x), p.y + s * (q.y - p.y)});
            }
        }
        poly = std::move(out);
    }
    return poly;
}

}  // namespace cullide::study
