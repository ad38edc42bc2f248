// Shared by the rasterizer tests: geometry given directly in window coordinates. With the view
// box [0,W] x [0,H] x [0,1] of windowView (W, H powers of two keep toWindow exact) a world point
// is its window point.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/raster/cpu_backend.h"

#include <algorithm>
#include <memory>
#include <random>
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

// 300 random triangles in the window coordinates of a 64x64 windowView, x and y in [-4, 68] (some
// cross the viewport's edges), depth in [0, 1]; every third is tiny (its other vertices within 3 px
// of its first). Fixed seed: the GPU backends' coverage tests compare them with the reference.
inline void randomWindowTriangles(std::vector<Vec3f>& p, std::vector<Triangle>& t) {
    std::mt19937 rng(20030707);
    std::uniform_real_distribution<float> xy(-4.0f, 68.0f), z(0.0f, 1.0f), small(-3.0f, 3.0f);
    for (uint32_t i = 0; i < 300; ++i) {
        const Vec3f a(xy(rng), xy(rng), z(rng));
        const bool tiny = i % 3 == 0;
        const Vec3f b = tiny ? a + Vec3f(small(rng), small(rng), 0) : Vec3f(xy(rng), xy(rng), z(rng));
        const Vec3f c = tiny ? a + Vec3f(small(rng), small(rng), 0) : Vec3f(xy(rng), xy(rng), z(rng));
        const uint32_t base = uint32_t(p.size());
        p.insert(p.end(), {a, b, c});
        t.push_back({base, base + 1, base + 2});
    }
}

// One SAMPLES_PASSED query per triangle under ALWAYS with writes off: each result is the
// triangle's coverage, whatever was drawn before.
inline CommandList coverageQueries(size_t triangles) {
    CommandList list;
    list.depthFunc(DepthFunc::Always);
    list.depthMask(false);
    for (uint32_t i = 0; i < uint32_t(triangles); ++i) {
        list.beginQuery();
        list.draw(i, 1);
        list.endQuery();
    }
    return list;
}

// The results of `list` on `backend` (geometry set) drawn in side x side tiles of `view`
// (OrthoView::tile, row by row), each query's counts added over the tiles.
inline std::vector<uint64_t> tiledResults(DepthBackend& backend, const OrthoView& view, const CommandList& list,
                                          int side) {
    std::vector<uint64_t> sum(list.queryCount(), 0);
    for (int y = 0; y < view.height; y += side)
        for (int x = 0; x < view.width; x += side) {
            backend.setView(view.tile(x, y, std::min(side, view.width - x), std::min(side, view.height - y)));
            const std::vector<uint64_t> r = backend.execute(list);
            for (size_t i = 0; i < r.size() && i < sum.size(); ++i) sum[i] += r[i];
        }
    return sum;
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
