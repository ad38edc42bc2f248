// The reference's rules re-derived for the interval evaluator (cullide/raster/validate.h) from
// cullide/raster/rules.h: stored depth values, the intervals of a clear, the depth test over
// intervals, and the depth plane. Private to the verification harness.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/raster/rules.h"

#include <cmath>
#include <cstdint>

namespace cullide::raster::intervals {

struct WinV {
    double x, y, z;
};

// Stored value of a window depth, clamped (rule 7).
inline uint32_t enc(double z, const DepthFormat& f) {
    return encodeDepth(z, f);
}

// Interval of stored values of a clear depth: exact when representable, else +-1 step.
inline void clearInterval(double c, const DepthFormat& f, uint32_t& lo, uint32_t& hi) {
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
inline void intervalTest(DepthFunc f, uint32_t a, uint32_t b, uint32_t s, uint32_t t, bool& all, bool& some) {
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

inline Plane planeFrom(const WinV& p0, const WinV& p1, const WinV& p2) {
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

}  // namespace cullide::raster::intervals
