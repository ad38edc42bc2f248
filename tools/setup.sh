#!/usr/bin/env bash
# Installs every Debian package cullide needs to build, test and plot, and three.js (npm) for the
# 3D view of `cullide report` (tools/report3d: `npm ci`, the version its package-lock.json pins).
#
# Non-interactive and idempotent: packages already installed are left alone, and when nothing
# is missing the script only checks (well under a second) and says so. Packages come from Debian's
# archive only (apt-get), three.js from npm's registry only (`npm ci` checks the lock file's
# integrity hashes); nothing is downloaded from anywhere else. Run as root (or with sudo available).
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake pkg-config git
  # core maths and threading
  libeigen3-dev libtbb-dev
  # oracle: Embree 3 broad phase, CGAL exact predicates (header-only, needs GMP/MPFR, Boost)
  libembree-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  # peers: the collision libraries the study compares with (FCL 0.7, Bullet 3.24's GImpact)
  libfcl-dev libbullet-dev
  # tests, benchmarks, command line, scene files, mesh input/output, PNG writer
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev libtinyobjloader-dev libmeshoptimizer-dev
  libstb-dev
  # GL backend: libepoxy for loading, headless EGL with Mesa (llvmpipe when there is no GPU)
  libepoxy-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
  # Vulkan backend: the loader and headers, Mesa's lavapipe (a Vulkan CPU device when there is no
  # GPU), the Khronos validation layer (on in the tests) and glslangValidator (shaders compiled at
  # build time). mesa-vulkan-drivers pulls Mesa's GL packages above up to its own point release
  # (llvmpipe changes with it), so both are installed together, in one apt-get call.
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers glslang-tools
  # charts
  python3 python3-matplotlib python3-numpy
  # headless Chromium: the test that `cullide report`'s page renders (Cli.ReportRendersInChromium)
  chromium
  # the Python module (python/) and its tests
  pybind11-dev python3-dev python3-pytest
  # the Slurm recipe of docs/studies.md, run by tools/cluster/slurm-smoke.sh on a private single-node cluster
  # (Slurm 22.05 and MUNGE; the script starts and stops its own daemons, nothing else runs them)
  slurm-wlm munge
)

# npm from Debian only where there is none (a newer one from elsewhere is kept).
command -v npm >/dev/null 2>&1 || packages+=(npm)

# three.js into tools/report3d/node_modules, unless the pinned version is already there.
report3d() {
  local dir want have
  dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/report3d"
  want=$(sed -n '/"node_modules\/three"/,/version/s/.*"version": *"\([^"]*\)".*/\1/p' "$dir/package-lock.json")
  have=""
  if [ -f "$dir/node_modules/three/package.json" ]; then
    have=$(sed -n 's/^ *"version": *"\([^"]*\)".*/\1/p' "$dir/node_modules/three/package.json" | head -1)
  fi
  if [ -n "$want" ] && [ "$want" = "$have" ]; then
    echo "setup: three.js $have already in tools/report3d/node_modules; nothing to do."
    return
  fi
  echo "setup: npm ci in tools/report3d (three.js $want)"
  (cd "$dir" && npm ci --omit=dev --no-audit --no-fund)
}

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} Debian packages already installed; nothing to do."
  report3d
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
    echo "setup: ${#missing[@]} packages missing (${missing[*]}) and not root, no sudo: install them as root." >&2
    exit 1
  fi
fi

echo "setup: installing ${#missing[@]} missing Debian packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
report3d
echo "setup: done."
