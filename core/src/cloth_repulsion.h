// Near particle pairs of a cloth, found with a spatial hash grid (Teschner et al., "Optimized
// Spatial Hashing for Collision Detection of Deformable Objects", 2003), for the simulator's
// repulsion (cloth_sim.h).
//
// Determinism: particles go into the hash table's buckets by a counting sort in index order, so a
// bucket lists its particles in ascending index; pairs are then listed particle by particle, its
// own cell and half of the 26 around it in a fixed order (each pair found once). The table is only
// looked up, never iterated, so the list is a function of the positions alone.
#pragma once

#include "cullide/mesh.h"

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace cullide::cloth {

class NearPairs {
public:
    // The pairs (i, j), i < j, of particles closer than `radius` that are not grid neighbours (at
    // most `skip` rows and `skip` columns apart on the (width x width) particle grid, where
    // particle k is at row k / width, column k % width), in a fixed order. Only the particles
    // whose row and column are multiples of `stride` take part (a coarser sub-grid).
    const std::vector<std::pair<uint32_t, uint32_t>>& find(std::span<const Vec3d> positions, size_t width,
                                                           uint32_t skip, double radius, size_t stride);

    // A particle as a bucket lists it: everything the search compares, in one place in memory.
    struct Entry {
        uint32_t particle = 0;
        int32_t row = 0, column = 0;
        int32_t cell[3] = {0, 0, 0};
    };

private:
    std::vector<Entry> byParticle_;   // entry of each particle
    std::vector<uint32_t> start_;     // bucket b: entries_[start_[b] .. start_[b + 1])
    std::vector<Entry> entries_;
    std::vector<std::pair<uint32_t, uint32_t>> pairs_;
};

}  // namespace cullide::cloth
