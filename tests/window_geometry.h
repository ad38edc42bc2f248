// Shared by the rasterizer tests: geometry given directly in window coordinates. With the view
// box [0,W] x [0,H] x [0,1] of windowView (W, H powers of two keep toWindow exact) a world point
// is its window point.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/raster/cpu_backend.h"

#include <memory>
#include <vector>

namespace cullide::test {

struct Geo {
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    uint32_t add(float x, float y, float z) {
        positions.emplace_back(x, y, z);
        return uint32_t(positions.size() - 1);
    }
    uint32_t tri(uint32_t a, uint32_t b, uint32_t c) {
        triangles.push_back({a, b, c});
        return uint32_t(triangles.size() - 1);
    }
    uint32_t tri(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
        return tri(add(a.x(), a.y(), a.z()), add(b.x(), b.y(), b.z()), add(c.x(), c.y(), c.z()));
    }
    // Axis-aligned quad at depth z (two triangles), returns the first triangle.
    uint32_t quad(float x0, float y0, float x1, float y1, float z) {
        const uint32_t a = add(x0, y0, z), b = add(x1, y0, z), c = add(x1, y1, z), d = add(x0, y1, z);
        const uint32_t t = tri(a, b, c);
        tri(a, c, d);
        return t;
    }
};

// An axis-aligned quad at depth z as two triangles (0-1-2, 0-2-3) appended to p and t.
inline void addQuad(std::vector<Vec3f>& p, std::vector<Triangle>& t, float x0, float y0, float x1, float y1, float z) {
    const uint32_t b = uint32_t(p.size());
    p.insert(p.end(), {Vec3f(x0, y0, z), Vec3f(x1, y0, z), Vec3f(x1, y1, z), Vec3f(x0, y1, z)});
    t.push_back({b, b + 1, b + 2});
    t.push_back({b, b + 2, b + 3});
}

inline OrthoView windowView(int W, int H, DepthFormat format = DepthFormat::unorm(24)) {
    OrthoView v;
    v.xmin = 0, v.xmax = W, v.ymin = 0, v.ymax = H, v.znear = 0, v.zfar = 1;
    v.width = W, v.height = H;
    v.depth = format;
    return v;
}

inline std::unique_ptr<raster::CpuBackend> backendFor(const Geo& g, const OrthoView& view,
                                                      raster::CpuBackendOptions o = {}) {
    auto b = raster::makeCpuBackend(o);
    b->setGeometry(g.positions, g.triangles);
    b->setView(view);
    return b;
}

}  // namespace cullide::test
