// Attribution of false prunes to the causes of the seed paper's Section 5 (causes.h).
#include "cullide/study/causes.h"

#include "polygon.h"

#include "cullide/error.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>

namespace cullide::study {

const char* toString(Cause c) {
    switch (c) {
        case Cause::DepthRounding: return "depth_rounding";
        case Cause::Sampling: return "sampling";
        case Cause::EdgeOn: return "edge_on";
        case Cause::Untested: return "untested";
        case Cause::Unexplained: return "unexplained";
    }
    return "?";
}

namespace {

// A triangle's window-space plane z(x, y) = z0 + a (x - x0) + b (y - y0), through the unsnapped
// window vertices (raster rule 6). valid = false for zero projected area.
struct Plane {
    double x0 = 0, y0 = 0, z0 = 0, a = 0, b = 0;
    bool valid = false;
    double at(double x, double y) const { return z0 + a * (x - x0) + b * (y - y0); }
};

Plane planeOf(const Vec3d w[3]) {
    Plane p;
    const double ux = w[1].x() - w[0].x(), uy = w[1].y() - w[0].y(), uz = w[1].z() - w[0].z();
    const double vx = w[2].x() - w[0].x(), vy = w[2].y() - w[0].y(), vz = w[2].z() - w[0].z();
    const double det = ux * vy - uy * vx;
    if (det == 0 || !std::isfinite(det)) return p;
    p.x0 = w[0].x(), p.y0 = w[0].y(), p.z0 = w[0].z();
    p.a = (uz * vy - uy * vz) / det;
    p.b = (ux * vz - uz * vx) / det;
    p.valid = std::isfinite(p.a) && std::isfinite(p.b);
    return p;
}

// Stored value as a signed integer that orders like the depth (unorm k, or float bits).
int64_t storedOrder(uint32_t v) {
    return int64_t(v);
}

}  // namespace

PairSample samplePair(DepthBackend& backend, const std::array<Vec3f, 3>& t, const std::array<Vec3f, 3>& x,
                      const OrthoView& view) {
    PairSampleScratch scratch;
    return samplePair(backend, t, x, view, scratch);
}

PairSample samplePair(DepthBackend& backend, const std::array<Vec3f, 3>& t, const std::array<Vec3f, 3>& x,
                      const OrthoView& view, PairSampleScratch& scratch) {
    const std::array<Vec3f, 6> positions{t[0], t[1], t[2], x[0], x[1], x[2]};
    const std::array<Triangle, 2> triangles{Triangle{0, 1, 2}, Triangle{3, 4, 5}};
    Vec3d wt[3], wx[3];
    for (int i = 0; i < 3; ++i) wt[i] = view.toWindow(t[size_t(i)]), wx[i] = view.toWindow(x[size_t(i)]);
    // Only the pixels that may hold a fragment of t or x are drawn and read: a tile of the view
    // (the same fragments at its pixels as the whole view's) around both. A covered centre i + 1/2
    // lies in the snapped triangle, whose corners are within half a pixel of the window ones, so
    // within [floor(min) - 1, floor(max)] of them; the box has a pixel more on each side. (The
    // whole view, drawn and read three times per pair, was most of the attribution's time.)
    int x0 = 0, y0 = 0, x1 = view.width - 1, y1 = view.height - 1;
    double lo[2] = {wt[0].x(), wt[0].y()}, hi[2] = {lo[0], lo[1]};
    for (const Vec3d& w : {wt[1], wt[2], wx[0], wx[1], wx[2]})
        for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], w[k]), hi[k] = std::max(hi[k], w[k]);
    if (std::isfinite(lo[0]) && std::isfinite(lo[1]) && std::isfinite(hi[0]) && std::isfinite(hi[1])) {
        const auto clampPixel = [](double v, int limit) { return int(std::clamp(v, -1.0, double(limit))); };
        x0 = clampPixel(std::floor(lo[0]) - 1, view.width - 1), x1 = clampPixel(std::floor(hi[0]) + 1, view.width - 1);
        y0 = clampPixel(std::floor(lo[1]) - 1, view.height - 1),
        y1 = clampPixel(std::floor(hi[1]) + 1, view.height - 1);
        if (x1 < 0 || y1 < 0 || x0 > x1 || y0 > y1) x0 = x1 = y0 = y1 = 0;  // off the view: nothing covered
        x0 = std::max(x0, 0), y0 = std::max(y0, 0);
    }
    backend.setGeometry(positions, triangles);
    backend.setView(view.tile(x0, y0, x1 - x0 + 1, y1 - y0 + 1));
    DepthImage* const img[2] = {&scratch.t, &scratch.x};
    for (uint32_t k = 0; k < 2; ++k) {
        CommandList list;
        list.clear(1.0);
        list.depthMask(true);
        list.depthFunc(DepthFunc::Always);
        list.draw(k, 1);
        backend.execute(list);
        backend.readDepthInto(*img[k]);
    }
    // The cleared value: fitted views keep every fragment of a PCS triangle below it.
    CommandList clearOnly;
    clearOnly.clear(1.0);
    backend.execute(clearOnly);
    backend.readDepthInto(scratch.blank);
    const DepthImage& blank = scratch.blank;
    const uint32_t cleared = blank.values.empty() ? 0 : blank.at(0, 0);

    const Plane pt = planeOf(wt), px = planeOf(wx);
    const double step = view.depth.resolution();

    PairSample s;
    // Inscribed diameter 4 area / perimeter, in pixels, against the pixel diagonal.
    const double pixel = (view.xmax - view.xmin) / view.width;
    auto large = [&](const std::array<Vec3f, 3>& c) {
        const Vec3d a = c[0].cast<double>(), b = c[1].cast<double>(), d = c[2].cast<double>();
        const double area2 = (b - a).cross(d - a).norm();
        const double perimeter = (b - a).norm() + (d - b).norm() + (a - d).norm();
        return perimeter > 0 && 2 * area2 / perimeter >= std::sqrt(2.0) * pixel;
    };
    s.largeT = large(t), s.largeX = large(x);
    s.maxDiffSteps = -std::numeric_limits<double>::infinity();
    for (int yy = 0; yy < img[0]->height; ++yy)
        for (int xx = 0; xx < img[0]->width; ++xx) {
            const uint32_t a = img[0]->at(xx, yy), b = img[1]->at(xx, yy);
            const bool inT = a != cleared, inX = b != cleared;
            s.coveredT += inT;
            s.coveredX += inX;
            if (!(inT && inX)) continue;
            ++s.shared;
            s.maxStoredDiff = std::max(s.maxStoredDiff, storedOrder(a) - storedOrder(b));
            const double cx = (xx + x0) + 0.5, cy = (yy + y0) + 0.5;  // in the view's pixels
            // A plane the rasterizer built from snapped corners (unsnapped ones collinear): use
            // the stored depth instead, within half a step.
            const double za = pt.valid ? pt.at(cx, cy) : img[0]->depth(xx, yy);
            const double zb = px.valid ? px.at(cx, cy) : img[1]->depth(xx, yy);
            s.maxDiffSteps = std::max(s.maxDiffSteps, (za - zb) / step);
        }

    s.reachSteps = std::numeric_limits<double>::quiet_NaN();
    if (pt.valid && px.valid) {
        const P2 tt[3] = {{wt[0].x(), wt[0].y()}, {wt[1].x(), wt[1].y()}, {wt[2].x(), wt[2].y()}};
        const P2 tx[3] = {{wx[0].x(), wx[0].y()}, {wx[1].x(), wx[1].y()}, {wx[2].x(), wx[2].y()}};
        const std::vector<P2> overlap = clipToTriangle({tt[0], tt[1], tt[2]}, tx);
        if (!overlap.empty()) {
            double reach = -std::numeric_limits<double>::infinity();
            for (const P2& p : overlap) reach = std::max(reach, (pt.at(p.x, p.y) - px.at(p.x, p.y)) / step);
            s.reachSteps = reach;
        }
    }
    return s;
}

Cause decide(CullMethod method, const PairSample& s) {
    if (s.coveredT == 0 || s.coveredX == 0)
        return (s.coveredT == 0 && s.largeT) || (s.coveredX == 0 && s.largeX) ? Cause::EdgeOn : Cause::Sampling;
    if (s.shared == 0) return Cause::Sampling;
    const int theta = method == CullMethod::Original ? 0 : 1;
    if (s.maxStoredDiff >= theta) return Cause::Unexplained;
    if (s.maxDiffSteps >= theta + 1e-6) return Cause::Unexplained;
    if (s.maxDiffSteps > theta - 1) return Cause::DepthRounding;
    if (theta == 1 && !(s.reachSteps >= 1)) return Cause::DepthRounding;
    return Cause::Sampling;
}

namespace {

// Order in which causes win when a triangle (or a pair) has several.
int rank(Cause c) {
    switch (c) {
        case Cause::Unexplained: return 0;
        case Cause::EdgeOn: return 1;
        case Cause::Sampling: return 2;
        case Cause::DepthRounding: return 3;
        case Cause::Untested: return 4;
    }
    return 0;
}
Cause worst(Cause a, Cause b) {
    return rank(a) <= rank(b) ? a : b;
}

constexpr uint32_t kNever = std::numeric_limits<uint32_t>::max();

}  // namespace

Attribution attributeFalsePrunes(const Scene& scene, const oracle::Truth& truth, DepthBackend& backend,
                                 const CullideOptions& options) {
    CullideOptions o = options;
    o.recordPrunes = true;
    CullideResult run = runCullide(scene, backend, o);
    return attributeFalsePrunes(scene, truth, backend, options, std::move(run));
}

Attribution attributeFalsePrunes(const Scene& scene, const oracle::Truth& truth, DepthBackend& backend,
                                 const CullideOptions& options, CullideResult run) {
    // The scene as one geometry in (object, triangle) order, as fitView needs it; the order of
    // CullideResult::prunedAtCall too.
    const FlatScene world = flatten(scene);
    const size_t total = world.mesh.triangles.size();
    auto global = [&](uint32_t object, uint32_t triangle) { return world.triangle(object, triangle); };
    CULLIDE_CHECK(run.prunedAtCall.size() == total, "attributeFalsePrunes needs a run with recordPrunes");
    static_assert(CullideResult::kNotPruned == kNever);

    std::vector<char> colliding(total, 0);
    for (const oracle::IntersectingPair& p : truth.pairs)
        colliding[global(p.objectA, p.triangleA)] = colliding[global(p.objectB, p.triangleB)] = 1;
    std::vector<uint32_t> prunedAt(total, kNever);  // of the colliding triangles
    std::set<uint32_t> calls;  // that dropped a colliding triangle
    for (size_t g = 0; g < total; ++g)
        if (colliding[g] && run.prunedAtCall[g] != kNever) calls.insert(prunedAt[g] = run.prunedAtCall[g]);
    // Each such call's view: its own direction and viewport (with chosen directions, not
    // options.directions), fitted to the triangles still in the PCS before it.
    std::map<uint32_t, OrthoView> views;
    std::map<uint32_t, uint32_t> directionOf;
    for (uint32_t c : calls) {
        std::vector<TriangleRange> ranges;
        for (size_t g = 0; g < total; ++g)
            if (run.prunedAtCall[g] >= c) {
                if (!ranges.empty() && ranges.back().first + ranges.back().count == g) ++ranges.back().count;
                else ranges.push_back({uint32_t(g), 1});
            }
        const PassStats& st = run.passes.at(c);
        views[c] = fitView(world.mesh.positions, world.mesh.triangles, ranges, st.dirVector, st.width, st.height,
                           options.depth);
        directionOf[c] = st.direction;
    }
    Attribution a;
    a.result = std::move(run);

    auto corners = [&](uint32_t object, uint32_t triangle) {
        const Mesh& m = world.mesh;
        const Triangle& t = m.triangles[global(object, triangle)];
        return std::array<Vec3f, 3>{m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]};
    };
    std::vector<int8_t> triangleCause(total, -1);
    PairSampleScratch scratch;
    for (const oracle::IntersectingPair& p : truth.pairs) {
        const uint32_t ga = global(p.objectA, p.triangleA), gb = global(p.objectB, p.triangleB);
        const uint32_t c = std::min(prunedAt[ga], prunedAt[gb]);
        if (c == kNever) continue;
        Cause cause = Cause::Untested;
        bool first = true;
        for (int side = 0; side < 2; ++side) {
            const uint32_t g = side == 0 ? ga : gb;
            if (prunedAt[g] != c) continue;
            Cause ci;
            if (options.method == CullMethod::Original && p.selfPair()) {
                ci = Cause::Untested;
            } else {
                const auto t = side == 0 ? corners(p.objectA, p.triangleA) : corners(p.objectB, p.triangleB);
                const auto x = side == 0 ? corners(p.objectB, p.triangleB) : corners(p.objectA, p.triangleA);
                ci = decide(options.method, samplePair(backend, t, x, views.at(c), scratch));
            }
            cause = first ? ci : worst(cause, ci);
            first = false;
        }
        a.missed.push_back({p, cause, c, directionOf.at(c)});
        ++a.pairs[size_t(cause)];
        for (uint32_t g : {ga, gb})
            if (prunedAt[g] != kNever)
                triangleCause[g] = triangleCause[g] < 0 ? int8_t(cause) : int8_t(worst(Cause(triangleCause[g]), cause));
    }
    for (size_t g = 0; g < total; ++g)
        if (triangleCause[g] >= 0) ++a.triangles[size_t(triangleCause[g])];
    return a;
}

}  // namespace cullide::study
