#!/usr/bin/env bash
# Builds the project and its tests under AddressSanitizer (with LeakSanitizer) and
# UndefinedBehaviorSanitizer into build-asan/ and runs the test suite there
# (docs/RELIABILITY.md, "Sanitizers"). Any finding fails the test that hit it (UBSan does not
# recover; ASan aborts; a leak fails the process at exit).
#   scripts/sanitize.sh [ctest args...]    e.g. scripts/sanitize.sh -R RawlogReader
# UPD_SANITIZE_SCOPE="core sim io" builds only those libraries' tests (tests/<library>/, ctest
# label <library>) and what they link, and runs only them: what CI runs
# (scripts/test.sh). An entry LIB/NAME takes one program, tests/LIB/NAME_test.cpp
# (apps/bad_input). The tests that run the `upd` binary (NavCli.*, BenchCli.*, the Kinect
# and ROS bag/node tests) come only with apps in the scope or named (apps/upd built
# instrumented). Default: every test.
# UPD_SANITIZE_EXCLUDE=REGEX leaves out more tests (ctest -E).
# Always left out: install_consumer (builds an outside project against the installed,
# instrumented libraries without the sanitizer runtime) and the closed-loop navigation
# scenarios (NavScenario.*: minutes each when instrumented; NavScenarioStart.* runs the first
# seconds of each, and their parts run in nav_simulation_test and nav_navigator_test);
# UPD_SANITIZE_ALL=1 runs them too.
set -euo pipefail
UPD_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${UPD_ASAN_BUILD:-$UPD_ROOT/build-asan}"
JOBS="${UPD_JOBS:-$(nproc)}"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
shared=()
[ -d "$UPD_ROOT/../shared/data" ] && shared=(-DUPD_SHARED_DATA_DIR="$UPD_ROOT/../shared/data")
[ -n "${UPD_SHARED_DATA_DIR:-}" ] && shared=(-DUPD_SHARED_DATA_DIR="$UPD_SHARED_DATA_DIR")

targets=()
labels=""
scope="${UPD_SANITIZE_SCOPE:-all}"
if [ "$scope" != all ]; then
  for entry in ${scope//,/ }; do
    lib="${entry%%/*}"
    files=("$UPD_ROOT"/tests/"$lib"/*_test.cpp)
    [ "$entry" = "$lib" ] || files=("$UPD_ROOT/tests/$entry"_test.cpp)
    if [ ! -f "${files[0]}" ]; then
      echo "sanitize: UPD_SANITIZE_SCOPE names '$entry': no tests/$entry*_test.cpp" >&2
      exit 2
    fi
    for f in "${files[@]}"; do
      # A test that runs the `upd` binary needs apps/upd built instrumented: only with apps
      # in the scope, or when the program is named.
      if [ "$entry" = "$lib" ] && [[ " ${scope//,/ } " != *" apps "* ]] &&
         grep -qE 'UPD_BINARY|runUpd\(' "$f"; then
        echo "sanitize: leaving out ${lib}_$(basename "$f" .cpp) (runs upd: add apps to the scope)"
        continue
      fi
      targets+=("${lib}_$(basename "$f" .cpp)")
    done
    [[ "|$labels|" == *"|$lib|"* ]] || labels="${labels:+$labels|}$lib"
  done
fi

# Line tables only (-g1): a finding still names file and line, and the build takes about a
# third less time than with full debug information. clang 14, as for the fuzzers: it compiles
# the instrumented code in a third to a half of gcc 12's time.
cmake -S "$UPD_ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DUPD_BUILD_BENCH=OFF \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
      -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_C_COMPILER=clang-14 \
      -DUPD_SANITIZE=address,undefined "${launcher[@]}" "${shared[@]}" >/dev/null
if ((${#targets[@]})); then
  # An optional library's tests (learn, freenect, ros) exist only when it was configured.
  known=" $(cmake --build "$BUILD" --target help | sed -n 's/^\.\.\. \([^ ]*\).*/\1/p' | tr '\n' ' ') "
  present=()
  for t in "${targets[@]}"; do
    if [[ "$known" == *" $t "* ]]; then present+=("$t"); else echo "sanitize: $t not configured"; fi
  done
  targets=("${present[@]}")
fi
if ((${#targets[@]})); then
  cmake --build "$BUILD" -j"$JOBS" --target "${targets[@]}"
else
  cmake --build "$BUILD" -j"$JOBS"
fi

# Leaks are reported at exit by LeakSanitizer; those inside system libraries are not ours and
# are suppressed by name, each with its reason (scripts/lsan.supp).
# verify_asan_link_order=0: the Kinect tests run `upd` under fakenect, which preloads its
# libfreenect (LD_PRELOAD) ahead of the ASan runtime; ASan would refuse to start.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:verify_asan_link_order=0}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$UPD_ROOT/scripts/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
exclude="install_consumer"
[ "${UPD_SANITIZE_ALL:-0}" = 1 ] || exclude="$exclude|^NavScenario\."
# The programs left out above appear to ctest as <program>_NOT_BUILT.
[ "$scope" = all ] || exclude="$exclude|_NOT_BUILT\$"
[ -n "${UPD_SANITIZE_EXCLUDE:-}" ] && exclude="$exclude|$UPD_SANITIZE_EXCLUDE"
select=()
[ -n "$labels" ] && select=(-L "^($labels)\$")
cd "$BUILD"
ctest --output-on-failure -j"$JOBS" -E "$exclude" "${select[@]}" "$@"
