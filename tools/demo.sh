#!/usr/bin/env bash
# The main job on the bundled data, from a fresh Debian 12 machine: installs the Debian packages
# (tools/setup.sh), builds cullide in Release, generates the paper's two scenes at ~5,000
# triangles (make-scene; same seed, same bytes) and describes every bundled and generated scene
# with `cullide info`.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/setup.sh
echo "== demo: configure and build (Release) in build/"
cmake --preset release >/dev/null
cmake --build build -j"$(nproc)" --target cullide
cullide=build/tools/cullide

mkdir -p out/scenes
echo "== demo: generate the paper's scenes into out/scenes"
"$cullide" make-scene bunny --triangles 5000 --seed 1 -o out/scenes/bunny_5k.json
"$cullide" make-scene cows --triangles 5000 --seed 1 -o out/scenes/cows_5k.json
"$cullide" make-scene cylinders --count 100 --triangles 20000 --frames 4 --seed 1 -o out/scenes/cylinders.json

echo "== demo: cullide info over the bundled and generated scenes"
"$cullide" info data/scenes/*.json data/meshes/*.off out/scenes/*.json
