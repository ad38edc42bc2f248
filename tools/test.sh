#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs the Debian packages the project
# needs (tools/setup.sh), builds in Release, runs every test with CTest and the Slurm recipe of docs/studies.md
# on a private single-node cluster (tools/cluster/slurm-smoke.sh, as root), then builds and runs the
# test suite under AddressSanitizer+UndefinedBehaviorSanitizer and under ThreadSanitizer.
# The ThreadSanitizer build links a oneTBB built with -fsanitize=thread from Debian's source package
# of the installed libtbb-dev (tools/sanitizers/build-tbb-tsan.sh: adds a deb-src entry for Debian's
# archive, then builds once into build-tsan/_deps/onetbb-tsan, a few minutes, reused later), so
# that TSan sees TBB's synchronisation and needs no TBB suppression.
#
#   bash tools/test.sh            # everything (what CI runs)
#   CULLIDE_SANITIZERS=0 bash tools/test.sh   # Release tests only (quicker, for development)
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/setup.sh
jobs=$(nproc)
# setup.sh installs Mesa's EGL (llvmpipe) and Vulkan (lavapipe, validation layers), so the GL and
# Vulkan tests must run here, not skip; and Chromium, so the report's render test must too.
export CULLIDE_REQUIRE_GL=1 CULLIDE_REQUIRE_VULKAN=1 CULLIDE_REQUIRE_CHROMIUM=1

run_suite() {  # preset name, build dir, extra configure arguments
  echo "== test.sh: configure and build ($1) in $2"
  cmake --preset "$1" "${@:3}" >/dev/null
  cmake --build "$2" -j"$jobs"
  echo "== test.sh: run the tests ($1)"
  ctest --test-dir "$2" --output-on-failure -j"$jobs" --timeout 900
}

run_suite release build
echo "== test.sh: the Slurm recipe of docs/studies.md (tools/cluster/slurm-smoke.sh)"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo" # munged's key must belong to the munge user
$sudo bash tools/cluster/slurm-smoke.sh build/tools/cullide
if [ "${CULLIDE_SANITIZERS:-1}" != "0" ]; then
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$PWD/tools/sanitizers/tsan.supp"
  run_suite asan build-asan
  echo "== test.sh: oneTBB with ThreadSanitizer (built once)"
  tbb=$PWD/build-tsan/_deps/onetbb-tsan
  bash tools/sanitizers/build-tbb-tsan.sh "$tbb"
  run_suite tsan build-tsan -DTBB_DIR="$tbb/install/lib/cmake/TBB"
fi
echo "== test.sh: all test suites passed"
