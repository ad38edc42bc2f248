// Stability sweeps over small controlled scenes and jittered paper scenes (probes.h).
#include "cullide/study/probes.h"

#include "cullide/study/causes.h"
#include "cullide/study/measures.h"
#include "cullide/study/study.h"

#include "cullide/options.h"
#include "cullide/raster/cpu_backend.h"

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>

namespace cullide::study {
namespace {

// Uniform in [0, 1) from 53 random bits (std's distributions are implementation-defined).
struct Rng {
    std::mt19937_64 gen;
    explicit Rng(uint64_t seed) : gen(seed) {}
    double uniform() { return double(gen() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
};

Object makeObject(const std::string& name, std::vector<Vec3f> positions, std::vector<Triangle> triangles) {
    Object o;
    o.name = name;
    o.mesh.positions = std::move(positions);
    o.mesh.triangles = std::move(triangles);
    return o;
}

// The anchor (probes.h): its projection along +z is the segment y = y0, x in [-x0, x0].
Object anchor(double x0, double y0) {
    return makeObject(
        "anchor",
        {Vec3f(float(-x0), float(y0), -1.f), Vec3f(float(x0), float(y0), 1.f), Vec3f(float(-x0), float(y0), 1.f)},
        {{0, 1, 2}});
}

// The view runCullide fits for its first call in direction `dir` (every triangle of the scene).
OrthoView firstView(const Scene& scene, const Vec3d& dir, const CullideOptions& o) {
    const FlatScene flat = flatten(scene);
    const TriangleRange all{0, uint32_t(flat.mesh.triangles.size())};
    return fitView(flat.mesh.positions, flat.mesh.triangles, std::span(&all, 1), dir, o.width, o.height, o.depth);
}

struct Trial {
    bool detected = false;
    size_t pcs = 0, pairs = 0, falsePrunes = 0;
    std::array<size_t, kCauseCount> causes{};
};

Trial evaluate(const Scene& scene, const CullideOptions& o, DepthBackend& backend) {
    const oracle::Truth truth = oracle::findIntersections(scene);
    const Attribution a = attributeFalsePrunes(scene, truth, backend, o);
    const PcsReport rep = measurePcs(scene, truth, a.result.pcs, o);
    Trial t;
    t.pcs = a.result.pcs.size();
    t.pairs = truth.pairs.size();
    t.falsePrunes = rep.falsePruneCount();
    t.detected = t.falsePrunes == 0;
    t.causes = a.triangles;
    return t;
}

void putTrial(nlohmann::ordered_json& row, const Trial& t) {
    row["detected"] = t.detected ? 1 : 0;
    row["pcs"] = t.pcs;
    row["oracle_pairs"] = t.pairs;
    row["false_prunes"] = t.falsePrunes;
    for (int k = 0; k < kCauseCount; ++k) row[std::string("fp_") + toString(Cause(k))] = t.causes[size_t(k)];
}

// The sweeps' values come from `cullide study`'s options (--methods, --depths, --resolution,
// --directions).
CullideOptions probeOptions(const std::string& method, const std::string& depth, int resolution,
                            const std::string& directions) {
    OptionText t;
    t.method = method, t.depth = depth, t.resolution = std::to_string(resolution), t.directions = directions;
    OptionNames names;
    names.method = "option --methods", names.depth = "option --depths";
    return parseCullideOptions(t, names);
}

Vec3f rotZ(const Vec3d& p, double psi, const Vec3d& offset) {
    const double c = std::cos(psi), s = std::sin(psi);
    return Vec3f(float(c * p.x() - s * p.y() + offset.x()), float(s * p.x() + c * p.y() + offset.y()),
                 float(p.z() + offset.z()));
}

}  // namespace

std::vector<nlohmann::ordered_json> penetrationSweep(const ProbeOptions& po, const std::vector<double>& factors) {
    std::vector<nlohmann::ordered_json> rows;
    auto backend = raster::makeCpuBackend();
    for (const std::string& method : po.methods)
        for (const std::string& depth : po.depths) {
            Rng rng(po.seed);
            const CullideOptions o = probeOptions(method, depth, po.resolution, "z");
            Scene frame;
            frame.objects.push_back(anchor(0.95, -0.95));
            const OrthoView v0 = firstView(frame, Vec3d(0, 0, 1), o);
            const double range = v0.zfar - v0.znear;
            const double step = range * o.depth.resolution();
            const double paperUnit =
                o.depth.kind == DepthFormat::Kind::Unorm ? range * std::ldexp(1.0, -o.depth.bits) : step;
            for (double f : factors)
                for (int trial = 0; trial < po.trials; ++trial) {
                    const double delta = f * paperUnit;
                    const double phase = rng.uniform() * step;  // A's depth within a step
                    const double psi = rng.uniform(0, 2 * std::numbers::pi);
                    const Vec3d off(rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), phase);
                    Scene s;
                    s.objects.push_back(makeObject("a",
                                                   {rotZ({-0.6, -0.6, 0}, psi, off), rotZ({0.6, -0.6, 0}, psi, off),
                                                    rotZ({0.6, 0.6, 0}, psi, off), rotZ({-0.6, 0.6, 0}, psi, off)},
                                                   {{0, 1, 2}, {0, 2, 3}}));
                    // B: its lower edge delta behind A, rising 4 steps in front of A at its apex.
                    s.objects.push_back(
                        makeObject("b",
                                   {rotZ({-0.5, -0.5, delta}, psi, off), rotZ({0.5, -0.5, delta}, psi, off),
                                    rotZ({0.05, 0.55, -4 * step}, psi, off)},
                                   {{0, 1, 2}}));
                    s.objects.push_back(anchor(0.95, -0.95));
                    const Trial t = evaluate(s, o, *backend);
                    // The deepest penetration of B behind A that the samples can see.
                    const OrthoView view = firstView(s, Vec3d(0, 0, 1), o);
                    const Mesh a = s.worldMesh(0), b = s.worldMesh(1);
                    const std::array<Vec3f, 3> tb{b.positions[0], b.positions[1], b.positions[2]};
                    double sampled = -std::numeric_limits<double>::infinity();
                    PairSampleScratch scratch;
                    for (const Triangle& ta : a.triangles) {
                        const PairSample ps = samplePair(
                            *backend, tb, {a.positions[ta[0]], a.positions[ta[1]], a.positions[ta[2]]}, view, scratch);
                        if (ps.shared) sampled = std::max(sampled, ps.maxDiffSteps);
                    }
                    nlohmann::ordered_json row;
                    row["sweep"] = "penetration";
                    row["method"] = method;
                    row["depth"] = o.depth.name();
                    row["resolution"] = po.resolution;
                    row["factor"] = f;
                    row["trial"] = trial;
                    row["delta_steps"] = delta / step;
                    row["sampled_steps"] =
                        std::isfinite(sampled) ? nlohmann::ordered_json(sampled) : nlohmann::ordered_json();
                    putTrial(row, t);
                    rows.push_back(row);
                }
        }
    return rows;
}

std::vector<nlohmann::ordered_json> tiltSweep(const ProbeOptions& po, const std::vector<double>& angles,
                                              const std::vector<std::string>& directionSets) {
    std::vector<nlohmann::ordered_json> rows;
    auto backend = raster::makeCpuBackend();
    const double deg = std::numbers::pi / 180;
    for (const std::string& method : po.methods)
        for (const std::string& dirs : directionSets) {
            Rng rng(po.seed);
            const CullideOptions o = probeOptions(method, "24", po.resolution, dirs);
            for (double angle : angles)
                for (int trial = 0; trial < po.trials; ++trial) {
                    const double th = angle * deg, tha = th - 60 * deg;
                    // In-plane directions across the common line (world y): B's and A's.
                    const Vec3d tb(std::cos(th), 0, -std::sin(th)), ta(std::cos(tha), 0, -std::sin(tha)), y(0, 1, 0);
                    const double psi = rng.uniform(0, 2 * std::numbers::pi);
                    const Vec3d off(rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05));
                    auto at = [&](const Vec3d& across, double along, double t) {
                        return rotZ(along * y + t * across, psi, off);
                    };
                    Scene s;
                    s.objects.push_back(
                        makeObject("a", {at(ta, -0.45, -0.4), at(ta, 0.55, -0.4), at(ta, 0.05, 0.6)}, {{0, 1, 2}}));
                    s.objects.push_back(
                        makeObject("b", {at(tb, -0.5, -0.4), at(tb, 0.5, -0.4), at(tb, 0.0, 0.6)}, {{0, 1, 2}}));
                    const Trial t = evaluate(s, o, *backend);
                    nlohmann::ordered_json row;
                    row["sweep"] = "tilt";
                    row["method"] = method;
                    row["directions"] = dirs;
                    row["resolution"] = po.resolution;
                    row["angle"] = angle;
                    row["trial"] = trial;
                    putTrial(row, t);
                    rows.push_back(row);
                }
        }
    return rows;
}

std::vector<nlohmann::ordered_json> overlapSweep(const ProbeOptions& po, const std::vector<double>& sizes) {
    std::vector<nlohmann::ordered_json> rows;
    auto backend = raster::makeCpuBackend();
    for (const std::string& method : po.methods)
        for (const std::string& depth : po.depths) {
            Rng rng(po.seed);
            const CullideOptions o = probeOptions(method, depth, po.resolution, "z");
            Scene base;
            base.objects.push_back(
                makeObject("a", {{-0.6f, -0.6f, 0.f}, {0.6f, -0.6f, 0.f}, {0.6f, 0.6f, 0.f}, {-0.6f, 0.6f, 0.f}},
                           {{0, 1, 2}, {0, 2, 3}}));
            base.objects.push_back(anchor(0.6, -0.7));
            const OrthoView v0 = firstView(base, Vec3d(0, 0, 1), o);
            const double pixel = (v0.xmax - v0.xmin) / o.width;
            for (double size : sizes)
                for (int trial = 0; trial < po.trials; ++trial) {
                    const double r = 0.5 * size * pixel * std::numbers::sqrt2, big = 2 * r;  // in- and circumradius
                    const double cx = rng.uniform(-0.3, 0.3), cy = rng.uniform(-0.3, 0.3),
                                 alpha = rng.uniform(0, 2 * std::numbers::pi);
                    std::vector<Vec3f> bp;
                    for (int k = 0; k < 3; ++k) {
                        const double a = alpha + 2 * std::numbers::pi * k / 3;
                        bp.push_back(Vec3f(float(cx + big * std::cos(a)), float(cy + big * std::sin(a)),
                                           k == 0 ? 0.05f : -0.05f));
                    }
                    Scene s = base;
                    s.objects.push_back(makeObject("b", bp, {{0, 1, 2}}));
                    const Trial t = evaluate(s, o, *backend);
                    nlohmann::ordered_json row;
                    row["sweep"] = "overlap";
                    row["method"] = method;
                    row["depth"] = o.depth.name();
                    row["resolution"] = po.resolution;
                    row["size"] = size;
                    row["trial"] = trial;
                    putTrial(row, t);
                    rows.push_back(row);
                }
        }
    return rows;
}

std::vector<nlohmann::ordered_json> jitterSweep(const ProbeOptions& po, const std::vector<std::string>& scenes,
                                                const std::vector<double>& magnitudes) {
    std::vector<nlohmann::ordered_json> rows;
    auto backend = raster::makeCpuBackend();
    for (const std::string& name : scenes) {
        const Scene original = loadStudyScene(name, 0);
        Bounds box;
        for (size_t i = 0; i < original.objects.size(); ++i)
            for (const Vec3f& p : original.worldMesh(i).positions) box.add(p);
        const Vec3d centre = 0.5 * (box.lo + box.hi).cast<double>();
        const double diagonal = double(box.extent().norm());
        for (const std::string& method : po.methods) {
            Rng rng(po.seed);
            const CullideOptions o =
                probeOptions(method, po.depths.empty() ? "24" : po.depths.front(), po.resolution, "axes");
            auto record = [&](const Scene& s, const char* kind, double magnitude, int trial) {
                const Trial t = evaluate(s, o, *backend);
                nlohmann::ordered_json row;
                row["sweep"] = "jitter";
                row["scene"] = name;
                row["method"] = method;
                row["kind"] = kind;
                row["magnitude"] = magnitude;
                row["trial"] = trial;
                putTrial(row, t);
                rows.push_back(row);
            };
            record(original, "none", 0, 0);
            // Random rotations about the bounding-box centre (uniform unit quaternions).
            for (int trial = 0; trial < po.trials; ++trial) {
                Eigen::Quaterniond q(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
                if (q.norm() < 1e-3) q = Eigen::Quaterniond::Identity();
                q.normalize();
                Scene s = original;
                for (size_t i = 0; i < s.objects.size(); ++i) {
                    Mesh w = original.worldMesh(i);
                    for (Vec3f& p : w.positions) p = (q * (p.cast<double>() - centre) + centre).cast<float>();
                    s.objects[i].mesh = std::move(w);
                    s.objects[i].transform = Transform::Identity();
                }
                record(s, "rotation", 0, trial);
            }
            for (double m : magnitudes)
                for (int trial = 0; trial < po.trials; ++trial) {
                    Scene s = original;
                    for (size_t i = 0; i < s.objects.size(); ++i) {
                        Mesh w = original.worldMesh(i);
                        for (Vec3f& p : w.positions)
                            for (int k = 0; k < 3; ++k) p[k] = float(double(p[k]) + m * diagonal * rng.uniform(-1, 1));
                        s.objects[i].mesh = std::move(w);
                        s.objects[i].transform = Transform::Identity();
                    }
                    record(s, "perturb", m, trial);
                }
        }
    }
    return rows;
}

std::string rowsToCsv(const std::vector<nlohmann::ordered_json>& rows) {
    std::vector<std::string> keys;
    for (const auto& r : rows)
        for (const auto& [k, v] : r.items())
            if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
    std::string out;
    for (size_t i = 0; i < keys.size(); ++i) out += (i ? "," : "") + keys[i];
    out += "\n";
    for (const auto& r : rows) {
        for (size_t i = 0; i < keys.size(); ++i) {
            out += i ? "," : "";
            if (!r.contains(keys[i]) || r[keys[i]].is_null()) continue;
            const auto& v = r[keys[i]];
            if (v.is_string()) {
                const std::string s = v.get<std::string>();
                out += s.find_first_of(",\"") == std::string::npos ? s : "\"" + s + "\"";
            } else if (v.is_number_float()) {
                char buf[64];
                std::snprintf(buf, sizeof buf, "%.9g", v.get<double>());
                out += buf;
            } else {
                out += v.dump();
            }
        }
        out += "\n";
    }
    return out;
}

}  // namespace cullide::study
