#!/usr/bin/env bash
# Quick start, command 2: set up, build, and run the whole test suite (ctest over gtest).
# Tests that need ../shared/data skip with a visible message when it is absent.
# In CI (CI=true), or with UPD_RELIABILITY=1, bounded reliability steps follow
# (docs/RELIABILITY.md): the fuzzers of the cloud readers and of the core pipeline for
# UPD_FUZZ_SECONDS each (default 30), and the Eigen-only libraries' tests under ASan + UBSan.
# Longer and wider: scripts/fuzz.sh SECONDS [TARGET...] and scripts/sanitize.sh (every test).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$UPD_BUILD"
ctest --output-on-failure -j"$(nproc)" "$@"
if [ "${CI:-}" = true ] || [ "${UPD_RELIABILITY:-0}" = 1 ]; then
  "$UPD_ROOT/scripts/fuzz.sh" "${UPD_FUZZ_SECONDS:-30}" pcd ply xyz kitti_bin pipeline
  UPD_SANITIZE_SCOPE=core "$UPD_ROOT/scripts/sanitize.sh"
fi
