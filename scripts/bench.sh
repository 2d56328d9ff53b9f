#!/usr/bin/env bash
# The benchmark in one command: set up, build, run bench/upd_bench against the PCL pipeline on
# ../shared/data and generated clouds; prints the targets met side by side with the PCL peer
# and writes out/bench.json. Extra arguments go to upd_bench (--quick skips the PCL peer).
#
# The main run keeps the OpenMP wait policy of the environment (unset: libgomp's default, the
# threads spin a while before they sleep), as `upd` runs on a robot's computer. The frame
# timings are then run again with OMP_WAIT_POLICY=passive (threads sleep at once: the setting
# for a machine shared with other jobs) into out/bench-passive.json, since the second core's
# gain depends on it. Last, `upd playback` of the demo run with the paper's config against the
# realtime one (scripts/bench-playback.sh, out/bench-playback.json); with ROS 1, the read of a
# bag against rosbag's own reader (bench/upd_bag_bench, out/bench-bag.json); the recording of
# `upd live --record` against MRPT's gzip stream in the loop thread (bench/upd_record_bench,
# out/bench-record.json).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
mkdir -p "$UPD_ROOT/out"
"$UPD_BUILD/bench/upd_bench" --data "$UPD_ROOT/../shared/data" \
  --json "$UPD_ROOT/out/bench.json" "$@"
echo
echo "The frame pipeline again with OMP_WAIT_POLICY=passive:"
OMP_WAIT_POLICY=passive "$UPD_BUILD/bench/upd_bench" --data "$UPD_ROOT/../shared/data" \
  --frames-only --json "$UPD_ROOT/out/bench-passive.json"
echo
echo "upd playback of the demo run, config/dune-kinect.ini against config/dune-kinect-realtime.ini:"
"$UPD_ROOT/scripts/bench-playback.sh"
if [ -x "$UPD_BUILD/bench/upd_bag_bench" ]; then
  echo
  echo "Reading a ROS 1 bag as upd playback RUN.bag does, against rosbag's own reader:"
  "$UPD_BUILD/bench/upd_bag_bench" --json "$UPD_ROOT/out/bench-bag.json"
fi
if [ -x "$UPD_BUILD/bench/upd_record_bench" ]; then
  echo
  echo "The recording of upd live --record, the loop thread's time a frame:"
  "$UPD_BUILD/bench/upd_record_bench" --json "$UPD_ROOT/out/bench-record.json"
fi
