#!/usr/bin/env bash
# The main job on the bundled data, from a fresh Debian 12 machine: installs the Debian packages
# (tools/setup.sh), builds cullide in Release, generates the paper's two scenes at ~5,000
# triangles (make-scene; same seed, same bytes), describes every scene with `cullide info`, and
# prunes the paper's scenes and the bundled animation with the self-intersection variant
# (`cullide prune`, 500x500, D24, the six axis directions), writing the PCS as JSON and as a
# coloured PLY (the paper's Figures 6 and 7) and the pruning pictures (Figure 12) into out/.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/setup.sh
echo "== demo: configure and build (Release) in build/"
cmake --preset release >/dev/null
cmake --build build -j"$(nproc)" --target cullide
cullide=build/tools/cullide

mkdir -p out/scenes
echo "== demo: generate the paper's scenes into out/scenes"
"$cullide" make-scene bunny --triangles 5000 -o out/scenes/bunny_5k.json
"$cullide" make-scene cows --triangles 5000 -o out/scenes/cows_5k.json
"$cullide" make-scene cylinders --count 100 --triangles 20000 --frames 4 --seed 1 -o out/scenes/cylinders.json

echo "== demo: cullide info over the bundled and generated scenes"
"$cullide" info data/scenes/*.json data/meshes/*.off out/scenes/*.json

echo "== demo: cullide prune (modified method: self-intersections stay in the PCS)"
# Exit status 1: --check found false prunes, as the paper says it may.
"$cullide" prune out/scenes/bunny_5k.json --check --json out/bunny_5k_pcs.json --out out/bunny_5k_pcs.ply \
  --frames out/bunny_5k_frames || [ $? -eq 1 ]
"$cullide" prune out/scenes/cows_5k.json --check --json out/cows_5k_pcs.json --out out/cows_5k_pcs.ply || [ $? -eq 1 ]
echo "== demo: the reliable method (no intersecting triangle is ever pruned), checked against the exact oracle"
"$cullide" prune out/scenes/cows_5k.json --method reliable --check
"$cullide" prune data/scenes/bunny_through_cow.json --json out/bunny_through_cow_pcs.json
echo "== demo: cullide prune --method original (Cullide: contacts between objects, no self-intersections)"
"$cullide" prune data/scenes/bunny_through_cow.json --method original --frame 4
echo "== demo: outputs in out/ (PCS JSON, PLY with PCS triangles green, PNG pictures)"
