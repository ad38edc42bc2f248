// The cloth-on-a-ball scene (cullide/cloth.h): the request checked, the simulation run
// (cloth_sim.h) and sampled at the requested frames, the sphere drawn as an icosphere.
#include "cullide/cloth.h"

#include "cloth_sim.h"

#include "cullide/error.h"
#include "cullide/generators.h"

#include <cmath>
#include <string>

namespace cullide {
namespace {

constexpr double kClothSide = 4.5 * cloth::kSphereRadius;  // corners hang well below the equator
constexpr double kDurationSeconds = 3.0;                   // the fall and the drape
constexpr size_t kSphereSubdivisions = 4;                  // 5120 triangles

void checkRequest(const ClothRequest& r) {
    if (r.triangles < kMinClothTriangles || r.triangles > kMaxClothTriangles)
        throw InputError("cloth", "triangles must be in [" + std::to_string(kMinClothTriangles) + ", " +
                                      std::to_string(kMaxClothTriangles) + "], got " + std::to_string(r.triangles));
    if (r.frames < 1 || r.frames > kMaxClothFrames)
        throw InputError("cloth", "frames must be in [1, " + std::to_string(kMaxClothFrames) + "], got " +
                                      std::to_string(r.frames));
    if (r.triangles * r.frames > kMaxClothTriangleFrames)
        throw InputError("cloth", "triangles x frames must be at most " + std::to_string(kMaxClothTriangleFrames) +
                                      " (every frame is held in memory: about 6 bytes per triangle and frame), got " +
                                      std::to_string(r.triangles) + " x " + std::to_string(r.frames));
}

// Cells per side of the square grid whose 2 n^2 triangles come closest to `triangles`.
size_t cellsFor(size_t triangles) {
    size_t n = static_cast<size_t>(std::sqrt(double(triangles) / 2.0));
    while (2 * (n + 1) * (n + 1) <= triangles) ++n;
    // n or n + 1, whichever is closer (2 n^2 <= triangles < 2 (n + 1)^2).
    if (2 * (n + 1) * (n + 1) - triangles < triangles - 2 * n * n) ++n;
    return n;
}

// Two triangles per cell, split along the diagonal the simulator links (alternating with the
// cell's parity), every triangle facing up (+y) in the flat cloth's own frame.
std::vector<Triangle> gridTriangles(size_t cells) {
    const uint32_t w = static_cast<uint32_t>(cells + 1);
    std::vector<Triangle> tris;
    tris.reserve(2 * cells * cells);
    for (uint32_t r = 0; r < cells; ++r)
        for (uint32_t c = 0; c < cells; ++c) {
            const uint32_t a = r * w + c, b = a + 1, cc = a + w, d = a + w + 1;
            if ((r + c) % 2 == 0) {
                tris.push_back({a, d, b});
                tris.push_back({a, cc, d});
            } else {
                tris.push_back({a, cc, b});
                tris.push_back({b, cc, d});
            }
        }
    return tris;
}

// An icosahedron subdivided, its vertices on the sphere (so its facets lie inside it).
Mesh icosphere(size_t subdivisions) {
    const float t = float((1.0 + std::sqrt(5.0)) / 2.0);
    Mesh m;
    m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                   {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                   {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (size_t s = 0; s < subdivisions; ++s) m = subdivide(m);
    for (Vec3f& p : m.positions) {
        const Vec3d q(p.x(), p.y(), p.z());
        p = (q * (cloth::kSphereRadius / std::sqrt(q.dot(q)))).cast<float>();
    }
    return m;
}

std::vector<Vec3f> toFloat(const std::vector<Vec3d>& x) {
    std::vector<Vec3f> out(x.size());
    for (size_t i = 0; i < x.size(); ++i) out[i] = x[i].cast<float>();
    return out;
}

// The step whose state is frame f of `frames` (the last for a single frame), nearest to
// f * steps / (frames - 1).
size_t stepOfFrame(size_t f, size_t frames, size_t steps) {
    if (frames == 1) return steps;
    return (2 * f * steps + (frames - 1)) / (2 * (frames - 1));
}

}  // namespace

Animation cloth::makeCloth(const ClothRequest& request, const Tuning& tuning) {
    checkRequest(request);
    cloth::SimSetup setup;
    setup.tuning = tuning;
    setup.cells = cellsFor(request.triangles);
    setup.side = kClothSide;
    setup.repulsion = request.selfCollision == SelfCollision::Repulsion;
    setup.seed = request.seed;
    cloth::Simulation sim(setup);
    const size_t steps = static_cast<size_t>(std::lround(kDurationSeconds / cloth::Simulation::kStepSeconds));

    Animation a;
    a.frames.resize(request.frames);
    size_t f = 0;
    for (size_t s = 0; f < request.frames; ++s) {
        if (s > 0) sim.step();
        for (; f < request.frames && stepOfFrame(f, request.frames, steps) == s; ++f) {
            a.frames[f].poses.resize(2);
            a.frames[f].poses[0].positions = toFloat(sim.positions());
        }
    }
    Object cloth;
    cloth.name = "cloth";
    cloth.mesh.triangles = gridTriangles(setup.cells);
    cloth.mesh.positions = *a.frames[0].poses[0].positions;
    Object sphere;
    sphere.name = "sphere";
    sphere.mesh = icosphere(kSphereSubdivisions);
    a.scene.objects.push_back(std::move(cloth));
    a.scene.objects.push_back(std::move(sphere));
    return a;
}

Animation makeCloth(const ClothRequest& request) {
    return cloth::makeCloth(request, cloth::Tuning{});
}

}  // namespace cullide
