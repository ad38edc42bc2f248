// Near particle pairs of a cloth by spatial hashing (cloth_repulsion.h).
#include "cloth_repulsion.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

namespace cullide::cloth {
namespace {

// Teschner et al.'s hash of a cell, on unsigned (wrap-around) arithmetic.
uint32_t hashCell(int32_t x, int32_t y, int32_t z) {
    return (uint32_t(x) * 73856093u) ^ (uint32_t(y) * 19349663u) ^ (uint32_t(z) * 83492791u);
}

// The own cell, then the 13 cell offsets that come after (0, 0, 0) in lexicographic order.
constexpr std::array<std::array<int32_t, 3>, 14> kHalfNeighbourhood = {{
    {0, 0, 0}, {0, 0, 1}, {0, 1, -1}, {0, 1, 0}, {0, 1, 1}, {1, -1, -1}, {1, -1, 0},
    {1, -1, 1}, {1, 0, -1}, {1, 0, 0}, {1, 0, 1}, {1, 1, -1}, {1, 1, 0}, {1, 1, 1}}};

// The cell index along one axis, held within int32 (far cells merely share an index).
int32_t cellOf(double coordinate, double size) {
    const double c = std::floor(coordinate / size);
    return static_cast<int32_t>(std::fmax(-1e9, std::fmin(1e9, c)));
}

}  // namespace

const std::vector<std::pair<uint32_t, uint32_t>>& NearPairs::find(std::span<const Vec3d> positions, size_t width,
                                                                  uint32_t skip, double radius, size_t stride) {
    const size_t n = positions.size();
    size_t buckets = 1;
    while (buckets < 2 * n) buckets *= 2;
    const uint32_t mask = static_cast<uint32_t>(buckets - 1);
    byParticle_.clear();
    start_.assign(buckets + 1, 0);
    pairs_.clear();
    // Counting sort of the particles by bucket, in index order.
    for (size_t i = 0; i < n; ++i) {
        if ((i / width) % stride != 0 || (i % width) % stride != 0) continue;
        Entry& e = byParticle_.emplace_back();
        e.particle = static_cast<uint32_t>(i);
        e.row = static_cast<int32_t>(i / width);
        e.column = static_cast<int32_t>(i % width);
        for (int k = 0; k < 3; ++k) e.cell[k] = cellOf(positions[i][k], radius);
        ++start_[(hashCell(e.cell[0], e.cell[1], e.cell[2]) & mask) + 1];
    }
    for (size_t b = 0; b < buckets; ++b) start_[b + 1] += start_[b];
    entries_.resize(byParticle_.size());
    for (const Entry& e : byParticle_) entries_[start_[hashCell(e.cell[0], e.cell[1], e.cell[2]) & mask]++] = e;
    for (size_t b = buckets; b > 0; --b) start_[b] = start_[b - 1];  // back to each bucket's start
    start_[0] = 0;

    // Each pair once: the particle's own cell (partners of higher index), then the 13 cells of
    // the half neighbourhood after it (every partner; the pair stored low index first).
    const double r2 = radius * radius;
    const int32_t reach = static_cast<int32_t>(skip);
    for (const Entry& self : byParticle_) {
        const Vec3d& p = positions[self.particle];
        for (const auto& o : kHalfNeighbourhood) {
            const int32_t cx = self.cell[0] + o[0], cy = self.cell[1] + o[1], cz = self.cell[2] + o[2];
            const bool own = o[0] == 0 && o[1] == 0 && o[2] == 0;
            const uint32_t b = hashCell(cx, cy, cz) & mask;
            for (uint32_t k = start_[b]; k < start_[b + 1]; ++k) {
                const Entry& other = entries_[k];
                if (other.cell[0] != cx || other.cell[1] != cy || other.cell[2] != cz) continue;  // another cell
                if (own && other.particle <= self.particle) continue;
                if (std::abs(other.row - self.row) <= reach && std::abs(other.column - self.column) <= reach) continue;
                const Vec3d d = positions[other.particle] - p;
                if (d.dot(d) < r2)
                    pairs_.emplace_back(std::min(self.particle, other.particle), std::max(self.particle, other.particle));
            }
        }
    }
    return pairs_;
}

}  // namespace cullide::cloth
