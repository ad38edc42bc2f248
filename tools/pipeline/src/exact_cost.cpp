// The exact stage's cost model for `--exact-switch auto` (exact_cost.h).
#include "cullide/pipeline/exact_cost.h"

#include "cullide/oracle/oracle.h"

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

namespace cullide {
namespace {

// Every triangle of the scene with its world centroid.
std::vector<std::pair<oracle::TriangleRef, Vec3d>> centroidsOf(const Scene& scene) {
    std::vector<std::pair<oracle::TriangleRef, Vec3d>> centroids;
    for (uint32_t i = 0; i < scene.objects.size(); ++i) {
        const Mesh m = scene.worldMesh(i);
        for (uint32_t t = 0; t < m.triangles.size(); ++t) {
            Vec3d c = Vec3d::Zero();
            for (uint32_t v : m.triangles[t]) c += m.positions[v].cast<double>();
            centroids.push_back({{i, t}, c / 3});
        }
    }
    return centroids;
}

// The calibration sample: the k triangles whose centroids lie nearest (max norm) to the
// coordinate-wise median centroid, sorted.
std::vector<oracle::TriangleRef> samplePatch(std::vector<std::pair<oracle::TriangleRef, Vec3d>>& centroids, size_t k) {
    const size_t total = centroids.size();
    Vec3d median;
    std::vector<double> axis(total);
    for (int a = 0; a < 3; ++a) {
        for (size_t i = 0; i < total; ++i) axis[i] = centroids[i].second[a];
        std::nth_element(axis.begin(), axis.begin() + ptrdiff_t(total / 2), axis.end());
        median[a] = axis[total / 2];
    }
    std::nth_element(centroids.begin(), centroids.begin() + ptrdiff_t(k - 1), centroids.end(),
                     [&](const auto& a, const auto& b) {
                         return (a.second - median).template lpNorm<Eigen::Infinity>() <
                             (b.second - median).template lpNorm<Eigen::Infinity>();
                     });
    std::vector<oracle::TriangleRef> sample;
    for (size_t i = 0; i < k; ++i) sample.push_back(centroids[i].first);
    std::sort(sample.begin(), sample.end());
    return sample;
}

// Seconds per triangle of the exact stage on the calibration sample of `scene`.
double calibrate(const Scene& scene) {
    std::vector<std::pair<oracle::TriangleRef, Vec3d>> centroids = centroidsOf(scene);
    const size_t total = centroids.size(), k = std::min(total, std::max<size_t>(2048, total / 16));
    if (k == 0) return 0;
    const std::vector<oracle::TriangleRef> sample = samplePatch(centroids, k);
    return oracle::exactStage(scene, sample).totalSeconds / double(k);
}

}  // namespace

std::function<double(size_t)> exactStageCostModel(const Scene& scene) {
    auto perTriangle = std::make_shared<double>(-1);  // shared by the copies std::function makes
    return [&scene, perTriangle](size_t n) {
        if (*perTriangle < 0) *perTriangle = calibrate(scene);
        return double(n) * *perTriangle;
    };
}

}  // namespace cullide
