#!/usr/bin/env bash
# Quick start, command 1: set up, build, and run the main job on data the project generates.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"

OUT="${1:-$UPD_ROOT/out/demo}"
mkdir -p "$OUT"
UPD="$UPD_BUILD/apps/upd/upd"
for scene in corner ramp step stairs ditch rocks; do
  "$UPD" scene "$scene" --output "$OUT/$scene.ply" --noise-m 0.002
  "$UPD" analyze "$OUT/$scene.ply" --no-preprocess --output "$OUT/$scene-upd.ply" \
    --stats-json "$OUT/$scene-upd.json"
done
echo "demo: outputs in $OUT (open the *-upd.ply files in CloudCompare or MeshLab)"
