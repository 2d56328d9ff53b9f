#!/usr/bin/env bash
# Quick start, command 2: set up, build, and run the whole test suite (ctest over gtest).
# Tests that need ../shared/data skip with a visible message when it is absent.
# In CI (CI=true), or with UPD_RELIABILITY=1, bounded reliability steps follow
# (docs/RELIABILITY.md): the fuzzers of the cloud readers, the robot config and the core
# pipeline and a rawlog object stream for at most UPD_FUZZ_SECONDS each (default 90; a fixed
# seed and 2,000 inputs, so a run is repeatable), and under ASan + UBSan the tests of the
# libraries (core, sim, io, maps, mrpt_bridge, nav, gdal, learn) and of `upd` on bad inputs.
# Longer and wider: scripts/fuzz.sh SECONDS [TARGET...] and scripts/sanitize.sh (every test).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$UPD_BUILD"
ctest --output-on-failure -j"$(nproc)" "$@"
if [ "${CI:-}" = true ] || [ "${UPD_RELIABILITY:-0}" = 1 ]; then
  # Repeatable: a fixed seed and 2,000 inputs per target (well within the time).
  UPD_FUZZ_SEED="${UPD_FUZZ_SEED:-1}" UPD_FUZZ_RUNS="${UPD_FUZZ_RUNS:-2000}" \
    "$UPD_ROOT/scripts/fuzz.sh" "${UPD_FUZZ_SECONDS:-90}" pcd ply xyz kitti_bin pipeline ini rawlog
  # The libraries and their tests under ASan + UBSan + LeakSanitizer, the navigation scenarios
  # shortened, and `upd` on the bad-input catalogue and damaged rawlogs (the other apps tests,
  # the Kinect and ROS tests: by hand; docs/RELIABILITY.md, "In CI").
  UPD_SANITIZE_SCOPE="core sim io maps mrpt_bridge nav gdal learn apps/bad_input apps/playback_damage" \
    "$UPD_ROOT/scripts/sanitize.sh"
fi
