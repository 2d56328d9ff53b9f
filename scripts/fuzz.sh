#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz with clang 14 under ASan and UBSan into
# build-fuzz/, and runs each for SECONDS (default 30): the four cloud readers (pcd, ply, xyz,
# kitti_bin), the robot config (ini), a rawlog object stream (rawlog), a depth PNG (depth_png)
# and a depth camera's calibration YAML (calibration), a ROS 1 bag and a compressed depth image
# (bag, compressed_depth: built when the ROS 1 packages are there), a classifier model (classifier: built with OpenCV's ml module) and the
# core pipeline on arbitrary float clouds (pipeline).
# docs/RELIABILITY.md, "Fuzzing".
#   scripts/fuzz.sh [SECONDS] [TARGET...]     e.g. scripts/fuzz.sh 600 pcd ply
# UPD_FUZZ_RUNS=N stops each target after N inputs as well (what comes first), and
# UPD_FUZZ_SEED=S fixes libFuzzer's random seed: with both, a run covers about the same inputs
# each time (what CI uses; not exactly, as libFuzzer's coverage feedback varies, so CI can still
# meet a new finding); longer runs hunt without them.
# Seeds are made at run time: generated samples and scenes (fuzz_seeds), the shipped configs,
# and the small clouds and rawlogs of ../shared/data (rawlogs decompressed, so the fuzzer
# mutates the object stream and not the gzip layer). The corpus grows in build-fuzz/corpus/
# from run to run. A crash stops with its input saved as build-fuzz/crashes/<target>-crash-*
# and the command that replays it; turn it into a regression: a reader's input into
# tests/io/regressions/ (a ctest case), any target's into tests/fuzz/regressions/<target>/
# (replayed first by every run of that target).
set -euo pipefail
UPD_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${UPD_FUZZ_BUILD:-$UPD_ROOT/build-fuzz}"
SECS="${1:-30}"
[ $# -gt 0 ] && shift
ALL=(pcd ply xyz kitti_bin ini rawlog depth_png calibration classifier bag compressed_depth pipeline)
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=("${ALL[@]}")
SHARED="${UPD_SHARED_DATA_DIR:-$UPD_ROOT/../shared/data}"

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# Line tables only (-g1): a finding still names file and line, and the build takes about a
# third less time than with full debug information.
cmake -S "$UPD_ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
      -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_C_COMPILER=clang-14 \
      -DUPD_FUZZ=ON -DUPD_SANITIZE=address,undefined -DUPD_BUILD_TESTS=OFF -DUPD_BUILD_BENCH=OFF \
      "${launcher[@]}" >/dev/null
# fuzz_bag and fuzz_compressed_depth exist only with the ROS 1 packages (scripts/setup.sh
# installs them).
# fuzz_classifier only with OpenCV's ml module (libopencv-ml-dev).
built="$(cmake --build "$BUILD" --target help)"
for optional in "bag:no ROS 1 packages" "compressed_depth:no ROS 1 packages" \
                "classifier:no OpenCV ml module"; do
  t="${optional%%:*}"
  if [[ " ${TARGETS[*]} " == *" $t "* ]] && ! grep -q "\bfuzz_$t\b" <<<"$built"; then
    echo "fuzz: $t: not built (${optional#*:}): left out"
    TARGETS=($(printf '%s\n' "${TARGETS[@]}" | grep -vx "$t"))
  fi
done
cmake --build "$BUILD" -j"${UPD_JOBS:-$(nproc)}" --target fuzz_seeds \
      $(printf 'fuzz_%s ' "${TARGETS[@]}")

seeds="$BUILD/seeds"
rm -rf "$seeds"
"$BUILD/tests/fuzz/fuzz_seeds" "$seeds"
mkdir -p "$seeds/ini" "$seeds/rawlog"
cp "$UPD_ROOT"/config/*.ini "$seeds/ini/"
if [ -d "$SHARED" ]; then
  for ext in pcd ply xyz; do
    find "$SHARED" -name "*.$ext" -size -512k -exec cp {} "$seeds/$ext/" \; 2>/dev/null || true
  done
  find "$SHARED" -name "*.bin" -size -512k -exec cp {} "$seeds/kitti_bin/" \; 2>/dev/null || true
  while IFS= read -r f; do
    out="$seeds/rawlog/$(basename "$f")"
    gzip -dc "$f" >"$out" 2>/dev/null || cp "$f" "$out"
  done < <(find "$SHARED" -name "*.rawlog" -size -256k)
else
  echo "fuzz: $SHARED not found: seeds from generated data only"
fi

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
failed=()
for t in "${TARGETS[@]}"; do
  corpus="$BUILD/corpus/$t"
  mkdir -p "$corpus" "$BUILD/crashes" "$seeds/$t"
  echo "fuzz: $t for ${SECS} s"
  repeatable=()
  [ -n "${UPD_FUZZ_RUNS:-}" ] && repeatable+=(-runs="$UPD_FUZZ_RUNS")
  [ -n "${UPD_FUZZ_SEED:-}" ] && repeatable+=(-seed="$UPD_FUZZ_SEED")
  # MRPT reads a string's length (32 bits) from the stream and allocates it before the bytes
  # are found missing: a corrupt length costs up to 4 GiB for a moment, then the object is
  # damage (docs/RELIABILITY.md, "Fuzzing"). The rawlog target may go that far, no further.
  limits=(-rss_limit_mb=2048)
  [ "$t" = rawlog ] && limits=(-rss_limit_mb=6144 -malloc_limit_mb=4200)
  if ! "$BUILD/tests/fuzz/fuzz_$t" -max_total_time="$SECS" -timeout=20 "${limits[@]}" \
        "${repeatable[@]}" \
        -print_final_stats=1 -artifact_prefix="$BUILD/crashes/$t-" "$corpus" "$seeds/$t" \
        $( [ -d "$UPD_ROOT/tests/fuzz/regressions/$t" ] && echo "$UPD_ROOT/tests/fuzz/regressions/$t") \
        >"$BUILD/fuzz_$t.log" 2>&1; then
    failed+=("$t")
    tail -40 "$BUILD/fuzz_$t.log"
    echo "fuzz: $t FAILED; replay: $BUILD/tests/fuzz/fuzz_$t $BUILD/crashes/$t-*"
  else
    grep -E "stat::number_of_executed_runs|cov:" "$BUILD/fuzz_$t.log" | tail -2 | tr '\n' ' '
    echo
  fi
done
if ((${#failed[@]})); then
  echo "fuzz: crashes in: ${failed[*]}"
  exit 1
fi
echo "fuzz: ${TARGETS[*]}: no crash in ${SECS} s each"
