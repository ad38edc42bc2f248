// Shared by the benchmarks: the workloads they compare.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"

#include <map>
#include <string>

#include <algorithm>
#include <utility>
#include <vector>

// The self variant's reducePCS (the seed paper's Figure 3), both passes, one direction, as one
// command list, over consecutive objects of `perObject` triangles (0: the whole mesh).
inline cullide::CommandList reducePcsList(uint32_t triangles, uint32_t perObject) {
    if (perObject == 0) perObject = triangles;
    std::vector<std::pair<uint32_t, uint32_t>> objects;
    for (uint32_t f = 0; f < triangles; f += perObject) objects.push_back({f, std::min(perObject, triangles - f)});
    using namespace cullide;
    CommandList l;
    l.clear(1.0);
    for (const auto& [first, count] : objects) {
        l.depthMask(true);
        l.depthFunc(DepthFunc::Less);
        l.draw(first, count);
        l.depthMask(false);
        l.depthFunc(DepthFunc::Greater);
        l.beginQuery();
        l.draw(first, count);
        l.endQuery();
    }
    l.clear(1.0);
    for (auto it = objects.rbegin(); it != objects.rend(); ++it) {
        l.depthMask(false);
        l.depthFunc(DepthFunc::Greater);
        l.beginQuery();
        l.draw(it->first, it->second);
        l.endQuery();
        l.depthMask(true);
        l.depthFunc(DepthFunc::Less);
        l.draw(it->first, it->second);
    }
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
