// Helpers of the CPU rasterizer's tests (raster_*_test.cpp): command lists of ALWAYS queries,
// debug pictures of differing depth images, and the random scenes of the differential tests with
// their comparison.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/raster/cpu_backend.h"

#include "window_geometry.h"

#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace cullide::test {

// A command list that clears, then counts with ALWAYS the samples of each (first, count) range of
// triangles, one query per range.
CommandList alwaysQueries(std::initializer_list<std::pair<uint32_t, uint32_t>> ranges);

// Where a failed test's picture `name` goes (the gtest temp folder).
std::string failPath(const std::string& name);

// Writes both depth images and their difference mask for a failed comparison; returns a note.
std::string dumpDiff(const std::string& name, const DepthImage& a, const DepthImage& b);

struct RandomScene {
    Geo geo;
    CommandList list;
};

// Random triangles of mixed sizes (sub-pixel to larger than the viewport), some crossing the
// depth range, some far outside, some degenerate; a random command list with every function,
// mask changes, clears, overlapping and repeated draw ranges and both query kinds.
RandomScene randomScene(uint64_t seed, int W, int H, int triangles, int commands, double bigSize = 0);

struct Outcome {
    std::vector<uint64_t> results;
    DepthImage depth;
    raster::RasterStats stats;
};

// The scene's list run `lists` times on a fresh backend (later lists start from the previous
// state): the last list's results and statistics, and the final depth image.
Outcome run(const RandomScene& s, const OrthoView& view, raster::CpuBackendOptions o, int lists = 1);

// The scalar reference path's options for a seeded test: the fill rule by the seed's parity (the
// seeds cover both), `subpixelBits` as given.
raster::CpuBackendOptions scalarReference(uint64_t seed, int subpixelBits);

// Expects equal results, statistics and depth images (pictures of the difference on failure).
void expectSame(const Outcome& a, const Outcome& b, const std::string& what);

// The direct path on one and two threads against `expected` (the scalar path's outcome), each run
// checked to have taken it.
void expectDirectOnThreads(const RandomScene& s, const OrthoView& view, const raster::CpuBackendOptions& ref,
                           const Outcome& expected, const std::string& what);

}  // namespace cullide::test
