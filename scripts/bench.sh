#!/usr/bin/env bash
# The benchmark in one command: set up, build, run bench/upd_bench against the PCL pipeline on
# ../shared/data and generated clouds; prints the targets met side by side with the PCL peer
# and writes out/bench.json. Extra arguments go to upd_bench (--quick skips the PCL peer).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
mkdir -p "$UPD_ROOT/out"
OMP_WAIT_POLICY=passive "$UPD_BUILD/bench/upd_bench" --data "$UPD_ROOT/../shared/data" \
  --json "$UPD_ROOT/out/bench.json" "$@"
