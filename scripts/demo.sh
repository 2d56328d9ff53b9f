#!/usr/bin/env bash
# Quick start, command 1: set up, build, and run the main job on data the project generates:
# a simulated Dune run through the mixed world (ramp, rocks, step, ditch) recorded as an MRPT
# rawlog, played back into fused traversability maps and scored against the world's truth.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

OUT="${1:-$UPD_ROOT/out/demo}"
mkdir -p "$OUT"
UPD="$UPD_BUILD/apps/upd/upd"
"$UPD" simulate --world mixed --output "$OUT/mixed.rawlog"
"$UPD" playback "$OUT/mixed.rawlog" --config "$UPD_ROOT/config/dune-kinect.ini" \
  --poses "$OUT/mixed.gt.tum" --output "$OUT/maps"
echo "demo: maps in $OUT/maps (map.png, map.tif, map.pgm/.yaml, map_cost.pgm/.yaml, map.ot/.bt,"
echo "      map_traversability.ot, map.3Dscene, summary.json)"
