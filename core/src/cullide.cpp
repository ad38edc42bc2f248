// Cullide (Govindaraju et al. 2003) and the seed paper's self-intersection variant: Figures 1-3
// of the seed paper (docs/paper.md#figure-1, #figure-2, #figure-3), on any DepthBackend. See cullide.h.
#include "cullide/cullide.h"

#include "reliable.h"

#include "cullide/error.h"
#include "cullide/parallel.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <tuple>

namespace cullide {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

const char* toString(CullMethod m) {
    switch (m) {
        case CullMethod::Original: return "original";
        case CullMethod::Modified: return "modified";
        case CullMethod::Reliable: return "reliable";
    }
    return "?";
}

CullMethod parseCullMethod(const std::string& text) {
    if (text == "original") return CullMethod::Original;
    if (text == "modified") return CullMethod::Modified;
    if (text == "reliable") return CullMethod::Reliable;
    throw InputError("option --method", "unknown method '" + text + "' (expected original, modified or reliable)");
}

const char* toString(ViewMode m) {
    switch (m) {
        case ViewMode::Fit: return "fit";
        case ViewMode::Clustered: return "clustered";
    }
    return "?";
}

ViewMode parseViewMode(const std::string& text) {
    if (text == "fit") return ViewMode::Fit;
    if (text == "clustered") return ViewMode::Clustered;
    throw InputError("option --views", "unknown view mode '" + text + "' (expected fit or clustered)");
}

bool promisesToKeep(CullMethod method, bool crossing, bool sameObject) {
    switch (method) {
        case CullMethod::Original: return !sameObject;
        case CullMethod::Modified: return crossing;
        case CullMethod::Reliable: return true;
    }
    return true;
}

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

const char* toString(DirectionMode m) {
    switch (m) {
        case DirectionMode::Fixed: return "fixed";
        case DirectionMode::Pca: return "pca";
        case DirectionMode::Coherent: return "coherent";
    }
    return "?";
}

namespace {

// The triangles of `ranges` cut into pieces of at most 4096: the pieces depend on the ranges only,
// so per-piece sums added in piece order do not depend on the thread count.
std::vector<TriangleRange> pieces(std::span<const TriangleRange> ranges) {
    constexpr uint32_t kPiece = 4096;
    std::vector<TriangleRange> out;
    for (const TriangleRange& r : ranges)
        for (uint32_t k = 0; k < r.count; k += kPiece) out.push_back({r.first + k, std::min(kPiece, r.count - k)});
    return out;
}

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
    const std::vector<TriangleRange> ps = pieces(ranges);
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
    const std::vector<TriangleRange> ps = pieces(ranges);
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

void CullideOptions::validate() const {
    if (directions.empty()) throw InputError("option --directions", "no directions given");
    for (const Vec3d& d : directions)
        if (!d.allFinite() || d.norm() == 0)
            throw InputError("option --directions", "a direction is zero or not finite");
    if (width < 1 || width > kMaxViewportSide || height < 1 || height > kMaxViewportSide)
        throw InputError("option --resolution",
                         "the viewport must be 1 to " + std::to_string(kMaxViewportSide) + " pixels per side, not " +
                             std::to_string(width) + "x" + std::to_string(height));
    if (autoCoverage != 0 && !(autoCoverage > 0 && autoCoverage <= kMaxAutoCoverage))
        throw InputError("option --resolution",
                         "the adaptive resolution's K must be more than 0 and at most " +
                             std::to_string(int(kMaxAutoCoverage)) + " pixels");
    if (autoCoverage != 0 && autoBudget < int64_t(width) * height)
        throw InputError("option --resolution",
                         "the adaptive resolution's pixel budget (" + std::to_string(autoBudget) +
                             ") is smaller than the base viewport");
    if (hierarchy.leafSize < 1) throw InputError("option --leaf-size", "the leaf size must be at least 1");
    if (hierarchy.branching < 2) throw InputError("option --branching", "the branching must be at least 2");
    if (exactSwitch.kind == ExactSwitchKind::Below && exactSwitch.triangles < 1)
        throw InputError("option --exact-switch", "the switch's triangle count must be at least 1");
}

void appendModifiedReducePcs(CommandList& list, std::span<const TriangleRange> ranges, std::span<uint32_t> forwardQuery,
                             std::span<uint32_t> reverseQuery) {
    CULLIDE_CHECK(forwardQuery.size() == ranges.size() && reverseQuery.size() == ranges.size(),
                  "appendModifiedReducePcs: one query slot per range");
    // Forward: write the object, then test it against everything so far, itself included, with
    // GREATER (anything in front of one of its fragments fails it).
    list.clear(1.0);
    for (size_t i = 0; i < ranges.size(); ++i) {
        list.depthMask(true);
        list.depthFunc(DepthFunc::Less);
        list.draw(ranges[i].first, ranges[i].count);
        list.depthMask(false);
        list.depthFunc(DepthFunc::Greater);
        forwardQuery[i] = list.beginQuery(QueryKind::SamplesPassed);
        list.draw(ranges[i].first, ranges[i].count);
        list.endQuery();
    }
    // Reverse: test against the objects after it, then write it.
    list.clear(1.0);
    for (size_t i = ranges.size(); i-- > 0;) {
        list.depthMask(false);
        list.depthFunc(DepthFunc::Greater);
        reverseQuery[i] = list.beginQuery(QueryKind::SamplesPassed);
        list.draw(ranges[i].first, ranges[i].count);
        list.endQuery();
        list.depthMask(true);
        list.depthFunc(DepthFunc::Less);
        list.draw(ranges[i].first, ranges[i].count);
    }
}

namespace {

// The ranges cut into pieces of at most kPiece triangles: the unit of the parallel loops over a
// call's triangles. The pieces depend on the ranges only, so a reduction over them in piece order
// does not depend on the thread count.
constexpr uint32_t kPiece = 4096;
std::vector<TriangleRange> piecesOf(std::span<const TriangleRange> ranges) {
    std::vector<TriangleRange> pieces;
    for (const TriangleRange& r : ranges)
        for (uint32_t k = 0; k < r.count; k += kPiece) pieces.push_back({r.first + k, std::min(kPiece, r.count - k)});
    return pieces;
}

}  // namespace

namespace {

OrthoView fitBox(OrthoView view, Vec3d lo, Vec3d hi);

// fitView's view before its box: the frame looking along dir, the viewport and depth format.
OrthoView frameOf(const Vec3d& dir, int width, int height, const DepthFormat& depth) {
    OrthoView view = OrthoView::looking(dir);
    view.width = width;
    view.height = height;
    view.depth = depth;
    return view;
}

// The bounds in `view`'s frame of the points that `each(i, f)` passes to f for block i of
// `blocks`, per block in parallel; min and max are exact, so the result is the same for any split.
//
// A frame whose rows are signed world axes (the `axes` directions): a row's projection right.p is
// the coordinate times +-1 (the dot product's other terms are zeros), so the bounds are the
// points' float box, permuted and negated: the same numbers, but for the sign of a zero, which
// fitBox's arithmetic does not see. No dot products per point (a fit was 3% of a prune on one
// thread; this saved 1-2%).
template <typename Each>
std::pair<Vec3d, Vec3d> projectedBounds(const OrthoView& view, size_t blocks, const Each& each) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    int axis[3], sign[3];
    bool axisFrame = true;
    const Vec3d* rows[3] = {&view.right, &view.up, &view.dir};
    for (int r = 0; r < 3 && axisFrame; ++r) {
        int nonZero = 0;
        for (int k = 0; k < 3; ++k)
            if ((*rows[r])[k] != 0) axis[r] = k, ++nonZero;
        axisFrame = nonZero == 1 && std::abs((*rows[r])[axis[r]]) == 1.0;
        if (axisFrame) sign[r] = (*rows[r])[axis[r]] > 0 ? 1 : -1;
    }
    if (axisFrame) {
        constexpr float finf = std::numeric_limits<float>::infinity();
        std::vector<std::array<float, 6>> boxes(blocks);
        parallelFor(0, blocks, 1, [&](const auto& block) {
            for (size_t i = block.begin(); i != block.end(); ++i) {
                float lo[3] = {finf, finf, finf}, hi[3] = {-finf, -finf, -finf};
                each(i, [&](const Vec3f& point) {
                    for (int k = 0; k < 3; ++k) {
                        lo[k] = std::min(lo[k], point[k]);
                        hi[k] = std::max(hi[k], point[k]);
                    }
                });
                boxes[i] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
            }
        });
        float lo[3] = {finf, finf, finf}, hi[3] = {-finf, -finf, -finf};
        for (const auto& b : boxes)
            for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], b[k]), hi[k] = std::max(hi[k], b[k + 3]);
        Vec3d qlo, qhi;
        for (int r = 0; r < 3; ++r) {
            const double l = lo[axis[r]], h = hi[axis[r]];
            qlo[r] = sign[r] > 0 ? l : -h;
            qhi[r] = sign[r] > 0 ? h : -l;
        }
        return {qlo, qhi};
    }
    std::vector<std::pair<Vec3d, Vec3d>> bounds(blocks);
    parallelFor(0, blocks, 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i) {
            Vec3d lo(inf, inf, inf), hi(-inf, -inf, -inf);
            each(i, [&](const Vec3f& point) {
                const Vec3d p = point.cast<double>();
                const Vec3d q(view.right.dot(p), view.up.dot(p), view.dir.dot(p));
                lo = lo.cwiseMin(q);
                hi = hi.cwiseMax(q);
            });
            bounds[i] = {lo, hi};
        }
    });
    Vec3d lo(inf, inf, inf), hi(-inf, -inf, -inf);
    for (const auto& [l, h] : bounds) lo = lo.cwiseMin(l), hi = hi.cwiseMax(h);
    return {lo, hi};
}

}  // namespace

OrthoView fitView(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                  std::span<const TriangleRange> ranges, const Vec3d& dir, int width, int height,
                  const DepthFormat& depth) {
    const OrthoView view = frameOf(dir, width, height, depth);
    // Per piece in parallel (levels 0-2 fit the whole mesh: 4-6% of a prune on one thread).
    const std::vector<TriangleRange> pieces = piecesOf(ranges);
    const auto [lo, hi] = projectedBounds(view, pieces.size(), [&](size_t i, auto&& f) {
        for (uint32_t t = pieces[i].first; t < pieces[i].first + pieces[i].count; ++t)
            for (uint32_t v : triangles[t]) f(positions[v]);
    });
    return fitBox(view, lo, hi);
}

namespace {

// fitView of every point: for a draw of every triangle of a geometry whose every vertex some
// triangle uses, the same view (min and max are exact), from each vertex once instead of each
// triangle corner (a vertex is the corner of about six triangles).
OrthoView fitViewToPoints(std::span<const Vec3f> positions, const Vec3d& dir, int width, int height,
                          const DepthFormat& depth) {
    const OrthoView view = frameOf(dir, width, height, depth);
    constexpr size_t kBlock = 4096;
    const auto [lo, hi] = projectedBounds(view, (positions.size() + kBlock - 1) / kBlock, [&](size_t i, auto&& f) {
        for (size_t v = i * kBlock; v < std::min(positions.size(), (i + 1) * kBlock); ++v) f(positions[v]);
    });
    return fitBox(view, lo, hi);
}

// The box of fitView around the bounds [lo, hi] in `view`'s frame, at its viewport and depth.
OrthoView fitBox(OrthoView view, Vec3d lo, Vec3d hi) {
    const int width = view.width, height = view.height;
    const DepthFormat depth = view.depth;
    if (!(lo.x() <= hi.x())) lo = hi = Vec3d::Zero();  // nothing to fit: any valid view will do

    // Square pixels: the pixel size that fits both extents; the box centred on the bounds.
    const double scale = std::max({std::abs(lo.x()), std::abs(hi.x()), std::abs(lo.y()), std::abs(hi.y()),
                                   std::abs(lo.z()), std::abs(hi.z()), 1e-30});
    const double tiny = scale * 1e-6;
    const double pixel =
        std::max({(hi.x() - lo.x()) / width, (hi.y() - lo.y()) / height, tiny / std::max(width, height)});
    const double cx = 0.5 * (lo.x() + hi.x()), cy = 0.5 * (lo.y() + hi.y());
    view.xmin = cx - 0.5 * pixel * width;
    view.xmax = cx + 0.5 * pixel * width;
    view.ymin = cy - 0.5 * pixel * height;
    view.ymax = cy + 0.5 * pixel * height;
    // Depth: the extent plus two depth units at each end (so the farthest fragment stays below
    // the cleared value 1.0 after rounding, and the nearest above 0).
    const double extent = std::max(hi.z() - lo.z(), tiny);
    const double margin = 2.0 * depth.resolution();
    const double range = extent / (1.0 - 2.0 * margin);
    view.znear = lo.z() - margin * range;
    view.zfar = view.znear + range;
    if (view.zfar < hi.z() + margin * range) view.zfar = hi.z() + margin * range;
    return view;
}

}  // namespace

std::pair<int, int> adaptiveViewport(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                     std::span<const TriangleRange> ranges, const Vec3d& dir, double coverage,
                                     int baseWidth, int baseHeight, int64_t budget, int maxSide) {
    const OrthoView frame = OrthoView::looking(dir);
    size_t n = 0;
    for (const TriangleRange& r : ranges) n += r.count;
    if (n == 0) return {baseWidth, baseHeight};
    // The PCS's projected area (the sum of its triangles' areas in the view plane) and bounds, per
    // piece of at most kPiece triangles and then in piece order: the pieces depend on the ranges
    // only, so the sums do not depend on the thread count.
    struct ProjectedBox {
        double area, xlo, xhi, ylo, yhi;
    };
    const std::vector<TriangleRange> pieces = piecesOf(ranges);
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<ProjectedBox> perPiece(pieces.size(), ProjectedBox{0, inf, -inf, inf, -inf});
    parallelFor(0, pieces.size(), 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i) {
            ProjectedBox& b = perPiece[i];
            for (uint32_t k = 0; k < pieces[i].count; ++k) {
                const Triangle& t = triangles[pieces[i].first + k];
                double x[3], y[3];
                for (int c = 0; c < 3; ++c) {
                    const Vec3d p = positions[t[c]].cast<double>();
                    x[c] = frame.right.dot(p), y[c] = frame.up.dot(p);
                    b.xlo = std::min(b.xlo, x[c]), b.xhi = std::max(b.xhi, x[c]);
                    b.ylo = std::min(b.ylo, y[c]), b.yhi = std::max(b.yhi, y[c]);
                }
                b.area += 0.5 * std::abs((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
            }
        }
    });
    ProjectedBox all{0, inf, -inf, inf, -inf};
    for (const ProjectedBox& b : perPiece) {
        all.area += b.area;
        all.xlo = std::min(all.xlo, b.xlo), all.xhi = std::max(all.xhi, b.xhi);
        all.ylo = std::min(all.ylo, b.ylo), all.yhi = std::max(all.yhi, b.yhi);
    }
    const double ex = all.xhi - all.xlo, ey = all.yhi - all.ylo;
    // The base's pixel (fitView's at the base viewport) and the wanted one: the PCS covers
    // `coverage` base viewports' worth of pixels.
    const double basePixel = std::max(ex / baseWidth, ey / baseHeight);
    const double wanted = std::sqrt(all.area / (coverage * double(baseWidth) * double(baseHeight)));
    if (!(basePixel > 0) || !(wanted < basePixel)) return {baseWidth, baseHeight};
    // Sides covering the bounds at the wanted pixel, in double so that nothing overflows.
    double w = std::max(1.0, std::ceil(ex / wanted)), h = std::max(1.0, std::ceil(ey / wanted));
    if (w * h > double(budget)) {
        const double f = std::sqrt(double(budget) / (w * h));
        w = std::max(1.0, std::floor(w * f)), h = std::max(1.0, std::floor(h * f));
    }
    const double side = double(std::clamp(maxSide, 1, kMaxViewportSide));
    if (w > side || h > side) {
        const double f = side / std::max(w, h);
        w = std::clamp(std::floor(w * f), 1.0, side), h = std::clamp(std::floor(h * f), 1.0, side);
    }
    // Rounding down to the budget or the side limit may have made the pixel the base's or coarser:
    // then the base itself (the side limit aside, never coarser than the base).
    if (std::max(ex / w, ey / h) >= basePixel && baseWidth <= side && baseHeight <= side)
        return {baseWidth, baseHeight};
    return {int(w), int(h)};
}

std::vector<std::vector<uint32_t>> viewGroups(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                              std::span<const TriangleRange> ranges, const Vec3d& dir) {
    const OrthoView frame = OrthoView::looking(dir);
    const size_t n = ranges.size();
    // Each item's projected rectangle, closed. Two triangles that share a point p have p's exact
    // projection inside both exact rectangles; the computed ones differ from those by the dot
    // products' rounding, a few units in the last place of |p|, far below the 1e-9 * |p|_1 added
    // on every side: so touching items always overlap here. Snapping and conservative dilation
    // need nothing: the argument is about the triangles themselves, not their images.
    struct Rect {
        double xlo, xhi, ylo, yhi;
    };
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<Rect> rect(n, Rect{inf, -inf, inf, -inf});
    parallelFor(0, n, 1, [&](const auto& block) {
        for (size_t i = block.begin(); i != block.end(); ++i) {
            Rect& r = rect[i];
            double scale = 0;
            for (uint32_t t = ranges[i].first; t < ranges[i].first + ranges[i].count; ++t)
                for (uint32_t v : triangles[t]) {
                    const Vec3d p = positions[v].cast<double>();
                    const double x = frame.right.dot(p), y = frame.up.dot(p);
                    r.xlo = std::min(r.xlo, x), r.xhi = std::max(r.xhi, x);
                    r.ylo = std::min(r.ylo, y), r.yhi = std::max(r.yhi, y);
                    scale = std::max(scale, p.cwiseAbs().sum());
                }
            const double eps = 1e-9 * scale;
            r.xlo -= eps, r.xhi += eps, r.ylo -= eps, r.yhi += eps;
        }
    });
    // Connected components of overlap: a sweep in increasing xlo (ties by index) keeps the items
    // whose x extent reaches the current one and unites those whose y extents meet it too.
    std::vector<uint32_t> order(n), parent(n);
    std::iota(order.begin(), order.end(), 0u);
    std::iota(parent.begin(), parent.end(), 0u);
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return std::tie(rect[a].xlo, a) < std::tie(rect[b].xlo, b); });
    auto find = [&](uint32_t a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    };
    std::vector<uint32_t> active;
    for (uint32_t i : order) {
        const Rect& r = rect[i];
        if (!(r.xlo <= r.xhi)) continue;  // an empty item: a group of its own
        size_t keep = 0;
        for (uint32_t a : active) {
            if (rect[a].xhi < r.xlo) continue;  // ends before every item still to come
            active[keep++] = a;
            if (rect[a].ylo <= r.yhi && r.ylo <= rect[a].yhi) {
                const uint32_t ra = find(a), ri = find(i);
                if (ra != ri) parent[std::max(ra, ri)] = std::min(ra, ri);
            }
        }
        active.resize(keep);
        active.push_back(i);
    }
    // Roots are each group's smallest index, so numbering the groups in index order numbers them
    // by their first item.
    std::vector<std::vector<uint32_t>> groups;
    std::vector<uint32_t> groupOf(n);
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t root = find(i);
        if (root == i) {
            groupOf[i] = uint32_t(groups.size());
            groups.emplace_back();
        }
        groups[groupOf[root]].push_back(i);
    }
    return groups;
}

namespace {

// One node of the PCS: an object's hierarchy node, and its triangles in the uploaded geometry.
struct Item {
    uint32_t object = 0, node = 0;
    TriangleRange range;
};

class Culler {
public:
    // `consumed`: the scene (the same object) may be emptied once the geometry is uploaded.
    Culler(const Scene& scene, DepthBackend& backend, const CullideOptions& opt, Scene* consumed = nullptr)
        : scene_(scene), backend_(backend), opt_(opt), consumed_(consumed) {}
    ~Culler() {
        if (lent_) backend_.borrowGeometry({}, {});  // the arrays die with this run
    }
    Culler(const Culler&) = delete;
    Culler& operator=(const Culler&) = delete;

    CullideResult run() {
        const auto start = Clock::now();
        CullideResult result;
        build(result);
        if (opt_.recordPrunes) {
            sceneOffset_.assign(hierarchies_.size() + 1, 0);
            keptMark_.resize(hierarchies_.size());
            for (size_t i = 0; i < hierarchies_.size(); ++i) {
                sceneOffset_[i + 1] = sceneOffset_[i] + hierarchies_[i]->order.size();
                keptMark_[i].assign(hierarchies_[i]->nodes.size(), 0);
            }
            result.prunedAtCall.assign(sceneOffset_.back(), CullideResult::kNotPruned);
            prunedAt_ = &result.prunedAtCall;
        }

        std::vector<Item> pcs;
        if (opt_.method == CullMethod::Reliable) {
            runReliable(result);
            recordHistory(result);
            result.totalSeconds = secondsSince(start);
            return result;
        }
        for (uint32_t i = 0; i < hierarchies_.size(); ++i)
            if (!hierarchies_[i]->nodes.empty() && hierarchies_[i]->nodes[0].count > 0) pcs.push_back(item(i, 0));

        bool switched = false;  // to the exact stage (CullideOptions::exactSwitch)
        for (uint32_t level = 0; !pcs.empty(); ++level) {
            const std::vector<std::pair<uint32_t, Vec3d>> dirs = callDirections(pcs, level);
            for (size_t k = 0; k < dirs.size() && !pcs.empty(); ++k) {
                if ((switched = switchNow(pcs, level, k == 0, result))) break;
                result.levels = level + 1;
                dir_ = dirs[k].second;
                pcs = reduce(pcs, level, dirs[k].first, result.passes);
            }
            if (switched) break;
            if (dirs.empty()) result.levels = level + 1;  // coherent: a level with no call is still visited
            bool allLeaves = true;
            for (const Item& it : pcs) allLeaves = allLeaves && node(it).isLeaf();
            if (pcs.empty() || allLeaves) break;
            std::vector<Item> next;  // children replace their parent in place: objects stay contiguous
            for (const Item& it : pcs) {
                const HierarchyNode& n = node(it);
                if (n.isLeaf()) next.push_back(it);
                else
                    for (uint32_t c = 0; c < n.childCount; ++c) next.push_back(item(it.object, n.firstChild + c));
            }
            pcs = std::move(next);
        }

        result.pcs = expand(pcs);
        recordHistory(result);
        result.totalSeconds = secondsSince(start);
        return result;
    }

private:
    // The directions of this run's calls on `pcs` at `step` (the level, or a reliable round): (the
    // index PassStats::direction records, the direction). Fixed: the given list; Coherent: the
    // history's plan for the step; Pca: pcaDirections of the PCS.
    std::vector<std::pair<uint32_t, Vec3d>> callDirections(const std::vector<Item>& pcs, uint32_t step) {
        step_ = step;
        std::vector<std::pair<uint32_t, Vec3d>> out;
        if (opt_.directionMode == DirectionMode::Pca) {
            ranges_.clear();
            for (const Item& it : pcs) ranges_.push_back(it.range);
            const std::vector<Vec3d> dirs = pcaDirections(positions_, triangles_, ranges_);
            for (uint32_t k = 0; k < dirs.size(); ++k) out.push_back({k, dirs[k]});
            return out;
        }
        const size_t n = opt_.directions.size();
        if (opt_.directionMode == DirectionMode::Coherent && opt_.directionHistory) {
            for (uint32_t d : opt_.directionHistory->plan(step, n)) out.push_back({d, opt_.directions[d]});
        } else {
            for (uint32_t d = 0; d < n; ++d) out.push_back({d, opt_.directions[d]});
        }
        return out;
    }

    void recordHistory(const CullideResult&) {
        if (opt_.directionMode == DirectionMode::Coherent && opt_.directionHistory)
            opt_.directionHistory->record(opt_.directions.size(), std::move(stepPruned_));
    }

    // World meshes, hierarchies, and the geometry upload (each object's triangles in hierarchy order).
    void build(CullideResult& result) {
        const size_t n = scene_.objects.size();
        const auto start = Clock::now();
        std::vector<Mesh> world(n);
        hierarchies_.resize(n);
        HierarchyCache* cache = opt_.hierarchyCache.get();
        if (cache) cache->resize(n);
        else built_.resize(n);
        parallelForEach(0, n, [&](size_t i) {
            world[i] = scene_.worldMesh(i);
            if (cache) {
                hierarchies_[i] = &cache->get(i, world[i], opt_.hierarchy);
            } else {
                built_[i] = buildHierarchy(world[i], opt_.hierarchy);
                hierarchies_[i] = &built_[i];
            }
        });
        result.hierarchySeconds = secondsSince(start);
        if (cache)
            for (size_t i = 0; i < n; ++i) result.hierarchiesReused += cache->reused(i) ? 1 : 0;

        triangleOffset_.assign(n, 0);
        size_t vertices = 0, triangles = 0;
        for (size_t i = 0; i < n; ++i) {
            triangleOffset_[i] = uint32_t(triangles);
            vertices += world[i].positions.size();
            triangles += world[i].triangles.size();
        }
        if (vertices > std::numeric_limits<uint32_t>::max() || triangles > std::numeric_limits<uint32_t>::max())
            throw InputError("scene", "more than 2^32 vertices or triangles");
        positions_.clear();
        positions_.reserve(vertices);
        triangles_.clear();
        triangles_.reserve(triangles);
        // Each object's vertices are renumbered in the order its triangles, in hierarchy order,
        // first use them (unused ones dropped): a node's triangles then read nearby vertices, so
        // every pass over a draw (its view's fit, setup's gathers) stays in cache. Only indices
        // change, and which triangles share a vertex does not: the same images and PCS.
        std::vector<uint32_t> renumber;
        for (size_t i = 0; i < n; ++i) {
            renumber.assign(world[i].positions.size(), UINT32_MAX);
            for (uint32_t t : hierarchies_[i]->order) {
                const Triangle& tri = world[i].triangles[t];
                Triangle out;
                for (int k = 0; k < 3; ++k) {
                    uint32_t& v = renumber[tri[k]];
                    if (v == UINT32_MAX) {
                        v = uint32_t(positions_.size());
                        positions_.push_back(world[i].positions[tri[k]]);
                    }
                    out[k] = v;
                }
                triangles_.push_back(out);
            }
        }
        world = {};
        if (consumed_) *consumed_ = Scene{};  // scene_ is not read after build()
        // Lent, not copied, where the backend can read it in place: positions_ and triangles_
        // live and stay unchanged until the destructor takes them back.
        lent_ = backend_.borrowGeometry(positions_, triangles_);
    }

    // The triangles of the given nodes (disjoint), as (object, triangle) sorted. Where many of an
    // object's triangles are asked for (onPass after the first levels: most of the mesh), they are
    // marked and read back in order, linear in the object's size; a few are sorted.
    std::vector<PcsTriangle> expand(const std::vector<Item>& items) const {
        const size_t objects = hierarchies_.size();
        std::vector<size_t> start(objects + 1, 0), triangles(objects, 0);  // items by object (counting sort)
        for (const Item& it : items) ++start[it.object + 1], triangles[it.object] += node(it).count;
        std::partial_sum(start.begin(), start.end(), start.begin());
        std::vector<uint32_t> byObject(items.size());
        std::vector<size_t> fill(start.begin(), start.end() - 1);
        for (uint32_t i = 0; i < items.size(); ++i) byObject[fill[items[i].object]++] = i;

        std::vector<PcsTriangle> out;
        out.reserve(std::accumulate(triangles.begin(), triangles.end(), size_t(0)));
        std::vector<uint8_t> marks;
        for (uint32_t o = 0; o < objects; ++o) {
            if (triangles[o] == 0) continue;
            const std::vector<uint32_t>& order = hierarchies_[o]->order;
            const bool dense = triangles[o] * 8 >= order.size();
            const size_t from = out.size();
            if (dense) marks.assign(order.size(), 0);
            for (size_t b = start[o]; b < start[o + 1]; ++b) {
                const HierarchyNode& n = node(items[byObject[b]]);
                for (uint32_t k = n.first; k < n.first + n.count; ++k) {
                    if (dense) marks[order[k]] = 1;
                    else out.push_back({o, order[k]});
                }
            }
            if (dense) {
                for (uint32_t t = 0; t < marks.size(); ++t)
                    if (marks[t]) out.push_back({o, t});
            } else {
                std::sort(out.begin() + ptrdiff_t(from), out.end());
            }
        }
        return out;
    }

    // Switch to exact (ExactSwitch): whether to stop before the next reducePCS call on `pcs`, at
    // `level`; `groupStart`: the call begins a level (a round for reliable) after the first, where
    // auto predicts. Records the switch in `result`.
    bool switchNow(const std::vector<Item>& pcs, uint32_t level, bool groupStart, CullideResult& result) const {
        const ExactSwitch& sw = opt_.exactSwitch;
        if (sw.kind == ExactSwitchKind::Never) return false;
        size_t triangles = 0;
        for (const Item& it : pcs) triangles += it.range.count;
        bool stop = false;
        if (sw.kind == ExactSwitchKind::Below) {
            stop = triangles < sw.triangles;
        } else if (sw.kind == ExactSwitchKind::AtLevel) {
            stop = groupStart && (opt_.method == CullMethod::Reliable ? round_ : level) == sw.level;
        } else if (groupStart && !result.passes.empty()) {
            // The last level's (round's) calls: their time, scaled by the PCS's shrinking since,
            // and the fraction of the PCS they kept.
            const PassStats& last = result.passes.back();
            double seconds = 0;
            size_t first = result.passes.size();
            while (first > 0 && result.passes[first - 1].level == last.level &&
                   result.passes[first - 1].round == last.round)
                seconds += result.passes[--first].seconds;
            const size_t began = result.passes[first].trianglesIn;
            const double kept = began ? double(last.trianglesOut) / double(began) : 1;
            auto exact = [&](size_t n) {
                return sw.exactCost ? sw.exactCost(n) : double(n) * kExactSecondsPerTriangle;
            };
            result.predictedLevelSeconds = began ? seconds * double(triangles) / double(began) : 0;
            result.predictedExactSeconds = exact(triangles);
            const double saved = result.predictedExactSeconds - exact(size_t(std::llround(kept * double(triangles))));
            stop = result.predictedLevelSeconds > saved;  // false when saved is NaN (an infinite model)
        }
        if (stop) result.switchedAtLevel = int32_t(level), result.switchedAtTriangles = triangles;
        return stop;
    }

    const HierarchyNode& node(const Item& it) const { return hierarchies_[it.object]->nodes[it.node]; }

    Item item(uint32_t object, uint32_t nodeIndex) const {
        const HierarchyNode& n = hierarchies_[object]->nodes[nodeIndex];
        return {object, nodeIndex, {triangleOffset_[object] + n.first, n.count}};
    }

    // The reliable method (docs/reliable.md): straight to the leaves, whose internal and adjacent
    // pairs only an exact check can clear (a node above them can never be pruned soundly without
    // knowing its own pairs); then one reliable reducePCS per direction.
    void runReliable(CullideResult& result) {
        std::vector<Item> pcs;
        uint32_t depth = 0;
        for (uint32_t i = 0; i < hierarchies_.size(); ++i) {
            const Hierarchy& h = *hierarchies_[i];
            std::vector<Item> leaves;
            for (uint32_t k = 0; k < h.nodes.size(); ++k)
                if (h.nodes[k].isLeaf() && h.nodes[k].count > 0) {
                    leaves.push_back(item(i, k));
                    depth = std::max(depth, h.nodes[k].depth);
                }
            std::sort(leaves.begin(), leaves.end(),
                      [](const Item& a, const Item& b) { return a.range.first < b.range.first; });
            pcs.insert(pcs.end(), leaves.begin(), leaves.end());
        }
        result.levels = pcs.empty() ? 0 : 1;
        // Exact checks, once: pairs inside a leaf and between leaves sharing a vertex.
        ranges_.clear();
        for (const Item& it : pcs) ranges_.push_back(it.range);
        const detail::UnitGraph all = detail::unitAdjacency(triangles_, ranges_);
        const std::vector<uint8_t> hits = detail::exactHits(positions_, triangles_, ranges_, all);
        exactHit_.assign(hierarchies_.size(), {});
        for (uint32_t i = 0; i < hierarchies_.size(); ++i) exactHit_[i].assign(hierarchies_[i]->nodes.size(), 0);
        for (size_t u = 0; u < pcs.size(); ++u) exactHit_[pcs[u].object][pcs[u].node] = hits[u];
        // With adaptive resolution, rounds of calls until one prunes nothing: each round's views are
        // refitted to the smaller PCS, so its pixels are finer. Every call is sound on its own
        // (docs/reliable.md), so any number of them is.
        bool switched = false;  // to the exact stage: before a call, or (auto) before a round after the first
        for (round_ = 0; !switched; ++round_) {
            const size_t before = pcs.size();
            const std::vector<std::pair<uint32_t, Vec3d>> dirs = callDirections(pcs, round_);
            for (size_t k = 0; k < dirs.size() && !pcs.empty(); ++k) {
                if ((switched = switchNow(pcs, depth, k == 0 && round_ > 0, result))) break;
                dir_ = dirs[k].second;
                pcs = reduceReliable(pcs, depth, dirs[k].first, result.passes);
            }
            if (switched || opt_.autoCoverage <= 0 || pcs.empty() || pcs.size() == before) break;
        }
        result.pcs = expand(pcs);
    }

    // One reliable reducePCS call in direction d (docs/reliable.md). Units are the PCS leaves.
    // Per class b of a distance-2 colouring of the units' vertex-sharing graph, with an emptied
    // interval buffer: forward, for each unit y of b in order, test every unit whose (unique)
    // neighbour in b is y, test y, then write y; then test the units with no neighbour in b.
    // Reverse: the same in reverse order without the last step. Every unit X is thus tested
    // against every other unit not adjacent to it, exactly once per side, and never against a
    // unit it shares a vertex with.
    std::vector<Item> reduceReliable(const std::vector<Item>& pcs, uint32_t level, uint32_t d,
                                     std::vector<PassStats>& passes) {
        const auto start = Clock::now();
        // A unit alone in its view has no unit to be tested against: it stays for its exact pairs only.
        std::vector<Item> kept = byViews(
            pcs, [&](const std::vector<Item>& units) { return testUnits(units); },
            [&](const std::vector<Item>& units) {
                return units.size() == 1 ? std::vector<uint8_t>{exactHit_[units[0].object][units[0].node]}
                                         : std::vector<uint8_t>{};
            });
        return finishCall(pcs, std::move(kept), level, d, start, passes);
    }

    // One reliable view: which of `pcs` stay (a conflict or an exact pair).
    std::vector<uint8_t> testUnits(const std::vector<Item>& pcs) {
        ranges_.clear();
        for (const Item& it : pcs) ranges_.push_back(it.range);
        setView();
        const uint32_t n = uint32_t(pcs.size());
        const detail::UnitGraph g = detail::unitAdjacency(triangles_, ranges_);
        const std::vector<uint32_t> colour = detail::distanceTwoColouring(g);
        const uint32_t classes = n == 0 ? 0 : *std::max_element(colour.begin(), colour.end()) + 1;
        std::vector<std::vector<uint32_t>> members(classes);
        for (uint32_t u = 0; u < n; ++u) members[colour[u]].push_back(u);

        list_.reset();
        std::vector<std::pair<uint32_t, uint32_t>> queries;  // (unit, query)
        auto test = [&](uint32_t u) {
            queries.push_back({u, list_.beginQuery(QueryKind::AnySamplesPassed)});
            list_.drawConservative(pcs[u].range.first, pcs[u].range.count, true, false);
            list_.endQuery();
        };
        std::vector<int64_t> matched(n);
        std::vector<std::vector<uint32_t>> matchedTo;
        for (uint32_t b = 0; b < classes; ++b) {
            // matched[x]: x's neighbour of class b (at most one, by the colouring), or -1.
            std::fill(matched.begin(), matched.end(), -1);
            matchedTo.assign(n, {});
            for (uint32_t x = 0; x < n; ++x) {
                if (colour[x] == b) continue;
                for (uint32_t y : g.neighbours(x))
                    if (colour[y] == b) {
                        CULLIDE_CHECK(matched[x] < 0, "distance-2 colouring gave a unit two neighbours of one class");
                        matched[x] = y;
                        matchedTo[y].push_back(x);
                    }
            }
            list_.clearIntervals();
            for (uint32_t y : members[b]) {
                for (uint32_t x : matchedTo[y]) test(x);
                test(y);
                list_.drawConservative(pcs[y].range.first, pcs[y].range.count, false, true);
            }
            for (uint32_t x = 0; x < n; ++x)
                if (colour[x] != b && matched[x] < 0) test(x);
            list_.clearIntervals();
            for (size_t k = members[b].size(); k-- > 0;) {
                const uint32_t y = members[b][k];
                for (uint32_t x : matchedTo[y]) test(x);
                test(y);
                list_.drawConservative(pcs[y].range.first, pcs[y].range.count, false, true);
            }
        }
        const std::vector<uint64_t> results = execute();
        std::vector<uint8_t> conflict(n, 0);
        for (const auto& [u, q] : queries) conflict[u] |= results[q] > 0 ? 1 : 0;

        std::vector<uint8_t> stays(n);
        for (uint32_t u = 0; u < n; ++u) stays[u] = conflict[u] || exactHit_[pcs[u].object][pcs[u].node];
        countView(Command::Op::DrawConservative);
        return stays;
    }

    // The view of a call in direction dir_ on ranges_: fitted at the fixed viewport, or at the one
    // adaptive resolution chooses for these triangles. A viewport larger than the backend draws is
    // cut into tiles_ of its largest side (row by row from the bottom-left), which execute() runs
    // one after the other; else tiles_ is empty and the backend gets the whole view here.
    void setView() {
        int w = opt_.width, h = opt_.height;
        if (opt_.autoCoverage > 0)
            std::tie(w, h) = adaptiveViewport(positions_, triangles_, ranges_, dir_, opt_.autoCoverage, opt_.width,
                                              opt_.height, opt_.autoBudget, kMaxViewportSide);
        size_t drawn = 0;
        for (const TriangleRange& r : ranges_) drawn += r.count;
        // Every triangle drawn (the first levels): positions_ holds only used vertices (build()
        // drops the others), so their bounds are the triangles'.
        view_ = drawn == triangles_.size() ? wholeFit(w, h)
                                           : fitView(positions_, triangles_, ranges_, dir_, w, h, opt_.depth);
        tiles_.clear();
        const int side = std::clamp(backend_.maxViewportSide(), 1, kMaxViewportSide);
        if (w <= side && h <= side) {
            backend_.setView(view_);
            return;
        }
        for (int y = 0; y < h; y += side)
            for (int x = 0; x < w; x += side)
                tiles_.push_back(view_.tile(x, y, std::min(side, w - x), std::min(side, h - y)));
    }

    // fitViewToPoints in direction dir_ at w x h, computed once per run: it depends on the
    // direction and viewport only (positions_ is fixed after build()), and the first levels draw
    // every triangle in the same directions level after level (the bunny's levels 0-2: 18 fits of
    // 6 views, 3-4% of a prune on one thread). At most kWholeFits are kept (per-level PCA
    // directions make new ones); later ones are computed every time.
    OrthoView wholeFit(int w, int h) {
        for (const auto& [d, v] : wholeFits_)
            if (d == dir_ && v.width == w && v.height == h) return v;
        const OrthoView v = fitViewToPoints(positions_, dir_, w, h, opt_.depth);
        if (wholeFits_.size() < kWholeFits) wholeFits_.push_back({dir_, v});
        return v;
    }

    // Runs list_ under the current view: once, or once per tile. A tile holds exactly the
    // fragments the whole view has at its pixels (OrthoView::tile), and every list of a call starts
    // from a clear with the depth mask set (each list leaves it set), so a query's result over the
    // whole view is the sum of its tiles' (SAMPLES_PASSED) or their maximum (ANY_SAMPLES_PASSED).
    std::vector<uint64_t> execute() {
        if (tiles_.empty()) return backend_.execute(list_);
        std::vector<uint8_t> any;  // per query: ANY_SAMPLES_PASSED
        for (const Command& c : list_.commands())
            if (c.op == Command::Op::BeginQuery) any.push_back(c.queryKind == QueryKind::AnySamplesPassed);
        std::vector<uint64_t> total(any.size(), 0);
        for (const OrthoView& tile : tiles_) {
            backend_.setView(tile);
            const std::vector<uint64_t> r = backend_.execute(list_);
            CULLIDE_CHECK(r.size() == total.size(), "a backend returned the wrong number of query results");
            for (size_t q = 0; q < r.size(); ++q) total[q] = any[q] ? std::max(total[q], r[q]) : total[q] + r[q];
        }
        return total;
    }

    // The nodes of `pcs` that stay after a call in direction dir_, in `pcs` order. With one view
    // (ViewMode::Fit, or a single group) `test(pcs)` draws them all, as the paper does. Otherwise
    // each group of viewGroups is drawn on its own by `test(group)`, with its own fitted view and
    // command list, unless `undrawn(group)` already says which of its nodes stay (non-empty).
    // Why that keeps every method's promise: the triangles of nodes in different groups have
    // disjoint projections in the call's frame, so no two of them cross or touch; whatever a
    // method promises is about such pairs, and each group's call is a call of the method on a PCS
    // of its own (any view will do: docs/cullide.md#views-per-cluster).
    template <typename Test, typename Undrawn>
    std::vector<Item> byViews(const std::vector<Item>& pcs, Test&& test, Undrawn&& undrawn) {
        views_ = {};
        std::vector<std::vector<uint32_t>> groups;
        if (opt_.views == ViewMode::Clustered && pcs.size() > 1) {
            ranges_.clear();
            for (const Item& it : pcs) ranges_.push_back(it.range);
            groups = viewGroups(positions_, triangles_, ranges_, dir_);
        }
        std::vector<uint8_t> stays;
        if (groups.size() <= 1) {
            stays = test(pcs);
        } else {
            stays.assign(pcs.size(), 0);
            std::vector<Item> group;
            for (const std::vector<uint32_t>& members : groups) {
                group.clear();
                for (uint32_t i : members) group.push_back(pcs[i]);
                std::vector<uint8_t> s = undrawn(group);
                if (s.empty()) s = test(group);
                for (size_t k = 0; k < members.size(); ++k) stays[members[k]] = s[k];
            }
        }
        std::vector<Item> kept;
        for (size_t i = 0; i < pcs.size(); ++i)
            if (stays[i]) kept.push_back(pcs[i]);
        return kept;
    }

    // Adds the view just executed (view_, list_) to the call's totals.
    void countView(Command::Op drawOp) {
        for (const Command& c : list_.commands())
            if (c.op == drawOp) views_.rendered += c.count;
        views_.queries += list_.queryCount();
        views_.tiles += std::max<uint32_t>(1, uint32_t(tiles_.size()));
        if (views_.count == 0 || int64_t(view_.width) * view_.height > int64_t(views_.width) * views_.height)
            views_.width = view_.width, views_.height = view_.height;
        ++views_.count;
    }

    // One reducePCS call in direction d: returns the nodes that stay.
    std::vector<Item> reduce(const std::vector<Item>& pcs, uint32_t level, uint32_t d, std::vector<PassStats>& passes) {
        const auto start = Clock::now();
        // The original method tests a node against the other objects only: in a view of one
        // object's nodes every node is fully visible, pruned without drawing. The modified method
        // tests a node against itself too, so even a lone node is drawn.
        std::vector<Item> kept = byViews(
            pcs, [&](const std::vector<Item>& nodes) { return testNodes(nodes); },
            [&](const std::vector<Item>& nodes) {
                const bool oneObject = std::all_of(nodes.begin(), nodes.end(),
                                                   [&](const Item& it) { return it.object == nodes[0].object; });
                return opt_.method == CullMethod::Original && oneObject ? std::vector<uint8_t>(nodes.size(), 0)
                                                                        : std::vector<uint8_t>{};
            });
        return finishCall(pcs, std::move(kept), level, d, start, passes);
    }

    // One view of a modified or original call: which of `pcs` stay (not fully visible).
    std::vector<uint8_t> testNodes(const std::vector<Item>& pcs) {
        ranges_.clear();
        for (const Item& it : pcs) ranges_.push_back(it.range);
        setView();

        list_.reset();
        // forwardQuery[i] / reverseQuery[i]: the query numbers of PCS item i in each pass.
        std::vector<uint32_t> forwardQuery(pcs.size()), reverseQuery(pcs.size());
        if (opt_.method == CullMethod::Modified) {
            appendModifiedReducePcs(list_, ranges_, forwardQuery, reverseQuery);  // Figure 3
        } else {
            // Figure 2, per object: query every node of the object with GEQUAL against the other
            // objects drawn so far, then write them all. Siblings never test each other.
            std::vector<std::pair<size_t, size_t>> groups;  // [begin, end) of each object's nodes
            for (size_t g = 0; g < pcs.size();) {
                size_t e = g;
                while (e < pcs.size() && pcs[e].object == pcs[g].object) ++e;
                groups.push_back({g, e});
                g = e;
            }
            auto group = [&](const std::pair<size_t, size_t>& grp, std::vector<uint32_t>& query) {
                list_.depthMask(false);
                list_.depthFunc(DepthFunc::GEqual);
                for (size_t i = grp.first; i < grp.second; ++i) {
                    query[i] = list_.beginQuery(QueryKind::SamplesPassed);
                    list_.draw(pcs[i].range.first, pcs[i].range.count);
                    list_.endQuery();
                }
                list_.depthMask(true);
                list_.depthFunc(DepthFunc::Less);
                for (size_t i = grp.first; i < grp.second; ++i) list_.draw(pcs[i].range.first, pcs[i].range.count);
            };
            list_.clear(1.0);
            for (const auto& grp : groups) group(grp, forwardQuery);
            list_.clear(1.0);
            for (size_t g = groups.size(); g-- > 0;) group(groups[g], reverseQuery);
        }

        const std::vector<uint64_t> results = execute();
        std::vector<uint8_t> stays(pcs.size());
        for (size_t i = 0; i < pcs.size(); ++i) {
            const bool fullyVisible = results[forwardQuery[i]] == 0 && results[reverseQuery[i]] == 0;
            stays[i] = !fullyVisible;
        }
        countView(Command::Op::Draw);
        return stays;
    }

    // options.recordPrunes: the triangles of the nodes in `pcs` but not in `kept` (a subset of
    // its nodes) were pruned by call `call`.
    void recordPrunes(const std::vector<Item>& pcs, const std::vector<Item>& kept, uint32_t call) {
        for (const Item& it : kept) keptMark_[it.object][it.node] = 1;
        for (const Item& it : pcs) {
            if (keptMark_[it.object][it.node]) continue;
            const Hierarchy& h = *hierarchies_[it.object];
            const HierarchyNode& n = node(it);
            uint32_t* const at = prunedAt_->data() + sceneOffset_[it.object];
            for (uint32_t k = n.first; k < n.first + n.count; ++k) at[h.order[k]] = call;
        }
        for (const Item& it : kept) keptMark_[it.object][it.node] = 0;  // clear for the next call
    }

    // The statistics of one reducePCS call from `pcs` to `kept` (its views' totals, views_),
    // appended to `passes` and reported to onPass and onPassStats. Returns `kept`.
    std::vector<Item> finishCall(const std::vector<Item>& pcs, std::vector<Item> kept, uint32_t level, uint32_t d,
                                 Clock::time_point start, std::vector<PassStats>& passes) {
        PassStats st;
        st.level = level;
        st.direction = d;
        st.dirVector = dir_;
        st.nodesIn = pcs.size();
        for (const Item& it : pcs) st.trianglesIn += it.range.count;
        st.nodesOut = kept.size();
        for (const Item& it : kept) st.trianglesOut += it.range.count;
        if (opt_.directionMode == DirectionMode::Coherent) {
            if (stepPruned_.size() <= step_) stepPruned_.resize(step_ + 1);
            std::vector<size_t>& p = stepPruned_[step_];
            p.resize(opt_.directions.size(), 0);
            p[d] += st.trianglesIn - st.trianglesOut;
        }
        st.trianglesRendered = views_.rendered;
        st.queries = views_.queries;
        // No view drawn (every group was decided undrawn): the base viewport.
        st.width = views_.count ? views_.width : opt_.width, st.height = views_.count ? views_.height : opt_.height;
        st.views = views_.count;
        st.tiles = views_.tiles;
        st.round = round_;
        st.seconds = secondsSince(start);
        if (prunedAt_) recordPrunes(pcs, kept, uint32_t(passes.size()));
        passes.push_back(st);
        if (opt_.onPass) opt_.onPass(st, expand(kept));
        if (opt_.onPassStats) opt_.onPassStats(st);
        return kept;
    }

    // options.recordPrunes: result.prunedAtCall, each object's first triangle in it, and a mark
    // per node (all clear between calls).
    std::vector<uint32_t>* prunedAt_ = nullptr;
    std::vector<size_t> sceneOffset_;
    std::vector<std::vector<uint8_t>> keptMark_;

    const Scene& scene_;
    DepthBackend& backend_;
    const CullideOptions& opt_;
    Scene* consumed_;
    bool lent_ = false;  // the backend reads positions_ and triangles_ in place
    std::vector<Hierarchy> built_;  // without a cache: this run's hierarchies
    std::vector<const Hierarchy*> hierarchies_;  // per object: in built_ or in the cache
    std::vector<uint32_t> triangleOffset_;
    std::vector<Vec3f> positions_;
    std::vector<Triangle> triangles_;
    std::vector<TriangleRange> ranges_;
    CommandList list_;
    OrthoView view_;  // the current view's
    // The current call's views so far: triangles rendered, queries, the largest viewport, count.
    struct ViewTotals {
        size_t rendered = 0, queries = 0;
        int width = 0, height = 0;
        uint32_t count = 0, tiles = 0;
    } views_;
    std::vector<OrthoView> tiles_;  // the current view's tiles (empty: drawn whole)
    Vec3d dir_ = Vec3d::Zero();  // the current call's direction
    static constexpr size_t kWholeFits = 64;
    std::vector<std::pair<Vec3d, OrthoView>> wholeFits_;  // wholeFit's: (direction, view)
    uint32_t step_ = 0;  // the current level (reliable: round), for the coherent history
    std::vector<std::vector<size_t>> stepPruned_;  // coherent: [step][direction] triangles pruned
    uint32_t round_ = 0;  // reliable with adaptive resolution: the current round of calls
    std::vector<std::vector<uint8_t>> exactHit_;  // reliable: per object and node, an exact pair may intersect
};

}  // namespace

namespace {
void checkRunnable(DepthBackend& backend, const CullideOptions& options) {
    options.validate();
    if (options.method == CullMethod::Reliable && !backend.supportsConservative())
        throw InputError(
            "option --method",
            "reliable is CPU-only: this backend (" + backend.describe() + ") has no conservative rasterization");
}
}  // namespace

CullideResult runCullide(const Scene& scene, DepthBackend& backend, const CullideOptions& options) {
    checkRunnable(backend, options);
    return Culler(scene, backend, options).run();
}

CullideResult runCullide(Scene&& scene, DepthBackend& backend, const CullideOptions& options) {
    checkRunnable(backend, options);
    return Culler(scene, backend, options, &scene).run();
}

}  // namespace cullide
