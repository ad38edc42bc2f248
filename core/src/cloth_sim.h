// The cloth simulator behind makeCloth (cullide/cloth.h): position-based dynamics on a square grid
// of particles, in double precision, one thread, every loop in a fixed order.
//
// Model (Mueller et al., "Position Based Dynamics", 2007; Macklin et al., "Small Steps in Physics
// Simulation", 2019, for many short substeps of few passes rather than one step of many passes):
//   - particles of equal mass on an (n + 1) x (n + 1) grid, rest spacing `edge`;
//   - distance constraints (stiffness 1) on every triangle edge: the grid's rows
//     and columns and the diagonal that splits each cell (alternating with the cell's parity, so
//     that the cloth has no preferred shear direction);
//   - bending resistance: each particle pulled a little towards the midpoint of its two
//     neighbours along a row and along a column (the discrete curvature, zero on the flat cloth);
//   - a sphere (centre origin, radius kSphereRadius) that particles are projected out of, with
//     Coulomb friction: a particle pressed onto it sticks, one that barely touches it slides;
//   - gravity along -y, velocity damping;
//   - optionally, repulsion (cloth_repulsion.h) between the particles of a sub-grid (every k-th
//     row and column, k chosen for a fixed spacing in radii, so that the same folds meet it at any
//     resolution) that are not grid neighbours: they are pushed apart to a fraction of the
//     sub-grid's spacing, which keeps most layers of a fold apart. The near pairs are found every
//     few steps with no margin: a wrinkle finer than the sub-grid, or a fold that closes between
//     two searches, passes through, as some folds do in real simulator output (whose collision
//     proxies are coarser than its mesh), which the scene stands for.
#pragma once

#include "cloth_repulsion.h"

#include "cullide/cloth.h"
#include "cullide/mesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cullide::cloth {

inline constexpr double kSphereRadius = 1.0;

// The model's constants: makeCloth uses these defaults; cloth::makeCloth below takes others (tuning).
struct Tuning {
    double referenceEdge = 0.02;    // the edge (in radii) the settings below hold for; others scale
    size_t substeps = 10;           // per step, at the reference edge
    size_t maxSubsteps = 16;
    size_t iterations = 2;          // passes over the constraints per substep
    double bendStiffness = 0.03;    // fraction of a row or column's curvature removed per pass
    double damping = 5.0;           // velocity lost per second, as a fraction
    double friction = 0.5;          // Coulomb coefficient of the sphere's friction
    double contactOffset = 0.005;   // particles are kept this fraction of the radius outside
    double proxySpacing = 0.125;    // repulsion acts between the particles of a sub-grid this far apart
    double repulsion = 0.6;         // repulsion distance, in sub-grid spacings
    double repulsionStiffness = 0.5;  // fraction of a near pair's overlap removed per pass
    double neighbourMargin = 0.0;   // the near-pair list's extra radius, in sub-grid spacings ...
    size_t neighbourEvery = 3;      // ... found every this many steps
    double lift = 0.25;             // initial height of the cloth above the sphere's top, in radii
    double gravity = 9.81;
};

struct SimSetup {
    size_t cells = 0;     // n: the grid has n x n cells, (n + 1)^2 particles
    double side = 0;      // the cloth's side length
    bool repulsion = true;
    uint64_t seed = 1;    // perturbs the initial placement
    Tuning tuning;
};

// One distance constraint: particles a and b kept `rest` apart.
struct Link {
    Link() = default;
    Link(uint32_t a_, uint32_t b_, double rest_) : a(a_), b(b_), rest(rest_), inverseRestSquared(1.0 / (rest_ * rest_)) {}
    uint32_t a = 0, b = 0;
    double rest = 0, inverseRestSquared = 0;
};

// A particle m and its two neighbours a, b along a row or a column.
struct Triple {
    uint32_t a = 0, m = 0, b = 0;
};

class Simulation {
public:
    explicit Simulation(const SimSetup& setup);

    // Advances the state by one step (kStepSeconds, in substeps()).
    void step();

    const std::vector<Vec3d>& positions() const { return x_; }

    static constexpr double kStepSeconds = 1.0 / 120.0;

private:
    void substep(double h, bool rebuildNeighbours);
    void solveLinks(bool backwards);
    void solveSphere();
    void solveTriples(double k, bool backwards);
    void solveRepulsion();
    void applyFriction();

    SimSetup setup_;
    double edge_ = 0, contactRadius_ = 0, repulsionDistance_ = 0, bendStiffness_ = 0;
    size_t substeps_ = 0, proxyStride_ = 1;
    std::vector<Vec3d> x_, v_, p_;   // positions, velocities, predicted positions
    std::vector<double> contact_;    // how far the sphere pushed each particle out in this substep
    std::vector<Link> links_;
    std::vector<Triple> triples_;
    NearPairs grid_;
    std::vector<std::pair<uint32_t, uint32_t>> near_;  // repulsion candidates (i < j), in order
    size_t steps_ = 0;
};

// cullide::makeCloth with the model's constants given (cloth.cpp).
Animation makeCloth(const ClothRequest& request, const Tuning& tuning);

}  // namespace cullide::cloth
