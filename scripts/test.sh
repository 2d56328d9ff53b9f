#!/usr/bin/env bash
# Quick start, command 2: set up, build, and run the whole test suite (ctest over gtest).
# Tests that need ../shared/data skip with a visible message when it is absent.
# In CI (CI=true), or with UPD_RELIABILITY=1, bounded reliability steps follow
# (docs/RELIABILITY.md): the fuzzers of the cloud readers, the robot config and the core
# pipeline, a rawlog object stream, a depth PNG and a ROS 1 bag for at most
# UPD_FUZZ_SECONDS each (default 90; a fixed seed and 2,000 inputs: close to repeatable), and
# under ASan + UBSan every test program (the navigation scenarios shortened, four long
# playbacks left out).
# Longer and wider: scripts/fuzz.sh SECONDS [TARGET...] and scripts/sanitize.sh (every test).
set -euo pipefail
step_start=$SECONDS
step_done() { echo "test: $1 took $((SECONDS - step_start)) s"; step_start=$SECONDS; }
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
step_done "set-up and build"
cd "$UPD_BUILD"
ctest --output-on-failure -j"$(nproc)" "$@"
step_done "the suite"
if [ "${CI:-}" = true ] || [ "${UPD_RELIABILITY:-0}" = 1 ]; then
  # Repeatable: a fixed seed and 2,000 inputs per target (well within the time).
  UPD_FUZZ_SEED="${UPD_FUZZ_SEED:-1}" UPD_FUZZ_RUNS="${UPD_FUZZ_RUNS:-2000}" \
    "$UPD_ROOT/scripts/fuzz.sh" "${UPD_FUZZ_SECONDS:-90}" pcd ply xyz kitti_bin pipeline ini rawlog depth_png bag compressed_depth
  step_done "fuzzing"
  # Every test program under ASan + UBSan + LeakSanitizer (apps/upd built instrumented), the
  # navigation scenarios shortened (NavScenarioStart.*) and nine long runs left out (a minute
  # or more each instrumented, on code the shorter cases run): the 300 m and 10,000-frame
  # playbacks, the ground-truth playback, the map merge, the full-resolution real frame
  # against the exact path, and the core's cases at d_m 1 m (the ramp's roughness index, the
  # corner band's growth, the corner at 1 m). By hand: scripts/sanitize.sh
  # (docs/RELIABILITY.md, "In CI").
  UPD_SANITIZE_SCOPE="core sim io maps mrpt_bridge nav gdal learn ros freenect apps" \
  UPD_SANITIZE_EXCLUDE="^LongRun\.|^PlaybackSoak\.|^Playback\.SimulatedRunAgreesWithGroundTruth$|^MapCommands\.MergeCropAndInfoOfSimulatedRuns$|^RealData\.FullResolutionFrameAgreesWithTheExactPath$|^Ramp\.RoughnessIndexFlagsTheSmoothRampBodyButNotTheGround$|^CornerBand\.WidensWithTheSearchRadius$|^SearchRadii/Corner\..*/1$" \
    "$UPD_ROOT/scripts/sanitize.sh"
  step_done "the sanitizer build and suite"
fi
