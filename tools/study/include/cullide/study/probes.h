// Stability where image-space culling fails: four sweeps over small controlled scenes (the seed
// paper's Section 5, docs/paper.md#figure-5), and the jitter of the
// paper's scenes. Each returns one flat JSON row per trial (written as CSV by `cullide study
// --stability`; charted by tools/plot.py).
//
// Conventions
//   - Every trial builds a scene, runs Cullide on the CPU reference, the exact oracle and the
//     cause attribution (causes.h); "detected" means no false prune (every colliding triangle is
//     in the PCS). Rows carry the false prunes by cause; "fp_unexplained" must be 0.
//   - Controlled scenes have an "anchor": a triangle whose projection along +z is a segment (no
//     fragments, no pair), spanning z in [-1, 1], so that the fitted view's depth range, and with
//     it the depth step, does not depend on the probe. Probes view along +z only, unless the
//     sweep varies the direction set. Each object is one hierarchy leaf.
//   - Seeded (std::mt19937_64 with our own conversion): same options, same rows.
#pragma once

#include "cullide/scene.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace cullide::study {

struct ProbeOptions {
    int resolution = 128;
    int trials = 20;
    uint64_t seed = 1;
    std::vector<std::string> methods{"original", "modified"};
    std::vector<std::string> depths{"16", "24", "float"};
};

// Two crossing surfaces (a square A and a triangle B whose edge lies delta behind A, almost
// parallel to it) for delta = factor x (far - near) / 2^n (for float: x (far - near) 2^-24),
// random sub-step phase, rotation about the view and offset. Row: method, depth, factor,
// delta_steps (delta in stored steps (far-near)/(2^n-1)), sampled_steps (the deepest penetration
// of B behind A at a pixel centre both cover, in stored steps), detected, causes.
std::vector<nlohmann::ordered_json> penetrationSweep(const ProbeOptions& o, const std::vector<double>& factors);

// A triangle B tilted from face-on (0 deg) to edge-on (90 deg) to the view axis +z, crossing a
// triangle A at a 60-degree dihedral (A is never more than 60 deg from face-on), random rotation
// about z and offset; per direction set (e.g. "0 0 1", "axes", "14"). Row: method, directions,
// angle, detected, causes.
std::vector<nlohmann::ordered_json> tiltSweep(const ProbeOptions& o, const std::vector<double>& angles,
                                              const std::vector<std::string>& directionSets);

// A small triangle B crossing a large square A, its projection (the overlap) an equilateral
// triangle whose inscribed circle has diameter `size` x the pixel diagonal; one corner 0.05
// behind A, two in front; random position and rotation. Row: method, depth, size, detected,
// causes.
std::vector<nlohmann::ordered_json> overlapSweep(const ProbeOptions& o, const std::vector<double>& sizes);

// The paper's scenes under jitter: per scene string (study.h), a random rotation of the whole
// scene ("rotation"), or every vertex moved by up to magnitude x the bounding-box diagonal
// ("perturb"); trial 0 of each scene is the scene as it is ("none"). Row: scene, method, kind,
// magnitude, trial, pcs, oracle_pairs, false_prunes, causes.
std::vector<nlohmann::ordered_json> jitterSweep(const ProbeOptions& o, const std::vector<std::string>& scenes,
                                                const std::vector<double>& magnitudes);

// Writes rows as CSV (columns: the union of the rows' keys, in first-seen order).
std::string rowsToCsv(const std::vector<nlohmann::ordered_json>& rows);

}  // namespace cullide::study
