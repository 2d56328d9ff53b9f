#!/usr/bin/env bash
# `upd playback` of the demo run (scripts/demo.sh's simulated Dune run through the mixed world)
# with config/dune-kinect.ini (the paper's pre-processing: voxel grid and outlier filter) against
# the same run with config/dune-kinect-realtime.ini, in turn, in the same session: prints each
# config's median time per frame (the median over the runs of each run's median), their ratio
# against the target (no slower than 1.3x), and writes out/bench-playback.json. Run by
# scripts/bench.sh; UPD_PLAYBACK_RUNS sets the runs per config (default 3).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
UPD="$UPD_BUILD/apps/upd/upd"
OUT="$UPD_ROOT/out/bench-playback"
RUNS="${UPD_PLAYBACK_RUNS:-3}"
mkdir -p "$OUT"
[ -f "$OUT/mixed.rawlog" ] || "$UPD" simulate --world mixed --output "$OUT/mixed.rawlog" >/dev/null
for ((run = 1; run <= RUNS; ++run)); do
  for cfg in dune-kinect dune-kinect-realtime; do
    "$UPD" playback "$OUT/mixed.rawlog" --config "$UPD_ROOT/config/$cfg.ini" \
      --poses "$OUT/mixed.gt.tum" --output "$OUT/$cfg-$run" >/dev/null
  done
done
python3 - "$OUT" "$RUNS" "$UPD_ROOT/out/bench-playback.json" <<'EOF'
import json, statistics, sys
out, runs, report = sys.argv[1], int(sys.argv[2]), sys.argv[3]
target = 1.3
medians = {}
for cfg in ("dune-kinect", "dune-kinect-realtime"):
    per_run = [json.load(open(f"{out}/{cfg}-{r}/summary.json"))["timing_ms_per_frame"]["frame_median"]
               for r in range(1, runs + 1)]
    medians[cfg] = {"runs_ms": per_run, "median_ms": statistics.median(per_run)}
ratio = medians["dune-kinect"]["median_ms"] / medians["dune-kinect-realtime"]["median_ms"]
met = ratio <= target
for cfg, m in medians.items():
    print(f"  {cfg + '.ini':28s} {m['median_ms']:7.2f} ms a frame (runs: "
          + ", ".join(f"{v:.2f}" for v in m["runs_ms"]) + ")")
print(f"  [{' met  ' if met else 'NOT MET'}] upd playback, dune-kinect.ini / dune-kinect-realtime.ini"
      f"  {ratio:.3f} <= {target}")
json.dump({"configs": medians, "ratio": ratio, "target_max_ratio": target, "met": met},
          open(report, "w"), indent=2)
EOF
