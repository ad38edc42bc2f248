// The cloth simulator (cloth_sim.h).
//
// Determinism: IEEE double + - * / and sqrt in a fixed order, std::sin/std::cos for the initial
// placement, std::mt19937_64 through our own conversion to double; one thread; every loop runs
// in a fixed order (each substep's two passes: the constraints forwards, then backwards).
#include "cloth_sim.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace cullide::cloth {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Uniform double in [0, 1): the top 53 bits of one mt19937_64 draw, scaled exactly.
double uniform01(std::mt19937_64& rng) {
    return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// v rotated about the unit vector k by `angle` (Rodrigues' formula).
Vec3d rotate(const Vec3d& v, const Vec3d& k, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    return v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c));
}

// The seed's placement: the flat grid turned about the vertical (yaw), tilted a little about a
// horizontal axis, moved off the sphere's axis a little, each particle lifted by a tiny jitter
// (so that the folds' buckling does not follow the grid's symmetry).
std::vector<Vec3d> initialPositions(const SimSetup& setup, double edge) {
    std::mt19937_64 rng(setup.seed);
    const double yaw = 2.0 * kPi * uniform01(rng);
    const double tiltAxis = 2.0 * kPi * uniform01(rng);
    const double tilt = (5.0 / 180.0 * kPi) * uniform01(rng);
    const double offsetX = 0.1 * kSphereRadius * (2.0 * uniform01(rng) - 1.0);
    const double offsetZ = 0.1 * kSphereRadius * (2.0 * uniform01(rng) - 1.0);
    const Vec3d up(0, 1, 0), axis(std::cos(tiltAxis), 0, std::sin(tiltAxis));
    const Vec3d centre(offsetX, kSphereRadius * (1.0 + setup.tuning.lift), offsetZ);
    const size_t w = setup.cells + 1;
    std::vector<Vec3d> x(w * w);
    for (size_t r = 0; r < w; ++r)
        for (size_t c = 0; c < w; ++c) {
            const double jitter = 1e-3 * edge * (2.0 * uniform01(rng) - 1.0);
            const Vec3d local(double(c) * edge - 0.5 * setup.side, jitter, double(r) * edge - 0.5 * setup.side);
            x[r * w + c] = centre + rotate(rotate(local, up, yaw), axis, tilt);
        }
    return x;
}

// Triangle edges (rows, columns, each cell's diagonal), in an order that is both a Gauss-Seidel
// sweep along the cloth and fast: row links column by column (each row swept from one end to the
// other, so that a pass carries a correction along the whole row), column links row by row,
// diagonals column by column (even rows, then odd). Consecutive links then share no particle, so
// that no link waits for the one before it: a pass runs at the processor's throughput, not at the
// latency of a square root and a division per link.
std::vector<Link> makeLinks(size_t cells, double edge) {
    const size_t w = cells + 1;
    const auto id = [w](size_t r, size_t c) { return static_cast<uint32_t>(r * w + c); };
    const double diagonal = edge * std::sqrt(2.0);
    std::vector<Link> links;
    for (size_t c = 0; c < cells; ++c)
        for (size_t r = 0; r < w; ++r) links.push_back({id(r, c), id(r, c + 1), edge});
    for (size_t r = 0; r < cells; ++r)
        for (size_t c = 0; c < w; ++c) links.push_back({id(r, c), id(r + 1, c), edge});
    for (size_t c = 0; c < cells; ++c)
        for (size_t parity = 0; parity < 2; ++parity)
            for (size_t r = parity; r < cells; r += 2) {
                if ((r + c) % 2 == 0) links.push_back({id(r, c), id(r + 1, c + 1), diagonal});
                else links.push_back({id(r, c + 1), id(r + 1, c), diagonal});
            }
    return links;
}

// Curvature triples: each particle with its two neighbours along a row, and along a column, in the
// same order as makeLinks' (consecutive triples disjoint).
std::vector<Triple> makeTriples(size_t cells) {
    const size_t w = cells + 1;
    const auto id = [w](size_t r, size_t c) { return static_cast<uint32_t>(r * w + c); };
    std::vector<Triple> triples;
    for (size_t c = 1; c < cells; ++c)
        for (size_t r = 0; r < w; ++r) triples.push_back({id(r, c - 1), id(r, c), id(r, c + 1)});
    for (size_t r = 1; r < cells; ++r)
        for (size_t c = 0; c < w; ++c) triples.push_back({id(r - 1, c), id(r, c), id(r + 1, c)});
    return triples;
}

// Moves a and b along their difference so that a fraction `k` of their distance's error to
// `rest` goes (equal masses: each moves half). Coincident particles are left alone.
void project(Vec3d& a, Vec3d& b, double rest, double k) {
    const Vec3d d = b - a;
    const double len = std::sqrt(d.dot(d));
    if (!(len > 0.0)) return;
    const Vec3d move = d * (0.5 * k * (len - rest) / len);
    a += move;
    b -= move;
}

// project() for a link near its rest length, without a square root or a division: the fraction
// (len - rest) / len = 1 - 1 / sqrt(1 + u), u = len^2 / rest^2 - 1, to second order in u while
// |u| <= 1/4 (the link within about 12 % of its rest length), exactly beyond. It is zero exactly at
// the rest length, so the passes settle where exact ones do; the step differs by under 4 %.
void projectNear(Vec3d& a, Vec3d& b, const Link& l, double k) {
    const Vec3d d = b - a;
    const double u = d.dot(d) * l.inverseRestSquared - 1.0;
    if (!(std::abs(u) <= 0.25)) return project(a, b, l.rest, k);
    const Vec3d move = d * (0.5 * k * u * (0.5 - 0.375 * u));
    a += move;
    b -= move;
}

}  // namespace

Simulation::Simulation(const SimSetup& setup) : setup_(setup) {
    edge_ = setup.side / double(setup.cells);
    const double sag = edge_ * edge_ / kSphereRadius;  // a cell's deepest dip below its corners' sphere
    contactRadius_ = kSphereRadius * (1.0 + setup.tuning.contactOffset) + 0.5 * sag;
    proxyStride_ = static_cast<size_t>(std::max(1.0, std::round(setup.tuning.proxySpacing / edge_)));
    repulsionDistance_ = setup.tuning.repulsion * double(proxyStride_) * edge_;
    const double scale = setup.tuning.referenceEdge / edge_;
    // A pass removes a fraction k of a curvature term C ~ edge^2 kappa / 2: the same cloth at any
    // resolution (the same folds) takes k ~ 1 / edge^2.
    bendStiffness_ = std::min(1.0, setup.tuning.bendStiffness * scale * scale);
    // A finer cloth has longer chains of links for a pass to carry a correction along: more
    // substeps keep its edges as near their rest length (about as sqrt(1 / edge), as measured).
    const double substeps = std::ceil(double(setup.tuning.substeps) * std::sqrt(scale) - 1e-9);
    substeps_ = static_cast<size_t>(std::clamp(substeps, 2.0, double(setup.tuning.maxSubsteps)));
    x_ = initialPositions(setup, edge_);
    v_.assign(x_.size(), Vec3d::Zero());
    p_ = x_;
    contact_.assign(x_.size(), 0.0);
    links_ = makeLinks(setup.cells, edge_);
    triples_ = makeTriples(setup.cells);
}

void Simulation::step() {
    const double h = kStepSeconds / double(substeps_);
    const bool rebuild = steps_ % setup_.tuning.neighbourEvery == 0;
    for (size_t s = 0; s < substeps_; ++s) substep(h, rebuild && s == 0);
    ++steps_;
}

void Simulation::substep(double h, bool rebuildNeighbours) {
    const Tuning& t = setup_.tuning;
    const double keep = 1.0 - t.damping * h;
    const Vec3d fall(0, -t.gravity * h, 0);
    for (size_t i = 0; i < x_.size(); ++i) {
        v_[i] = (v_[i] + fall) * keep;
        p_[i] = x_[i] + v_[i] * h;
        contact_[i] = 0.0;
    }
    if (setup_.repulsion && rebuildNeighbours) {
        const double radius = (t.repulsion + t.neighbourMargin) * double(proxyStride_) * edge_;
        near_ = grid_.find(p_, setup_.cells + 1, 1, radius, proxyStride_);
    }
    for (size_t it = 0; it < t.iterations; ++it) {
        // Forwards, then backwards: the pair has no preferred direction. (Passes that alternate
        // from one substep to the next instead feed their bias into the velocities: it oscillates.)
        const bool backwards = it % 2 == 1;
        solveLinks(backwards);
        solveTriples(bendStiffness_, backwards);
        if (setup_.repulsion) solveRepulsion();
        solveSphere();
    }
    applyFriction();
    for (size_t i = 0; i < x_.size(); ++i) {
        v_[i] = (p_[i] - x_[i]) / h;
        x_[i] = p_[i];
    }
}

void Simulation::solveLinks(bool backwards) {
    const size_t n = links_.size();
    for (size_t k = 0; k < n; ++k) {
        const Link& l = links_[backwards ? n - 1 - k : k];
        projectNear(p_[l.a], p_[l.b], l, 1.0);
    }
}

// Bending: C = x_m - (x_a + x_b) / 2, the discrete curvature of a row or column (zero on the flat
// cloth at rest), projected linearly (no square root): a fraction k of it goes, the middle particle
// moving -k C / 1.5 and its neighbours k C / 3 each (equal masses, momentum kept). Unlike links
// between particles two apart, it also resists the grid-scale zigzag (a checkerboard of particles
// up and down) that leaves every distance between same-parity particles unchanged.
void Simulation::solveTriples(double k, bool backwards) {
    const size_t n = triples_.size();
    const double middle = k / 1.5, side = k / 3.0;
    for (size_t j = 0; j < n; ++j) {
        const Triple& t = triples_[backwards ? n - 1 - j : j];
        Vec3d& a = p_[t.a];
        Vec3d& m = p_[t.m];
        Vec3d& b = p_[t.b];
        const Vec3d c = m - (a + b) * 0.5;
        m -= c * middle;
        a += c * side;
        b += c * side;
    }
}

void Simulation::solveRepulsion() {
    for (const auto& [i, j] : near_) {
        const Vec3d d = p_[j] - p_[i];
        if (d.dot(d) < repulsionDistance_ * repulsionDistance_)
            project(p_[i], p_[j], repulsionDistance_, setup_.tuning.repulsionStiffness);
    }
}

void Simulation::solveSphere() {
    const double r2 = contactRadius_ * contactRadius_;
    for (size_t i = 0; i < p_.size(); ++i) {
        Vec3d& p = p_[i];
        const double d2 = p.dot(p);
        if (d2 >= r2) continue;
        const double d = std::sqrt(d2);
        contact_[i] += contactRadius_ - d;
        if (d > 0.0) p *= contactRadius_ / d;
        else p = Vec3d(0, contactRadius_, 0);
    }
}

// Coulomb friction (Macklin et al., "Unified Particle Physics for Real-Time Applications", 2014):
// a particle the sphere pushed out by a depth d in this substep (the normal force's measure) loses
// up to friction * d of its motion along the surface; all of it when that motion is smaller (it
// sticks). Pressed hard (under the cloth's weight and tension), it stays; barely touching, it slides.
void Simulation::applyFriction() {
    for (size_t i = 0; i < p_.size(); ++i) {
        if (!(contact_[i] > 0.0)) continue;
        const Vec3d n = p_[i] / std::sqrt(p_[i].dot(p_[i]));
        const Vec3d dx = p_[i] - x_[i];
        const Vec3d tangential = dx - n * n.dot(dx);
        const double slide = std::sqrt(tangential.dot(tangential));
        const double grip = setup_.tuning.friction * contact_[i];
        p_[i] -= slide <= grip ? tangential : tangential * (grip / slide);
    }
}

}  // namespace cullide::cloth
