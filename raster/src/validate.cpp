// Per-query intervals [certain, certain + ambiguous] and the comparing tee (cullide/raster/validate.h).
//
// The reference's rules are re-derived here from cullide/raster/rules.h (snapping, fill rule,
// depth plane, storage), for triangles that need no clipping; a triangle that needs clipping is
// treated as ambiguous over its bounding box (Cullide's fitted views never clip). References:
// the dEQP rasterization verifier (FULL / PARTIAL / NONE pixels, floor/ceil snapping of every
// vertex), docs/gl-rules.md#deqp.
#include "cullide/raster/validate.h"

#include "command_state.h"
#include "cullide/error.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>

namespace cullide::raster {

namespace {

struct WinV {
    double x, y, z;
};

// Stored value of a window depth, clamped (rule 7).
uint32_t enc(double z, const DepthFormat& f) {
    return encodeDepth(z, f);
}

// Interval of stored values of a clear depth: exact when representable, else +-1 step.
void clearInterval(double c, const DepthFormat& f, uint32_t& lo, uint32_t& hi) {
    const uint32_t k = enc(c, f);
    bool exact;
    if (f.kind == DepthFormat::Kind::Float32) exact = double(float(c)) == c;
    else exact = double(k) / (std::ldexp(1.0, f.bits) - 1.0) == c;
    lo = hi = k;
    if (!exact) {
        lo = k > 0 ? k - 1 : 0;
        hi = k < 0xFFFFFFFFu ? k + 1 : k;
    }
}

// Whether `incoming FUNC stored` holds for every / for some incoming in [a, b], stored in [s, t].
void intervalTest(DepthFunc f, uint32_t a, uint32_t b, uint32_t s, uint32_t t, bool& all, bool& some) {
    switch (f) {
        case DepthFunc::Never: all = some = false; return;
        case DepthFunc::Always: all = some = true; return;
        case DepthFunc::Less: all = b < s, some = a < t; return;
        case DepthFunc::LEqual: all = b <= s, some = a <= t; return;
        case DepthFunc::Greater: all = a > t, some = b > s; return;
        case DepthFunc::GEqual: all = a >= t, some = b >= s; return;
        case DepthFunc::Equal: all = a == b && s == t && a == s, some = a <= t && s <= b; return;
        case DepthFunc::NotEqual: all = b < s || t < a, some = !(a == b && s == t && a == s); return;
    }
    all = some = false;
}

// The reference's depth plane (rule 6): through the unsnapped double vertices, evaluated as
// (z0 + dzdy*(y - y0)) + dzdx*(x - x0).
struct Plane {
    double x0 = 0, y0 = 0, z0 = 0, dzdx = 0, dzdy = 0;
    bool valid = false;
    double at(double x, double y) const { return (z0 + dzdy * (y - y0)) + dzdx * (x - x0); }
};

Plane planeFrom(const WinV& p0, const WinV& p1, const WinV& p2) {
    Plane p;
    const double x1 = p1.x - p0.x, y1 = p1.y - p0.y, z1 = p1.z - p0.z;
    const double x2 = p2.x - p0.x, y2 = p2.y - p0.y, z2 = p2.z - p0.z;
    const double det = x1 * y2 - x2 * y1;
    if (det == 0.0 || !std::isfinite(det)) return p;
    p.x0 = p0.x, p.y0 = p0.y, p.z0 = p0.z;
    p.dzdx = (z1 * y2 - z2 * y1) / det;
    p.dzdy = (x1 * z2 - x2 * z1) / det;
    p.valid = std::isfinite(p.dzdx) && std::isfinite(p.dzdy);
    return p;
}

}  // namespace

QueryIntervals::QueryIntervals(const IntervalOptions& options) : options_(options) {
    if (options.subpixelBits < kMinSubpixelBits || options.subpixelBits > kMaxSubpixelBits ||
        options.otherSubpixelBits < 1 || !(options.depthLsb >= 0) || !(options.depthFloatUlps >= 0))
        throw InputError("interval options", "subpixel bits or depth margins out of range");
}

void QueryIntervals::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    positions_.assign(positions.begin(), positions.end());
    triangles_.assign(triangles.begin(), triangles.end());
}

void QueryIntervals::setView(const OrthoView& view) {
    view.validate();
    if (!haveView_ || view.width != view_.width || view.height != view_.height || !(view.depth == view_.depth)) {
        const size_t n = size_t(view.width) * size_t(view.height);
        const uint32_t far = enc(1.0, view.depth);
        exactDepth_.assign(n, far);
        lo_.assign(n, far);
        hi_.assign(n, far);
        writer_.assign(n, -1);
        exactTrusted_ = true;
    }
    view_ = view;
    haveView_ = true;
}

std::vector<QueryInterval> QueryIntervals::execute(const CommandList& list, std::vector<uint64_t>* exact,
                                                   bool* exactValid, CoverageCapture* capture) {
    if (!haveView_) throw InputError("command list", "execute() before setView()");
    const uint32_t nq = list.queryCount();
    std::vector<QueryInterval> out(nq);
    std::vector<uint64_t> ex(nq, 0);
    const int W = view_.width, H = view_.height, S = options_.subpixelBits;
    const DepthFormat& fmt = view_.depth;
    const int64_t one = int64_t(1) << S, half = one >> 1;
    const int64_t r = options_.otherSubpixelBits >= S ? 2 : (int64_t(1) << (S - options_.otherSubpixelBits)) + 1;
    const double res = fmt.resolution();
    const double floatUnit = std::ldexp(1.0, -24);
    if (capture) capture->classes.assign(size_t(W) * size_t(H), 0);

    // Window coordinates of every vertex (once per list; the view is fixed within it).
    std::vector<WinV> win(positions_.size());
    for (size_t i = 0; i < positions_.size(); ++i) {
        const Vec3d w = view_.toWindow(positions_[i]);
        win[i] = {w.x(), w.y(), w.z()};
    }
    const double G = guardBandPixels(S);
    auto inside = [&](const WinV& v) { return v.z >= 0 && v.z <= 1 && v.x >= -G && v.x <= G && v.y >= -G && v.y <= G; };

    detail::StateWalker walk(func_, mask_, nq);
    for (const Command& c : list.commands()) {
        if (walk.apply(c)) continue;
        const int64_t query = walk.query();
        switch (c.op) {
            case Command::Op::Clear: {
                uint32_t a, b;
                clearInterval(c.clearDepth, fmt, a, b);
                std::fill(exactDepth_.begin(), exactDepth_.end(), enc(c.clearDepth, fmt));
                std::fill(lo_.begin(), lo_.end(), a);
                std::fill(hi_.begin(), hi_.end(), b);
                std::fill(writer_.begin(), writer_.end(), -1);
                exactTrusted_ = true;
                break;
            }
            case Command::Op::ClearIntervals:
            case Command::Op::DrawConservative:
                throw InputError("command list", "validation covers the GL-like commands only, not conservative ones");
            case Command::Op::Draw:
                if (uint64_t(c.first) + c.count > triangles_.size())
                    throw InputError("command list", "draw range outside the geometry");
                for (uint32_t t = c.first; t < c.first + c.count; ++t) {
                    const Triangle& tri = triangles_[t];
                    const WinV v[3] = {win[tri[0]], win[tri[1]], win[tri[2]]};
                    bool finite = true;
                    for (const WinV& p : v)
                        finite = finite && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
                    if (!finite) continue;
                    // Trivially outside (rule 2): nothing under any snapping either.
                    if ((v[0].x < 0 && v[1].x < 0 && v[2].x < 0) || (v[0].x > W && v[1].x > W && v[2].x > W) ||
                        (v[0].y < 0 && v[1].y < 0 && v[2].y < 0) || (v[0].y > H && v[1].y > H && v[2].y > H) ||
                        (v[0].z < 0 && v[1].z < 0 && v[2].z < 0) || (v[0].z > 1 && v[1].z > 1 && v[2].z > 1))
                        continue;
                    const bool clipped = !(inside(v[0]) && inside(v[1]) && inside(v[2]));
                    if (clipped) exactTrusted_ = false;

                    int64_t sx[3], sy[3];
                    for (int k = 0; k < 3; ++k) sx[k] = snapToFixed(v[k].x, S), sy[k] = snapToFixed(v[k].y, S);
                    const int64_t area2 = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
                    int o[3] = {0, 1, 2};
                    if (area2 < 0) std::swap(o[1], o[2]);
                    // The reference's plane (with its fallback to the snapped vertices when the
                    // double vertices are collinear).
                    Plane plane = planeFrom(v[0], v[1], v[2]);
                    if (!plane.valid && area2 != 0) {
                        const double unit = std::ldexp(1.0, -S);
                        WinV s[3];
                        for (int k = 0; k < 3; ++k)
                            s[k] = {double(sx[o[k]]) * unit, double(sy[o[k]]) * unit, v[o[k]].z};
                        plane = planeFrom(s[0], s[1], s[2]);
                        if (!plane.valid) plane = {s[0].x, s[0].y, s[0].z, 0.0, 0.0, true};
                    }
                    const double zmin = std::min({v[0].z, v[1].z, v[2].z}), zmax = std::max({v[0].z, v[1].z, v[2].z});
                    const double slopeMargin = plane.valid ? options_.depthFloatUlps * floatUnit *
                            (1.0 + (std::abs(plane.dzdx) + std::abs(plane.dzdy)) * double(W + H))
                                                           : 0.0;
                    const double depthMargin = options_.depthLsb * res + slopeMargin;

                    // Pixel range: the snapped bounding box grown by r units and one pixel.
                    const int64_t minx = std::min({sx[0], sx[1], sx[2]}) - r,
                                  maxx = std::max({sx[0], sx[1], sx[2]}) + r;
                    const int64_t miny = std::min({sy[0], sy[1], sy[2]}) - r,
                                  maxy = std::max({sy[0], sy[1], sy[2]}) + r;
                    const int64_t i0 = std::max<int64_t>(((minx - half) >> S), 0),
                                  i1 = std::min<int64_t>(((maxx - half) >> S) + 1, W - 1);
                    const int64_t j0 = std::max<int64_t>(((miny - half) >> S), 0),
                                  j1 = std::min<int64_t>(((maxy - half) >> S) + 1, H - 1);
                    // Edges of the oriented snapped triangle.
                    int64_t ax[3], ay[3], dx[3], dy[3], dl1[3];
                    bool incl[3];
                    for (int k = 0; k < 3; ++k) {
                        const int a = o[k], b = o[(k + 1) % 3];
                        ax[k] = sx[a], ay[k] = sy[a];
                        dx[k] = sx[b] - sx[a], dy[k] = sy[b] - sy[a];
                        dl1[k] = std::abs(dx[k]) + std::abs(dy[k]);
                        incl[k] = isInclusiveEdge(options_.fillRule, dx[k], dy[k]);
                    }
                    for (int64_t j = j0; j <= j1; ++j) {
                        const int64_t py = j * one + half;
                        for (int64_t i = i0; i <= i1; ++i) {
                            const int64_t px = i * one + half;
                            bool certain = !clipped && area2 != 0, posA = true, posB = true, exactCov = area2 != 0;
                            for (int k = 0; k < 3; ++k) {
                                const int64_t e = dx[k] * (py - ay[k]) - dy[k] * (px - ax[k]);
                                const int64_t da = std::abs(px - ax[k]) + std::abs(py - ay[k]);
                                const int64_t db = std::abs(px - ax[k] - dx[k]) + std::abs(py - ay[k] - dy[k]);
                                const int64_t m = r * dl1[k] + 2 * r * std::min(da, db) + 4 * r * r;
                                certain = certain && e > m;
                                posA = posA && e >= -m;
                                posB = posB && e <= m;
                                exactCov = exactCov && (e > 0 || (e == 0 && incl[k]));
                            }
                            bool possible = clipped || posA || posB;
                            if (!possible) continue;
                            const size_t idx = size_t(j) * size_t(W) + size_t(i);
                            const double xc = double(i) + 0.5, yc = double(j) + 0.5;
                            uint32_t a, b, inc = 0;
                            if (plane.valid && !clipped) {
                                const double z = clampDepth(plane.at(xc, yc));
                                inc = enc(z, fmt);
                                a = enc(z - depthMargin, fmt);
                                b = enc(z + depthMargin, fmt);
                            } else {
                                a = enc(zmin - depthMargin, fmt);
                                b = enc(zmax + depthMargin, fmt);
                                exactCov = false;
                            }
                            // The exact track.
                            if (exactCov && depthTest(func_, inc, exactDepth_[idx])) {
                                if (query >= 0) ++ex[size_t(query)];
                                if (mask_) exactDepth_[idx] = inc;
                                if (capture && query == int64_t(capture->query)) capture->classes[idx] |= 4;
                            }
                            bool all, some;
                            if (writer_[idx] == int64_t(t)) {
                                // The stored value was certainly written by this very triangle:
                                // GL's invariance rules (same primitive, same vertex data, only
                                // the depth function or mask changed) make the incoming depth
                                // equal to it, whatever its exact value.
                                all = some = depthTest(func_, lo_[idx], lo_[idx]);
                                a = lo_[idx], b = hi_[idx];
                            } else {
                                intervalTest(func_, a, b, lo_[idx], hi_[idx], all, some);
                            }
                            const bool surely = certain && all, maybe = some;  // `possible` holds here
                            if (query >= 0) {
                                if (surely) ++out[size_t(query)].certain;
                                if (maybe) ++out[size_t(query)].possible;
                                if (capture && query == int64_t(capture->query))
                                    capture->classes[idx] |= uint8_t((surely ? 1 : 0) | (maybe ? 2 : 0));
                            }
                            if (mask_) {
                                if (surely) {
                                    lo_[idx] = a, hi_[idx] = b;
                                    writer_[idx] = int64_t(t);
                                } else if (maybe) {
                                    lo_[idx] = std::min(lo_[idx], a), hi_[idx] = std::max(hi_[idx], b);
                                    writer_[idx] = -1;
                                }
                            }
                        }
                    }
                }
                break;
            default: break;  // state commands: walk.apply
        }
    }
    for (uint32_t q = 0; q < nq; ++q) {
        if (walk.anySamples(q)) {
            out[q].certain = out[q].certain > 0 ? 1 : 0;
            out[q].possible = out[q].possible > 0 ? 1 : 0;
            ex[q] = ex[q] > 0 ? 1 : 0;
        }
    }
    if (exact) *exact = std::move(ex);
    if (exactValid) *exactValid = exactTrusted_;
    return out;
}

// ---------------------------------------------------------------------------------------------
// TeeBackend

TeeBackend::TeeBackend(DepthBackend& reference, DepthBackend& other, const IntervalOptions& options)
    : reference_(reference), other_(other), intervals_(options) {}

std::string TeeBackend::describe() const {
    return "tee: " + reference_.describe() + " | " + other_.describe();
}

void TeeBackend::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    reference_.setGeometry(positions, triangles);
    other_.setGeometry(positions, triangles);
    intervals_.setGeometry(positions, triangles);
}

void TeeBackend::setView(const OrthoView& view) {
    reference_.setView(view);
    other_.setView(view);
    intervals_.setView(view);
    view_ = view;
}

std::vector<uint64_t> TeeBackend::execute(const CommandList& list) {
    std::vector<uint64_t> ref = reference_.execute(list);
    const std::vector<uint64_t> oth = other_.execute(list);
    std::vector<uint64_t> exact;
    bool exactValid = false;
    CoverageCapture capture;
    const int64_t want = onCapture ? onCapture(frame_, list_) : -1;
    capture.query = want >= 0 ? uint32_t(want) : 0;
    const std::vector<QueryInterval> iv = intervals_.execute(list, &exact, &exactValid, want >= 0 ? &capture : nullptr);
    std::vector<QueryKind> kinds;
    for (const Command& c : list.commands())
        if (c.op == Command::Op::BeginQuery) kinds.push_back(c.queryKind);
    for (uint32_t q = 0; q < ref.size(); ++q) {
        QueryComparison cmp;
        cmp.frame = frame_;
        cmp.list = list_;
        cmp.query = q;
        cmp.kind = kinds[q];
        cmp.reference = ref[q];
        cmp.other = oth[q];
        cmp.interval = iv[q];
        if (exactValid) {
            ++selfChecked_;
            if (exact[q] != ref[q]) ++selfCheckMismatches_;
        }
        comparisons_.push_back(cmp);
        if (want == int64_t(q) && captured) captured(cmp, capture, view_);
    }
    ++list_;
    return ref;
}

DepthImage TeeBackend::readDepth() {
    return reference_.readDepth();
}

}  // namespace cullide::raster
