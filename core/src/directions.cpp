// Where the reducePCS calls look: the fixed lists (axisDirections, spreadDirections), the PCS's
// own directions (pcaFrame, pcaDirections: DirectionMode::Pca) and the coherent history across
// frames (DirectionHistory: DirectionMode::Coherent). docs/cullide.md#chosen-directions; see
// cullide.h.
#include "cullide/cullide.h"

#include "triangle_pieces.h"

#include "cullide/error.h"
#include "cullide/parallel.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cullide {

std::vector<Vec3d> axisDirections() {
    return {Vec3d(1, 0, 0), Vec3d(-1, 0, 0), Vec3d(0, 1, 0), Vec3d(0, -1, 0), Vec3d(0, 0, 1), Vec3d(0, 0, -1)};
}

std::vector<Vec3d> spreadDirections(uint32_t n) {
    if (n < 1 || n > 10000) throw InputError("option --directions", "the number of directions must be 1 to 10000");
    // Fibonacci lattice: z evenly spaced in (-1, 1), longitude stepped by the golden angle.
    std::vector<Vec3d> dirs;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (uint32_t i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / n;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden * i;
        dirs.push_back(Vec3d(r * std::cos(phi), r * std::sin(phi), z).normalized());
    }
    return dirs;
}

namespace {

// Twice the area times the unit normal of a triangle (its edges' cross product), in double.
Vec3d areaNormal(std::span<const Vec3f> positions, const Triangle& t) {
    const Vec3d a = positions[t[0]].cast<double>(), b = positions[t[1]].cast<double>(),
                c = positions[t[2]].cast<double>();
    return (b - a).cross(c - a);
}

// A unit vector with its largest-magnitude component (the first on a tie) positive.
Vec3d signFixed(const Vec3d& v) {
    int k = 0;
    for (int i = 1; i < 3; ++i)
        if (std::abs(v[i]) > std::abs(v[k])) k = i;
    return v[k] < 0 ? Vec3d(-v) : v;
}

// pcaDirections' orientation bins: normals folded to their sign-fixed half (n and -n face every
// view alike), binned by their largest component's axis and a 16 x 16 grid of the other two
// components divided by it (a cube map of three faces).
constexpr int kBinSide = 16;
constexpr int kBins = 3 * kBinSide * kBinSide;

int binOf(const Vec3d& n) {
    int a = 0;
    for (int i = 1; i < 3; ++i)
        if (std::abs(n[i]) > std::abs(n[a])) a = i;
    const double m = std::abs(n[a]);
    auto cell = [&](double x) { return std::clamp(int((x / m + 1.0) * 0.5 * kBinSide), 0, kBinSide - 1); };
    return (a * kBinSide + cell(n[(a + 1) % 3])) * kBinSide + cell(n[(a + 2) % 3]);
}

// The candidate frames of pcaDirections, in pcaFrame coordinates (columns: the three axes): the
// frame itself, then for each of 64 first axes w (the upper half, z >= 0, of a 128-direction
// Fibonacci lattice) 8 turns about w over a quarter turn (a frame repeats after a quarter turn).
const std::vector<Eigen::Matrix3d>& pcaCandidates() {
    static const std::vector<Eigen::Matrix3d> all = [] {
        std::vector<Eigen::Matrix3d> c{Eigen::Matrix3d::Identity()};
        for (const Vec3d& w : spreadDirections(128)) {
            if (w.z() < 0) continue;
            const Vec3d helper = std::abs(w.x()) < 0.6 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
            const Vec3d u0 = w.cross(helper).normalized(), v0 = w.cross(u0);
            for (int t = 0; t < 8; ++t) {
                const double th = 0.5 * std::numbers::pi * t / 8.0;  // t/8 of a quarter turn
                const Vec3d u = std::cos(th) * u0 + std::sin(th) * v0;
                Eigen::Matrix3d m;
                m.col(0) = w, m.col(1) = u, m.col(2) = w.cross(u);
                c.push_back(m);
            }
        }
        return c;
    }();
    return all;
}

}  // namespace

std::vector<Vec3d> pcaFrame(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                            std::span<const TriangleRange> ranges) {
    const std::vector<TriangleRange> ps = detail::piecesOf(ranges);
    std::vector<Eigen::Matrix3d> perPiece(ps.size(), Eigen::Matrix3d::Zero());
    parallelFor(0, ps.size(), 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i)
            for (uint32_t k = 0; k < ps[i].count; ++k) {
                const Vec3d c = areaNormal(positions, triangles[ps[i].first + k]);
                const double len = c.norm();
                if (len > 0) perPiece[i] += (c * c.transpose()) / (2.0 * len);  // area * n n^T
            }
    });
    Eigen::Matrix3d t = Eigen::Matrix3d::Zero();
    for (const Eigen::Matrix3d& m : perPiece) t += m;
    if (!t.allFinite() || !(t.trace() > 0)) return {};
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(t);
    if (es.info() != Eigen::Success) return {};
    // Eigen sorts the eigenvalues in increasing order: the largest (the most faced orientation) first.
    return {signFixed(es.eigenvectors().col(2)), signFixed(es.eigenvectors().col(1)),
            signFixed(es.eigenvectors().col(0))};
}

std::vector<Vec3d> pcaDirections(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                 std::span<const TriangleRange> ranges) {
    const std::vector<Vec3d> frame = pcaFrame(positions, triangles, ranges);
    if (frame.empty()) return axisDirections();
    Eigen::Matrix3d e;
    e.col(0) = frame[0], e.col(1) = frame[1], e.col(2) = frame[2];
    // The PCS's orientations in frame coordinates: per bin the area and the area-weighted folded normal.
    const std::vector<TriangleRange> ps = detail::piecesOf(ranges);
    using Bins = std::vector<Eigen::Vector4d>;  // (area-weighted normal, area)
    std::vector<Bins> perPiece(ps.size());
    parallelFor(0, ps.size(), 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i) {
            Bins& b = perPiece[i];
            b.assign(kBins, Eigen::Vector4d::Zero());
            for (uint32_t k = 0; k < ps[i].count; ++k) {
                const Vec3d c = areaNormal(positions, triangles[ps[i].first + k]);
                const double len = c.norm();
                if (!(len > 0)) continue;
                const Vec3d n = signFixed(e.transpose() * (c / len));
                const double area = 0.5 * len;
                b[size_t(binOf(n))] += Eigen::Vector4d(area * n.x(), area * n.y(), area * n.z(), area);
            }
        }
    });
    Bins all(kBins, Eigen::Vector4d::Zero());
    for (const Bins& b : perPiece)
        for (int k = 0; k < kBins; ++k) all[size_t(k)] += b[size_t(k)];
    std::vector<std::pair<Vec3d, double>> orientations;  // (unit normal, area)
    for (const Eigen::Vector4d& b : all) {
        const Vec3d n = b.head<3>();
        if (b.w() > 0 && n.norm() > 0) orientations.push_back({n.normalized(), b.w()});
    }
    const std::vector<Eigen::Matrix3d>& candidates = pcaCandidates();
    size_t best = 0;
    double bestScore = -1;
    for (size_t c = 0; c < candidates.size(); ++c) {
        double score = 0;
        for (const auto& [n, area] : orientations) {
            const Vec3d f = (candidates[c].transpose() * n).cwiseAbs();
            score += area * std::min(1.0 / 3.0, f.minCoeff());
        }
        if (score > bestScore) best = c, bestScore = score;
    }
    std::vector<Vec3d> dirs;
    for (int k = 0; k < 3; ++k) {
        const Vec3d v = signFixed((e * candidates[best].col(k)).normalized());
        dirs.push_back(v);
        dirs.push_back(-v);
    }
    return dirs;
}

std::vector<uint32_t> DirectionHistory::plan(uint32_t level, size_t n) const {
    std::vector<uint32_t> all(n);
    for (size_t i = 0; i < n; ++i) all[i] = uint32_t(i);
    if (frames == 0 || count != n || frames % std::max<uint32_t>(period, 1) == 0 || level >= pruned.size()) return all;
    // The given order, not most-pruned first: a call that would prune nothing changes nothing, so
    // dropping only those keeps the PCS of the full list bit for bit wherever the last frame
    // predicted them right (reordering changed the views of the later calls and, on the
    // animations measured, added false prunes: docs/cullide.md#chosen-directions).
    const std::vector<size_t>& p = pruned[level];
    std::vector<uint32_t> used;
    for (uint32_t i : all)
        if (i < p.size() && p[i] > 0) used.push_back(i);
    return used;
}

void DirectionHistory::record(size_t n, std::vector<std::vector<size_t>> prunedPerLevel) {
    count = n;
    pruned = std::move(prunedPerLevel);
    ++frames;
}

}  // namespace cullide
