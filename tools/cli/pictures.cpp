#include "pictures.h"

#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/png.h"

#include <algorithm>
#include <cmath>

namespace cullide::cli {

struct PcsPictures::State {
    std::unique_ptr<raster::CpuBackend> backend;
    FlatScene flat;  // the scene as one geometry
    DepthImage scene;  // the whole scene's depth
    int width = 0, height = 0;
};

PcsPictures::PcsPictures(const Scene& scene, const Vec3d& direction, int width, int height)
    : state_(std::make_unique<State>()) {
    State& s = *state_;
    s.width = width;
    s.height = height;
    s.backend = raster::makeCpuBackend();
    s.flat = flatten(scene);
    const Mesh& m = s.flat.mesh;
    s.backend->setGeometry(m.positions, m.triangles);
    const TriangleRange all{0, uint32_t(m.triangles.size())};
    s.backend->setView(
        fitView(m.positions, m.triangles, {&all, 1}, direction.normalized(), width, height, DepthFormat::unorm(24)));
    CommandList list;
    list.clear(1.0);
    list.draw(all.first, all.count);
    s.backend->execute(list);
    s.scene = s.backend->readDepth();
}

PcsPictures::~PcsPictures() = default;

void PcsPictures::write(std::span<const PcsTriangle> pcs, const std::filesystem::path& path) {
    State& s = *state_;
    CommandList list;
    list.clear(1.0);
    // Consecutive triangles of the PCS become one draw.
    for (size_t i = 0; i < pcs.size();) {
        const uint32_t first = s.flat.triangle(pcs[i].object, pcs[i].triangle);
        size_t j = i + 1;
        while (j < pcs.size() && s.flat.triangle(pcs[j].object, pcs[j].triangle) == first + (j - i)) ++j;
        list.draw(first, uint32_t(j - i));
        i = j;
    }
    s.backend->execute(list);
    const DepthImage front = s.backend->readDepth();

    const uint32_t cleared = s.scene.values.empty() ? 0 : (1u << 24) - 1;
    uint32_t lo = cleared, hi = 0;
    for (uint32_t v : s.scene.values)
        if (v != cleared) lo = std::min(lo, v), hi = std::max(hi, v);
    std::vector<uint8_t> rgb(size_t(s.width) * size_t(s.height) * 3);
    for (size_t p = 0; p < s.scene.values.size(); ++p) {
        const uint32_t v = s.scene.values[p];
        uint8_t* px = &rgb[3 * p];
        if (v == cleared) {
            px[0] = 24, px[1] = 24, px[2] = 32;
            continue;
        }
        const double t = hi > lo ? double(v - lo) / double(hi - lo) : 0.0;  // 0 near, 1 far
        const auto shade = uint8_t(std::lround(230.0 - 150.0 * t));
        if (front.values[p] == v) px[0] = uint8_t(shade / 4), px[1] = shade, px[2] = uint8_t(shade / 4);
        else px[0] = px[1] = px[2] = shade;
    }
    raster::writeRgbPng(s.width, s.height, rgb, path);
}

}  // namespace cullide::cli
