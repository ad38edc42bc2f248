// The N-body scene (nbody.h): rigid bodies in a box, moving in closed form.
//
// Bodies. Each source mesh that some body uses is resampled once to the per-body triangle count,
// reduced to its referenced vertices, centred at its bounding-box centre and scaled to a bounding
// radius of 1 about that centre (in double, rounded to float once): box, sizes and speeds are then
// in units of their own, whatever the mesh's. Body i is its source's mesh at scale r0 * f_i (f_i
// seeded in [0.6, 1.4]); r0 makes the bodies' bounding spheres fill kVolumeFraction of the box.
// For equal spheres placed at random at volume fraction phi a body's sphere overlaps about 8 phi
// others, so at 0.4 most bodies overlap a few others in every frame and many surfaces cross or
// nearly touch (the defaults, bunny and cow: 35 to 68 pairs of bodies crossing per frame; 0.3
// gives about two thirds of that, 0.5 a third more).
//
// Motion, per body (no time stepping, no response between bodies):
//   - the centre moves at a constant velocity and bounces off the walls: per axis, a reflected
//     "triangle wave" within the box shrunk by the body's bounding radius (plus a margin that
//     covers float rounding), so every vertex stays inside the box at every time;
//   - the orientation turns at a constant angular velocity w: R(t) = AngleAxis(|w| t, w/|w|) R0.
// Frame f of F is time f T / (F - 1) (T = kDuration); its pose is one float Transform per body,
// (R(t) * scale) and the centre, computed in double and rounded to float once.
//
// Determinism: std::mt19937_64 through our own conversion to double, all draws made up front in
// a fixed order; IEEE arithmetic plus sqrt, cbrt, fmod, sin, cos (deterministic on one platform
// and library build); one thread, no unordered containers.
#include "cullide/nbody.h"

#include "cullide/error.h"
#include "cullide/generators.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace cullide {
namespace {

constexpr double kPi = 3.14159265358979323846;

constexpr double kVolumeFraction = 0.4;  // of the box, filled by the bodies' bounding spheres
constexpr double kMaxRadius = 0.75;  // of the box's half-size: a lone body still has room to move
constexpr double kMinFactor = 0.6, kMaxFactor = 1.4;  // a body's scale, as a factor of r0
constexpr double kDuration = 1.0;  // T: the motion's time span, whatever the frame count
constexpr double kMinSpeed = 1.0, kMaxSpeed = 2.0;  // of the centre, box half-sizes per T
constexpr double kMinSpin = 0.5 * kPi, kMaxSpin = 1.5 * kPi;  // radians per T
// Room left between a body's bounding sphere and the walls, for the float rounding of its pose
// and of applyTransform (a few ulps of coordinates of magnitude <= 1: below 1e-6).
constexpr double kWallMargin = 1e-5;

// Uniform double in [0, 1): the top 53 bits of one mt19937_64 draw, scaled exactly.
double uniform01(std::mt19937_64& rng) {
    return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
    return lo + (hi - lo) * uniform01(rng);
}

// A direction uniform on the unit sphere (two draws: z, then the azimuth).
Eigen::Vector3d unitVector(std::mt19937_64& rng) {
    const double z = uniform(rng, -1.0, 1.0), az = uniform(rng, 0.0, 2.0 * kPi);
    const double rxy = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {rxy * std::cos(az), rxy * std::sin(az), z};
}

// A rotation uniform over SO(3) (three draws; Shoemake's unit quaternion).
Eigen::Matrix3d randomRotation(std::mt19937_64& rng) {
    const double u1 = uniform01(rng), u2 = uniform01(rng), u3 = uniform01(rng);
    const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
    const Eigen::Quaterniond q(b * std::cos(2.0 * kPi * u3), a * std::sin(2.0 * kPi * u2),
                               a * std::cos(2.0 * kPi * u2), b * std::sin(2.0 * kPi * u3));
    return q.toRotationMatrix();
}

// What the seed decides for one body, drawn in this order.
struct Body {
    size_t source = 0;  // index into the source meshes
    double factor = 1;  // scale, as a factor of r0
    Eigen::Matrix3d rotation0;  // orientation at time 0
    Eigen::Vector3d start;  // the centre at time 0, per axis a fraction of its range, in [0, 1)
    Eigen::Vector3d velocity;  // box half-sizes per T
    Eigen::Vector3d spinAxis;  // unit
    double spin = 0;  // radians per T
    // Set once the sizes are known:
    double scale = 1;  // model space to world space
    double reach = 0;  // the centre stays within [-reach, reach] on every axis
};

Body drawBody(std::mt19937_64& rng, size_t sources) {
    Body b;
    b.source = std::min(sources - 1, size_t(uniform01(rng) * double(sources)));
    b.factor = uniform(rng, kMinFactor, kMaxFactor);
    b.rotation0 = randomRotation(rng);
    for (int k = 0; k < 3; ++k) b.start[k] = uniform01(rng);
    const Eigen::Vector3d direction = unitVector(rng);
    b.velocity = uniform(rng, kMinSpeed, kMaxSpeed) * direction;
    b.spinAxis = unitVector(rng);
    b.spin = uniform(rng, kMinSpin, kMaxSpin);
    return b;
}

void checkRequest(const NBodyRequest& r) {
    auto refuse = [](const std::string& cause) { throw InputError("nbody", cause); };
    if (r.count == 0 || r.count > kMaxNBodyCount)
        refuse("count " + std::to_string(r.count) + " is out of range (1 to " + std::to_string(kMaxNBodyCount) + ")");
    if (r.triangles > kMaxNBodyTriangles)
        refuse("triangles " + std::to_string(r.triangles) + " is over the limit (" +
               std::to_string(kMaxNBodyTriangles) + ")");
    if (r.triangles < kMinNBodyTrianglesPerBody * r.count)
        refuse("triangles " + std::to_string(r.triangles) + " is too few for count " + std::to_string(r.count) +
               " (at least " + std::to_string(kMinNBodyTrianglesPerBody) + " per body: " +
               std::to_string(kMinNBodyTrianglesPerBody * r.count) + ")");
    if (r.frames == 0 || r.frames > kMaxNBodyFrames)
        refuse("frames " + std::to_string(r.frames) + " is out of range (1 to " + std::to_string(kMaxNBodyFrames) +
               ")");
}

// Throws InputError(source, ...) unless `mesh` can be resampled and scaled: valid (validateMesh),
// and its referenced vertices not all one point.
void checkSource(const Mesh& mesh, const std::string& source) {
    validateMesh(mesh, source);
    const Vec3f& first = mesh.positions[mesh.triangles[0][0]];
    for (const Triangle& t : mesh.triangles)
        for (uint32_t v : t)
            if (mesh.positions[v] != first) return;
    throw InputError(source, "zero extent (all its vertices are one point); cannot be scaled");
}

// `mesh` resampled to about `triangles`, its referenced vertices only (in their order), centred at
// their bounding-box centre and scaled to a bounding radius of 1 about it.
Mesh unitBody(const Mesh& source, size_t triangles, const std::string& sourceName) {
    const Mesh m = resample(source, triangles);
    // Decimation cannot always reach a tiny target (it keeps the input then), and subdividing a
    // mesh of very few triangles overshoots by up to 4x: beyond that, refuse rather than give the
    // bodies far more triangles than asked for.
    if (m.triangleCount() > 4 * triangles)
        throw InputError(sourceName, "cannot be resampled to about " + std::to_string(triangles) +
                                         " triangles per body (got " + std::to_string(m.triangleCount()) +
                                         "); ask for more triangles");
    std::vector<uint32_t> remap(m.positions.size(), UINT32_MAX);
    for (const Triangle& t : m.triangles)
        for (uint32_t v : t) remap[v] = 0;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = Eigen::Vector3d::Constant(-INFINITY);
    Mesh out;
    for (size_t v = 0; v < m.positions.size(); ++v) {
        if (remap[v] == UINT32_MAX) continue;
        remap[v] = uint32_t(out.positions.size());
        out.positions.push_back(m.positions[v]);
        const Eigen::Vector3d p = m.positions[v].cast<double>();
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    for (const Triangle& t : m.triangles) out.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
    // In double: the extent of finite floats cannot overflow there.
    const Eigen::Vector3d centre = 0.5 * lo + 0.5 * hi;
    double radius = 0;
    for (const Vec3f& p : out.positions) radius = std::max(radius, (p.cast<double>() - centre).norm());
    if (!(radius > 0))  // resampling collapsed the mesh to one point
        throw InputError(sourceName, "zero extent after resampling to " + std::to_string(triangles) + " triangles");
    for (Vec3f& p : out.positions) p = ((p.cast<double>() - centre) / radius).cast<float>();
    return out;
}

// The largest distance of a vertex from the model origin (about 1 after unitBody's rounding).
double modelRadius(const Mesh& mesh) {
    double r = 0;
    for (const Vec3f& p : mesh.positions) r = std::max(r, p.cast<double>().norm());
    return r;
}

// Sets each body's scale (r0 f_i, r0 from the volume fraction, capped by kMaxRadius) and the
// reach of its centre.
void sizeBodies(std::vector<Body>& bodies, const std::vector<double>& sourceRadius) {
    const double h = double(kNBodyHalfSize);
    double sphereVolume = 0, largest = 0;  // at r0 = 1
    for (const Body& b : bodies) {
        const double r = b.factor * sourceRadius[b.source];
        sphereVolume += 4.0 / 3.0 * kPi * r * r * r;
        largest = std::max(largest, r);
    }
    const double boxVolume = 8.0 * h * h * h;
    const double r0 = std::min(std::cbrt(kVolumeFraction * boxVolume / sphereVolume), kMaxRadius * h / largest);
    for (Body& b : bodies) {
        b.scale = r0 * b.factor;
        b.reach = h - b.scale * sourceRadius[b.source] - kWallMargin;
    }
}

// The coordinate at time t of a point that starts at `start` (a fraction of [-reach, reach]) and
// moves at `velocity`, reflected off -reach and +reach: a triangle wave, in [-reach, reach].
double bounce(double start, double velocity, double t, double reach) {
    const double width = 2.0 * reach, period = 2.0 * width;
    double u = std::fmod(start * width + velocity * t, period);
    if (u < 0) u += period;
    const double x = u <= width ? u : period - u;
    return std::clamp(x - reach, -reach, reach);
}

Transform poseAt(const Body& b, double t) {
    const Eigen::Matrix3d r = Eigen::AngleAxisd(b.spin * t, b.spinAxis).toRotationMatrix() * b.rotation0;
    Transform x = Transform::Identity();
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) x.linear()(i, j) = float(r(i, j) * b.scale);
        x.translation()[i] = float(bounce(b.start[i], b.velocity[i], t, b.reach));
    }
    return x;
}

}  // namespace

Animation makeNBody(std::span<const Mesh> meshes, const NBodyRequest& request, const std::string& source) {
    checkRequest(request);
    if (meshes.empty()) throw InputError(source, "no source meshes for the bodies");
    for (const Mesh& m : meshes) checkSource(m, source);

    std::mt19937_64 rng(request.seed);
    std::vector<Body> bodies;
    bodies.reserve(request.count);
    for (size_t i = 0; i < request.count; ++i) bodies.push_back(drawBody(rng, meshes.size()));

    // One resampled mesh per source that a body uses.
    const size_t perBody = (request.triangles + request.count / 2) / request.count;
    std::vector<Mesh> units(meshes.size());
    std::vector<double> radius(meshes.size(), 1.0);
    for (const Body& b : bodies) {
        if (!units[b.source].empty()) continue;
        units[b.source] = unitBody(meshes[b.source], perBody, source);
        radius[b.source] = modelRadius(units[b.source]);
    }
    sizeBodies(bodies, radius);

    Animation a;
    a.frames.resize(request.frames);
    for (size_t f = 0; f < request.frames; ++f) {
        const double t = request.frames > 1 ? kDuration * double(f) / double(request.frames - 1) : 0.0;
        a.frames[f].poses.resize(request.count);
        for (size_t i = 0; i < request.count; ++i) a.frames[f].poses[i].transform = poseAt(bodies[i], t);
    }
    a.scene.objects.resize(request.count);
    for (size_t i = 0; i < request.count; ++i) {
        Object& o = a.scene.objects[i];
        char name[32];
        std::snprintf(name, sizeof name, "body_%03zu", i);
        o.name = name;
        o.mesh = units[bodies[i].source];
        o.transform = *a.frames[0].poses[i].transform;
    }
    return a;
}

}  // namespace cullide
