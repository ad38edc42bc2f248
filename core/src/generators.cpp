// The paper's scenes, generated reproducibly.
//
// Based on: "Cullide" (Govindaraju, Redon, Lin, Manocha, Graphics Hardware 2003) for the
// many-deforming-cylinders benchmark, and the self-intersection variant's Section 6 (a deformed
// Stanford bunny with a single self-intersection area; two cows combined into one object). The
// decimation is meshoptimizer's simplifier (Garland-Heckbert quadric edge collapse, with the grid
// clustering "sloppy" simplifier as the fallback).
//
// Determinism: every function here is a pure function of its arguments. Random numbers come from
// std::mt19937_64 (its output sequence is fixed by the standard) through our own conversion to
// double; no std distribution is used (their algorithms are implementation-defined). Arithmetic
// is IEEE float/double + - * / and sqrt in a fixed order, plus std::sin/std::cos: glibc's sin
// and cos are correctly rounded in practice and in any case deterministic on one platform and
// library build, which is the guarantee we give (same inputs, same build: same bits). No threads,
// no unordered containers.
#include "cullide/generators.h"

#include "cullide/error.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>

namespace cullide {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Uniform double in [0, 1): the top 53 bits of one mt19937_64 draw, scaled exactly.
double uniform01(std::mt19937_64& rng) {
    return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
    return lo + (hi - lo) * uniform01(rng);
}

double smoothstep(double x) {
    if (x <= 0.0) return 0.0;
    if (x >= 1.0) return 1.0;
    return x * x * (3.0 - 2.0 * x);
}

Vec3d toD(const Vec3f& p) {
    return Vec3d(double(p.x()), double(p.y()), double(p.z()));
}
Vec3f toF(const Vec3d& p) {
    return Vec3f(float(p.x()), float(p.y()), float(p.z()));
}

Vec3d cross(const Vec3d& a, const Vec3d& b) {
    return Vec3d(a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x());
}
double dot(const Vec3d& a, const Vec3d& b) {
    return (a.x() * b.x() + a.y() * b.y()) + a.z() * b.z();
}
Vec3d normalized(const Vec3d& a) {
    const double n = std::sqrt(dot(a, a));
    return Vec3d(a.x() / n, a.y() / n, a.z() / n);
}

// (R(axis, angle) - I) v by Rodrigues' formula: sin(a) (k x v) + (1 - cos(a)) k x (k x v).
// Written as a displacement so that angle 0 gives exactly zero and p + 0 == p bit for bit: the
// undeformed frames of an animation are then bit-identical to the undeformed mesh.
Vec3d rotationDelta(const Vec3d& axis, double angle, const Vec3d& v) {
    const double s = std::sin(angle);
    const double c1 = 1.0 - std::cos(angle);
    const Vec3d kv = cross(axis, v);
    const Vec3d kkv = cross(axis, kv);
    return Vec3d(s * kv.x() + c1 * kkv.x(), s * kv.y() + c1 * kkv.y(), s * kv.z() + c1 * kkv.z());
}

Vec3f addDelta(const Vec3f& p, const Vec3d& d) {
    return Vec3f(float(double(p.x()) + d.x()), float(double(p.y()) + d.y()), float(double(p.z()) + d.z()));
}

// Animation parameter of frame f of n (0 at the first frame, 1 at the last; 1 for a single frame).
double ramp(size_t f, size_t n) {
    return n > 1 ? double(f) / double(n - 1) : 1.0;
}

// One deforming object: `triangles` with positions shape(1) in the base scene and
// shape(ramp(f, frames)) in frame f.
template <typename Shape>
Animation deformingObject(const std::string& name, const std::vector<Triangle>& triangles, size_t frames,
                          Shape&& shape) {
    Animation a;
    Object o;
    o.name = name;
    o.mesh.triangles = triangles;
    o.mesh.positions = shape(1.0);
    a.scene.objects.push_back(std::move(o));
    for (size_t f = 0; f < frames; ++f) {
        Frame fr;
        fr.poses.resize(1);
        fr.poses[0].positions = shape(ramp(f, frames));
        a.frames.push_back(std::move(fr));
    }
    return a;
}

// The referenced bounds of a source mesh, by whose fractions a generator places its deformation;
// throws InputError(source, ...) when no fractions can be taken of them: no triangles, an extent
// that overflows float, or none at all (every referenced vertex one point), where the placement
// would divide by zero and write NaN.
Bounds sourceBounds(const Mesh& mesh, const std::string& source) {
    if (mesh.triangles.empty()) throw InputError(source, "no triangles; a generated scene needs a surface");
    const Bounds box = referencedBounds(mesh);
    const Vec3f ext = box.extent();
    if (!ext.allFinite()) throw InputError(source, "its extent overflows float; cannot be scaled");
    if (ext == Vec3f::Zero())
        throw InputError(source, "zero extent (all its vertices are one point); cannot be scaled");
    return box;
}

// Keeps referenced vertices only, in their original order; remaps the triangles.
Mesh compact(const std::vector<Vec3f>& positions, const std::vector<unsigned int>& indices) {
    std::vector<uint32_t> remap(positions.size(), UINT32_MAX);
    for (unsigned int v : indices) remap[v] = 0;
    Mesh out;
    for (size_t v = 0; v < positions.size(); ++v) {
        if (remap[v] == UINT32_MAX) continue;
        remap[v] = static_cast<uint32_t>(out.positions.size());
        out.positions.push_back(positions[v]);
    }
    out.triangles.reserve(indices.size() / 3);
    for (size_t i = 0; i + 2 < indices.size(); i += 3)
        out.triangles.push_back({remap[indices[i]], remap[indices[i + 1]], remap[indices[i + 2]]});
    return out;
}

size_t distance(size_t a, size_t b) {
    return a > b ? a - b : b - a;
}

}  // namespace

Mesh subdivide(const Mesh& mesh) {
    const size_t nv = mesh.positions.size();
    Mesh out;
    out.positions = mesh.positions;
    out.triangles.reserve(mesh.triangles.size() * 4);
    // Edge (lo, hi) -> midpoint index, stored with the smaller endpoint: a vertex has few
    // edges, so a linear scan is fast and the numbering depends only on triangle order.
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> edges(nv);
    auto midpoint = [&](uint32_t a, uint32_t b) -> uint32_t {
        const uint32_t lo = std::min(a, b), hi = std::max(a, b);
        for (const auto& e : edges[lo])
            if (e.first == hi) return e.second;
        CULLIDE_CHECK(out.positions.size() < UINT32_MAX, "subdivided mesh exceeds 32-bit indices");
        const uint32_t m = static_cast<uint32_t>(out.positions.size());
        const Vec3f& p = mesh.positions[lo];
        const Vec3f& q = mesh.positions[hi];
        // Same operands in the same order for both triangles of the edge (lo first).
        out.positions.emplace_back((p.x() + q.x()) * 0.5f, (p.y() + q.y()) * 0.5f, (p.z() + q.z()) * 0.5f);
        edges[lo].emplace_back(hi, m);
        return m;
    };
    for (const Triangle& t : mesh.triangles) {
        CULLIDE_CHECK(t[0] < nv && t[1] < nv && t[2] < nv, "subdivide: triangle index out of range");
        const uint32_t ab = midpoint(t[0], t[1]);
        const uint32_t bc = midpoint(t[1], t[2]);
        const uint32_t ca = midpoint(t[2], t[0]);
        // Corners first, centre last; all four keep the parent's orientation.
        out.triangles.push_back({t[0], ab, ca});
        out.triangles.push_back({ab, t[1], bc});
        out.triangles.push_back({ca, bc, t[2]});
        out.triangles.push_back({ab, bc, ca});
    }
    return out;
}

Mesh decimate(const Mesh& mesh, size_t targetTriangles) {
    if (targetTriangles >= mesh.triangles.size()) return mesh;
    std::vector<unsigned int> indices;
    indices.reserve(mesh.triangles.size() * 3);
    for (const Triangle& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());
    const float* xyz = mesh.positions.empty() ? nullptr : mesh.positions[0].data();
    static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be three packed floats");
    const size_t target = targetTriangles * 3;

    // No error bound: we want the count, whatever it costs in appearance.
    const float kAnyError = 1e6f;
    std::vector<unsigned int> simplified(indices.size());
    simplified.resize(meshopt_simplify(simplified.data(), indices.data(), indices.size(), xyz, mesh.positions.size(),
                                       sizeof(Vec3f), target, kAnyError, 0, nullptr));
    // meshopt_simplify stops early where topology forbids collapses (borders, seams, non-manifold
    // fans). Outside 10% of the target, the sloppy (vertex clustering) simplifier also runs on the
    // original and the closer of the two results wins.
    if (simplified.size() > target + target / 10) {
        std::vector<unsigned int> sloppy(indices.size());
        sloppy.resize(meshopt_simplifySloppy(sloppy.data(), indices.data(), indices.size(), xyz, mesh.positions.size(),
                                             sizeof(Vec3f), target, kAnyError, nullptr));
        if (!sloppy.empty() && distance(sloppy.size(), target) < distance(simplified.size(), target))
            simplified.swap(sloppy);
    }
    if (simplified.empty()) return mesh;  // nothing usable (tiny target): keep the input
    return compact(mesh.positions, simplified);
}

Mesh resample(const Mesh& mesh, size_t targetTriangles) {
    CULLIDE_CHECK(targetTriangles > 0, "resample: target must be positive");
    const size_t n = mesh.triangles.size();
    if (n == 0 || targetTriangles == n) return mesh;
    if (targetTriangles < n) return decimate(mesh, targetTriangles);
    // Upsampling decimates first and subdivides last: decimate to target / 4^k, with the smallest
    // k that makes that at most n, then subdivide k times. The other order (subdivide past the
    // target, then decimate) folds the flat patches that subdivision makes: edge collapses among
    // coplanar triangles are free in quadric error and meshoptimizer's flip test does not catch
    // same-facing overlaps (measured: 54 overlapping pairs in the bunny at 50,000 triangles, where
    // this order gives none).
    size_t levels = 0;
    double base = double(targetTriangles);
    while (base > double(n)) {
        base /= 4.0;
        ++levels;
    }
    const size_t baseCount = std::max<size_t>(1, size_t(base + 0.5));
    Mesh m = baseCount < n ? decimate(mesh, baseCount) : mesh;
    for (size_t i = 0; i < levels; ++i) m = subdivide(m);
    return m;
}

// ---- The deformed bunny -------------------------------------------------------------------
//
// The bundled bunny (data/meshes/bunny.off) has Y up, faces -x, and has two ears: the "back" ear
// leans towards +x, its tip near (0.2, 9.6, -1.0) in a box of about [-5, 5] x [0, 9.7] x [-3.7, 3.8];
// the other leans towards -z. We bend the back ear about its root so that its tip turns down and
// plunges into the bunny's back: the ear crosses the back's surface along one closed curve, the
// single self-intersection area; nothing else moves. All parameters are fractions of the input
// bunny's bounding box (before resampling), so the same geometric deformation is applied at every
// triangle count.
namespace {

// The bend turns the ear in the plane of (root -> tip, root -> target) by this angle; the
// target point only fixes that plane. ~90 degrees points the tip at the target.
constexpr double kEarBendDegrees = 100.0;

struct EarBend {
    Vec3d pivot;  // the ear's root
    Vec3d direction;  // unit vector from the root towards the ear tip
    Vec3d axis;  // unit rotation axis
    double angle;  // full bend angle (radians)
    double h0, h1;  // along `direction`: no rotation below h0, full rotation above h1
    double r0, r1;  // distance from the ear's line: full rotation inside r0, none beyond r1
};

EarBend earBendFor(const Bounds& box) {
    const Vec3d lo = toD(box.lo), ext = toD(box.extent());
    auto at = [&](double fx, double fy, double fz) {
        return Vec3d(lo.x() + fx * ext.x(), lo.y() + fy * ext.y(), lo.z() + fz * ext.z());
    };
    const double unit = ext.y() / 9.658;  // the bundled bunny's height
    EarBend b;
    b.pivot = at(0.3087, 0.7769, 0.508);  // about (-1.9, 7.5, 0.1)
    const Vec3d tip = at(0.5208, 0.9943, 0.362);  // about (0.2, 9.6, -1.0)
    const Vec3d target = at(0.5809, 0.5180, 0.574);  // inside the back: about (0.8, 5.0, 0.6)
    const Vec3d d1 = tip - b.pivot, d2 = target - b.pivot;
    b.direction = normalized(d1);
    b.axis = normalized(cross(d1, d2));
    b.angle = kEarBendDegrees * kPi / 180.0;
    // The bend spreads over 2 units of the ear's length (a radius of about 1.1, over twice the ear's
    // thickness), so the inside of the bend does not fold onto itself; 0.2..1.2 did, at some counts.
    b.h0 = 0.0;
    b.h1 = 2.0 * unit;
    b.r0 = 1.3 * unit;
    b.r1 = 2.1 * unit;
    return b;
}

Vec3f bendEar(const EarBend& b, const Vec3f& p, double amount) {
    const Vec3d v = toD(p) - b.pivot;
    const double h = dot(v, b.direction);
    const Vec3d radial = v - h * b.direction;
    const double r = std::sqrt(dot(radial, radial));
    const double w = smoothstep((h - b.h0) / (b.h1 - b.h0)) * (1.0 - smoothstep((r - b.r0) / (b.r1 - b.r0)));
    if (w == 0.0 || amount == 0.0) return p;
    return addDelta(p, rotationDelta(b.axis, amount * w * b.angle, v));
}

}  // namespace

Animation makeDeformedBunny(const Mesh& bunny, const SceneRequest& request, const std::string& source) {
    const Bounds box = sourceBounds(bunny, source);
    // The bend's size is a fraction of the height, its plane spans the height and the width.
    if (box.extent().y() == 0)
        throw InputError(source, "zero extent along y (its height); the ear bend cannot be scaled to it");
    if (box.extent().x() == 0 && box.extent().z() == 0)
        throw InputError(source, "zero extent along x and z (its width); the ear bend cannot be scaled to it");
    const EarBend bend = earBendFor(box);
    const Mesh rest = resample(bunny, request.triangles);

    auto deformed = [&](double amount) {
        std::vector<Vec3f> ps;
        ps.reserve(rest.positions.size());
        for (const Vec3f& p : rest.positions) ps.push_back(bendEar(bend, p, amount));
        return ps;
    };
    return deformingObject("bunny", rest.triangles, request.frames, deformed);
}

// ---- Two cows ----------------------------------------------------------------------------
//
// The second cow is turned 35 degrees about y and shifted by a fraction of the cow's box, so the
// bodies, heads and legs cross in many places. Frames move it along x from fully left of the first
// to fully right of it, clear of it at both ends; the still scene is the middle position.
Animation makeTwoCows(const Mesh& cow, const SceneRequest& request, const std::string& source) {
    (void)sourceBounds(cow, source);
    const Mesh one = resample(cow, std::max<size_t>(1, request.triangles / 2));
    const Bounds box = referencedBounds(one);
    const Vec3d ext = toD(box.extent());
    const Vec3d centre = toD(box.lo) + 0.5 * ext;
    const double angle = 35.0 * kPi / 180.0;
    const double c = std::cos(angle), s = std::sin(angle);
    const Vec3d shift(0.25 * ext.x(), 0.04 * ext.y(), 0.03 * ext.z());
    // Far enough that the first and last frames are clear: the turned cow reaches at most
    // (ext.x + ext.z) / 2 from its centre along x, the first cow ext.x / 2, plus the shift.
    const double sweep = 1.3 * ext.x() + 0.6 * ext.z();

    const uint32_t n = static_cast<uint32_t>(one.positions.size());
    auto positions = [&](double offsetX) {
        std::vector<Vec3f> ps = one.positions;
        ps.reserve(2 * one.positions.size());
        for (const Vec3f& p : one.positions) {
            const Vec3d v = toD(p) - centre;  // rotate about the box centre, about y
            const Vec3d r(c * v.x() + s * v.z(), v.y(), -s * v.x() + c * v.z());
            ps.push_back(toF(Vec3d(centre.x() + r.x() + shift.x() + offsetX, centre.y() + r.y() + shift.y(),
                                   centre.z() + r.z() + shift.z())));
        }
        return ps;
    };
    Animation a;
    Object o;
    o.name = "two_cows";
    o.mesh.positions = positions(0.0);
    o.mesh.triangles = one.triangles;
    o.mesh.triangles.reserve(2 * one.triangles.size());
    for (const Triangle& t : one.triangles) o.mesh.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
    a.scene.objects.push_back(std::move(o));
    for (size_t f = 0; f < request.frames; ++f) {
        Frame fr;
        fr.poses.resize(1);
        fr.poses[0].positions = positions(request.frames > 1 ? (2.0 * ramp(f, request.frames) - 1.0) * sweep : 0.0);
        a.frames.push_back(std::move(fr));
    }
    return a;
}

// ---- Cylinders ---------------------------------------------------------------------------
//
// Open tubes of length 0.6 and radius 0.06 with centres uniform in [-1, 1]^3 and directions
// uniform on the sphere. For thin rods the chance that two cross is about (pi/2) L^2 D / V
// (Onsager's excluded volume): 0.0085 here, so with 100 tubes about half of them touch another
// and most pairs do not. Each tube bows sideways, in its own random direction and amplitude, as
// sin(2 pi f / frames): frame 0 is straight (the still scene).
namespace {

struct Tube {
    Vec3d centre, axis, u, v;  // u, v, axis: orthonormal
    Vec3d bowDir;  // unit, perpendicular to axis
    double bow;  // full bow amplitude (at the middle of the tube)
};

constexpr double kTubeLength = 0.6;
constexpr double kTubeRadius = 0.06;

std::vector<Vec3f> tubePositions(const Tube& t, size_t rings, size_t sides, double bowAmount) {
    std::vector<Vec3f> ps;
    ps.reserve((rings + 1) * sides);
    for (size_t j = 0; j <= rings; ++j) {
        const double s = double(j) / double(rings);  // 0..1 along the tube
        const double x = 2.0 * s - 1.0;
        const double off = bowAmount * t.bow * (1.0 - x * x);
        const Vec3d c = t.centre + ((s - 0.5) * kTubeLength) * t.axis + off * t.bowDir;
        for (size_t k = 0; k < sides; ++k) {
            const double phi = 2.0 * kPi * double(k) / double(sides);
            const double cp = std::cos(phi) * kTubeRadius, sp = std::sin(phi) * kTubeRadius;
            ps.push_back(toF(Vec3d(c.x() + cp * t.u.x() + sp * t.v.x(), c.y() + cp * t.u.y() + sp * t.v.y(),
                                   c.z() + cp * t.u.z() + sp * t.v.z())));
        }
    }
    return ps;
}

}  // namespace

Animation makeCylinders(size_t count, const SceneRequest& request) {
    CULLIDE_CHECK(count > 0, "makeCylinders: count must be positive");
    // 2 * sides * rings triangles per tube, sides >= 3, rings >= 1, rings about sides.
    const double per = double(request.triangles) / double(count);
    const size_t sides = std::max<size_t>(3, size_t(std::sqrt(per * 0.5) + 0.5));
    const size_t rings = std::max<size_t>(1, size_t(per / (2.0 * double(sides)) + 0.5));

    std::vector<Triangle> tris;
    for (size_t j = 0; j < rings; ++j)
        for (size_t k = 0; k < sides; ++k) {
            const uint32_t a = uint32_t(j * sides + k), b = uint32_t(j * sides + (k + 1) % sides);
            const uint32_t c = uint32_t(a + sides), d = uint32_t(b + sides);
            tris.push_back({a, b, d});
            tris.push_back({a, d, c});
        }

    std::mt19937_64 rng(request.seed);
    std::vector<Tube> tubes(count);
    for (Tube& t : tubes) {
        // Draws in a fixed order: centre x, y, z; direction z, azimuth; bow angle, bow size.
        const double cx = uniform(rng, -1.0, 1.0), cy = uniform(rng, -1.0, 1.0), cz = uniform(rng, -1.0, 1.0);
        t.centre = Vec3d(cx, cy, cz);
        const double z = uniform(rng, -1.0, 1.0), az = uniform(rng, 0.0, 2.0 * kPi);
        const double rxy = std::sqrt(std::max(0.0, 1.0 - z * z));
        t.axis = Vec3d(rxy * std::cos(az), rxy * std::sin(az), z);
        // Any unit vector not parallel to the axis gives the frame.
        const Vec3d helper = std::abs(t.axis.x()) < 0.6 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
        t.u = normalized(cross(t.axis, helper));
        t.v = cross(t.axis, t.u);
        const double bowAngle = uniform(rng, 0.0, 2.0 * kPi);
        const double cb = std::cos(bowAngle), sb = std::sin(bowAngle);
        t.bowDir = Vec3d(cb * t.u.x() + sb * t.v.x(), cb * t.u.y() + sb * t.v.y(), cb * t.u.z() + sb * t.v.z());
        t.bow = uniform(rng, 0.1, 0.3) * kTubeLength;
    }

    Animation a;
    for (size_t i = 0; i < count; ++i) {
        Object o;
        char name[32];
        std::snprintf(name, sizeof name, "cyl_%03zu", i);
        o.name = name;
        o.mesh.triangles = tris;
        o.mesh.positions = tubePositions(tubes[i], rings, sides, 0.0);
        a.scene.objects.push_back(std::move(o));
    }
    for (size_t f = 0; f < request.frames; ++f) {
        const double amount = std::sin(2.0 * kPi * double(f) / double(request.frames));
        Frame fr;
        fr.poses.resize(count);
        for (size_t i = 0; i < count; ++i) fr.poses[i].positions = tubePositions(tubes[i], rings, sides, amount);
        a.frames.push_back(std::move(fr));
    }
    return a;
}

// ---- Sheets -------------------------------------------------------------------------------
Animation makeSheets(size_t count, double tiltDegrees, const SceneRequest& request) {
    CULLIDE_CHECK(count > 0, "makeSheets: count must be positive");
    CULLIDE_CHECK(tiltDegrees >= 0 && tiltDegrees < 60, "makeSheets: tilt must be in [0, 60) degrees");
    // cells x cells squares of two triangles each.
    const size_t cells = std::max<size_t>(1, size_t(std::sqrt(double(request.triangles) / double(count) * 0.5) + 0.5));
    std::vector<Triangle> tris;
    for (size_t j = 0; j < cells; ++j)
        for (size_t k = 0; k < cells; ++k) {
            const uint32_t a = uint32_t(j * (cells + 1) + k), b = a + 1, c = uint32_t(a + cells + 1), d = c + 1;
            tris.push_back({a, b, d});
            tris.push_back({a, d, c});
        }
    std::mt19937_64 rng(request.seed);
    // Stack slots along z, in a seeded order (a Fisher-Yates shuffle with our own draws).
    std::vector<size_t> slot(count);
    for (size_t i = 0; i < count; ++i) slot[i] = i;
    for (size_t i = count; i-- > 1;) std::swap(slot[i], slot[size_t(uniform01(rng) * double(i + 1))]);
    Animation a;
    for (size_t i = 0; i < count; ++i) {
        // Draws in a fixed order: tilt factor, azimuth, turn about the normal, centre x, y.
        const double theta = tiltDegrees * uniform(rng, 0.5, 1.5) * kPi / 180.0;
        const double phi = uniform(rng, 0.0, 2.0 * kPi), turn = uniform(rng, 0.0, 2.0 * kPi);
        const double cx = uniform(rng, -0.15, 0.15), cy = uniform(rng, -0.15, 0.15);
        const double cz = count > 1 ? -0.08 + 0.16 * double(slot[i]) / double(count - 1) : 0.0;
        const Vec3d n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        // An in-plane frame: any unit vector perpendicular to n, turned by `turn` about n.
        const Vec3d u0 = normalized(cross(Vec3d(0, 1, 0), n)), v0 = cross(n, u0);
        const Vec3d u = std::cos(turn) * u0 + std::sin(turn) * v0, v = cross(n, u);
        Object o;
        char name[32];
        std::snprintf(name, sizeof name, "sheet_%03zu", i);
        o.name = name;
        o.mesh.triangles = tris;
        for (size_t j = 0; j <= cells; ++j)
            for (size_t k = 0; k <= cells; ++k) {
                const double s = double(k) / double(cells) - 0.5, t = double(j) / double(cells) - 0.5;
                o.mesh.positions.push_back(
                    toF(Vec3d(cx + s * u.x() + t * v.x(), cy + s * u.y() + t * v.y(), cz + s * u.z() + t * v.z())));
            }
        a.scene.objects.push_back(std::move(o));
    }
    return a;
}

// ---- Twist -------------------------------------------------------------------------------
//
// About the longest axis of the referenced bounding box, through the box centre; the angle grows
// linearly along that axis from -total/2 at one end to +total/2 at the other, and total grows from
// 0 (frame 0: the mesh unchanged, bit for bit) to 90 degrees (last frame, and the still scene).
Animation makeTwistAnimation(const Mesh& base, const SceneRequest& request, const std::string& source) {
    const Bounds box = sourceBounds(base, source);
    const Vec3d ext = toD(box.extent());
    int ax = 0;
    if (ext.y() > ext[ax]) ax = 1;
    if (ext.z() > ext[ax]) ax = 2;
    const Vec3d centre = toD(box.lo) + 0.5 * ext;
    Vec3d axis = Vec3d::Zero();
    axis[ax] = 1.0;
    const double total = 0.5 * kPi;

    auto twisted = [&](double amount) {
        std::vector<Vec3f> ps;
        ps.reserve(base.positions.size());
        for (const Vec3f& p : base.positions) {
            if (amount == 0.0) {
                ps.push_back(p);
                continue;
            }
            const Vec3d v = toD(p) - centre;
            const double along = ext[ax] > 0.0 ? v[ax] / ext[ax] : 0.0;  // -0.5..0.5
            ps.push_back(addDelta(p, rotationDelta(axis, amount * total * along, v)));
        }
        return ps;
    };
    return deformingObject("twist", base.triangles, request.frames, twisted);
}

}  // namespace cullide
