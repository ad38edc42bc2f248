#!/usr/bin/env bash
# Builds oneTBB with -fsanitize=thread for the tsan preset, from Debian's own source package of
# the installed libtbb-dev (same version, same Debian patches).
#
# Why: Debian's libtbb.so is not instrumented, so ThreadSanitizer cannot see the synchronisation
# inside it (task hand-over, the wait of tbb::parallel_for for its workers) and reports TBB's
# objects, and the caller's stack slots that TBB's workers touched, as racing. With libtbb
# itself built with TSan every such happens-before is visible and no TBB suppression is needed.
#
#   bash tools/sanitizers/build-tbb-tsan.sh [DIR]   # DIR defaults to build-tsan/_deps/onetbb-tsan
#
# Leaves DIR/{src,build,install}; CMake finds the library with -DTBB_DIR=DIR/install/lib/cmake/TBB
# (the tsan preset sets that). Built once: DIR/install/stamp records the version and the recipe,
# and a later run with the same ones only checks it and exits. Needs root (or sudo) only the
# first time, to add a deb-src entry for Debian's archive (a separate file, written only if it
# differs) and run apt-get update.
set -euo pipefail
cd "$(dirname "$0")/../.."

dir=$(realpath -m "${1:-build-tsan/_deps/onetbb-tsan}")
version=$(dpkg-query -W -f='${Version}' libtbb-dev)
# tbbmalloc and tbbbind are not built: without them in DIR/install/lib, libtbb falls back to
# malloc (which TSan intercepts) and to no hwloc binding. Change the recipe -> rebuild.
recipe="TBB_SANITIZE=thread TBB_TEST=OFF TBB_STRICT=OFF TBBMALLOC_BUILD=OFF RelWithDebInfo"
stamp="$dir/install/stamp"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "onetbb $version $recipe" ]; then
  echo "build-tbb-tsan: oneTBB $version (TSan) already built in $dir/install"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
    echo "build-tbb-tsan: not root and no sudo: cannot add the deb-src entry or install dpkg-dev." >&2
    exit 1
  fi
fi

# apt-get source unpacks with dpkg-source (dpkg-dev).
if ! dpkg-query -W -f='${Status}' dpkg-dev 2>/dev/null | grep -q "install ok installed"; then
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends dpkg-dev
fi

# Source entries for the same archive and suites as Debian 12's binary ones (debian.sources).
list=/etc/apt/sources.list.d/cullide-deb-src.sources
entry="Types: deb-src
URIs: http://deb.debian.org/debian
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb-src
URIs: http://deb.debian.org/debian-security
Suites: bookworm-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg"
if [ "$(cat "$list" 2>/dev/null)" != "$entry" ]; then
  echo "build-tbb-tsan: adding $list"
  printf '%s\n' "$entry" | $sudo tee "$list" >/dev/null
fi
if ! apt-cache showsrc onetbb 2>/dev/null | grep -qxF "Version: $version"; then
  $sudo apt-get update -qq
fi

start=$SECONDS
rm -rf "$dir/src" "$dir/build" "$dir/install"
mkdir -p "$dir/src"
echo "build-tbb-tsan: apt-get source onetbb=$version into $dir/src"
(cd "$dir/src" && apt-get source -qq "onetbb=$version" 2>&1 | grep -v "unsandboxed as root" || true)
src=$(find "$dir/src" -mindepth 1 -maxdepth 1 -type d -name 'onetbb-*' | head -n 1)
if [ -z "$src" ] || [ ! -f "$src/CMakeLists.txt" ]; then
  echo "build-tbb-tsan: apt-get source onetbb=$version did not unpack a source tree in $dir/src" >&2
  exit 1
fi

# TBB_STRICT=OFF: upstream's -Werror is meant for its own CI compilers (Debian's
# warning-flags.patch already has to demote four of GCC 12's warnings); a warning must not stop
# the test run. -Wno-tsan: GCC notes at every inlined std::atomic_thread_fence that TSan does
# not model fences (TBB has a few in its sleep/wake-up code, beside atomics that TSan does see).
cmake -S "$src" -B "$dir/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS=-Wno-tsan \
  -DCMAKE_INSTALL_PREFIX="$dir/install" -DCMAKE_INSTALL_LIBDIR=lib \
  -DTBB_SANITIZE=thread -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF -DTBB_STRICT=OFF \
  -DTBBMALLOC_BUILD=OFF -DTBB_DISABLE_HWLOC_AUTOMATIC_SEARCH=ON >/dev/null
cmake --build "$dir/build" -j"$(nproc)"
cmake --install "$dir/build" >/dev/null
echo "onetbb $version $recipe" >"$stamp"
echo "build-tbb-tsan: oneTBB $version built with TSan in $((SECONDS - start)) s: $dir/install"
