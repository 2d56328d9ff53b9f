#!/usr/bin/env bash
# Builds the project and its tests under AddressSanitizer and UndefinedBehaviorSanitizer into
# build-asan/ and runs the test suite there (docs/RELIABILITY.md, "Sanitizers"). Any finding
# fails the test that hit it (UBSan does not recover; ASan aborts).
#   scripts/sanitize.sh [ctest args...]    e.g. scripts/sanitize.sh -R io_
# UPD_SANITIZE_SCOPE=core builds only the Eigen-only libraries and their tests (libs/core,
# libs/sim: -DUPD_CORE_ONLY=ON) into build-asan-core/: the bounded step CI runs.
# Left out under the sanitizers: install_consumer (builds an outside project against the
# installed, instrumented libraries without the sanitizer runtime) and the closed-loop
# navigation scenarios (NavScenario.*: minutes each when instrumented; their code paths
# run in nav_simulation_test and nav_navigator_test). UPD_SANITIZE_ALL=1 runs them too.
set -euo pipefail
UPD_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${UPD_ASAN_BUILD:-$UPD_ROOT/build-asan}"
scope=()
if [ "${UPD_SANITIZE_SCOPE:-all}" = core ]; then
  BUILD="${UPD_ASAN_BUILD:-$UPD_ROOT/build-asan-core}"
  scope=(-DUPD_CORE_ONLY=ON)
fi
JOBS="${UPD_JOBS:-$(nproc)}"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
shared=()
[ -d "$UPD_ROOT/../shared/data" ] && shared=(-DUPD_SHARED_DATA_DIR="$UPD_ROOT/../shared/data")
[ -n "${UPD_SHARED_DATA_DIR:-}" ] && shared=(-DUPD_SHARED_DATA_DIR="$UPD_SHARED_DATA_DIR")

cmake -S "$UPD_ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DUPD_BUILD_BENCH=OFF \
      -DUPD_SANITIZE=address,undefined "${scope[@]}" "${launcher[@]}" "${shared[@]}" >/dev/null
cmake --build "$BUILD" -j"$JOBS"

# Leaks are reported at exit by ASan; those inside system libraries (MRPT's class registry,
# OpenMP's thread pool, VTK) are not ours and are suppressed by name.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$UPD_ROOT/scripts/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
exclude="install_consumer"
[ "${UPD_SANITIZE_ALL:-0}" = 1 ] || exclude="$exclude|^NavScenario\."
cd "$BUILD"
ctest --output-on-failure -j"$JOBS" -E "$exclude" "$@"
