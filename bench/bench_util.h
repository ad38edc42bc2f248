// Shared by the benchmarks: the workloads they compare.
#pragma once

#include "cullide/cullide.h"
#include "cullide/depth_backend.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <map>
#include <string>

#include <algorithm>
#include <utility>
#include <vector>

// The 0.1.0 reference build's recorded figure for `benchmark` (bench/baseline.json, the one place
// that holds them), or 0 when it has none: the x_v010 counters divide by it where that build cannot
// run in the same process.
inline double baselineFigure(const std::string& benchmark) {
    static const nlohmann::json baseline = [] {
        std::ifstream f(CULLIDE_BASELINE_JSON);
        return f ? nlohmann::json::parse(f, nullptr, false) : nlohmann::json();
    }();
    if (!baseline.is_object() || !baseline.contains("figures")) return 0;
    for (const nlohmann::json& figure : baseline["figures"])
        if (figure.value("benchmark", "") == benchmark) return figure.value("value", 0.0);
    return 0;
}

// The self variant's reducePCS (the seed paper's Figure 3, docs/paper.md#figure-3), both passes, one direction, as one
// command list, over consecutive objects of `perObject` triangles (0: the whole mesh).
inline cullide::CommandList reducePcsList(uint32_t triangles, uint32_t perObject) {
    if (perObject == 0) perObject = triangles;
    std::vector<cullide::TriangleRange> ranges;
    for (uint32_t f = 0; f < triangles; f += perObject) ranges.push_back({f, std::min(perObject, triangles - f)});
    std::vector<uint32_t> forward(ranges.size()), reverse(ranges.size());
    cullide::CommandList l;
    cullide::appendModifiedReducePcs(l, ranges, forward, reverse);
    return l;
}

// The benchmark meshes, loaded once: 0 = the cow subdivided 1-to-4 three times (371,456
// triangles), 1 = the 75k bunny.
inline const cullide::Mesh& benchMesh(int which) {
    static std::map<int, cullide::Mesh> cache;
    auto it = cache.find(which);
    if (it != cache.end()) return it->second;
    cullide::Mesh m;
    if (which == 0) {
        m = cullide::loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/cow.off");
        for (int k = 0; k < 3; ++k) m = cullide::subdivide(m);
    } else {
        m = cullide::loadMesh(std::string(CULLIDE_DATA_DIR) + "/meshes/bunny75k.off");
    }
    return cache.emplace(which, std::move(m)).first->second;
}

// The paper's scenes at frame 0, built once per (which, triangles): 0 = the deformed bunny
// (make-scene bunny), 1 = two cows merged into one object (make-scene cows), 2 = 12 cylinders.
inline const cullide::Scene& paperScene(int which, size_t triangles) {
    static std::map<std::pair<int, size_t>, cullide::Scene> cache;
    auto it = cache.find({which, triangles});
    if (it == cache.end()) {
        cullide::SceneRequest r;
        r.triangles = triangles;
        cullide::Animation a;
        if (which == 2) {
            a = cullide::makeCylinders(12, r);
        } else {
            const cullide::Mesh source = cullide::loadMesh(std::string(CULLIDE_DATA_DIR) +
                                                           (which == 0 ? "/meshes/bunny.off" : "/meshes/cow.off"));
            a = which == 0 ? cullide::makeDeformedBunny(source, r) : cullide::makeTwoCows(source, r);
        }
        it = cache.emplace(std::make_pair(which, triangles), a.sceneAt(0)).first;
    }
    return it->second;
}
