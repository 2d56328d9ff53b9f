#!/usr/bin/env bash
# The paper reproduced: every figure and number of docs/RESULTS.md, regenerated with the `upd`
# commands (scene, analyze, baseline, render, histogram, evaluate) and formatted by
# scripts/results_report.py from their outputs. Run after the build:
#
#   scripts/results.sh [--output DIR] [--build DIR] [--data DIR] [--quick]
#
#   --output DIR  where RESULTS.md and figures/results/ go (default: docs)
#   --build DIR   the CMake build folder holding apps/upd/upd (default: build)
#   --data DIR    the real sensor data (default: ../shared/data beside the repository, or
#                 $UPD_SHARED_DATA_DIR); its parts are skipped, with a message, when it is absent
#   --quick       coarser scenes, smaller images, one real frame, no evaluation: a check that
#                 the whole chain works (the test suite runs it), not the published numbers
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/docs"
BUILD="$ROOT/build"
DATA="${UPD_SHARED_DATA_DIR:-$ROOT/../shared/data}"
QUICK=0
while [ $# -gt 0 ]; do
  case "$1" in
    --output) OUT="$2"; shift 2 ;;
    --build) BUILD="$2"; shift 2 ;;
    --data) DATA="$2"; shift 2 ;;
    --quick) QUICK=1; shift ;;
    -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "results.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

UPD="${UPD:-$BUILD/apps/upd/upd}"
[ -x "$UPD" ] || { echo "results.sh: $UPD not found: build first (cmake --build $BUILD --target upd)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "results.sh: python3 is needed to format RESULTS.md" >&2; exit 1; }

FIG_REL="figures/results"
WORK="$(mktemp -d "${TMPDIR:-/tmp}/upd-results.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
# Everything is made in a staging folder and moved into OUT at the end: a failed run leaves
# OUT as it was.
STAGE="$WORK/stage"
FIG="$STAGE/$FIG_REL"
mkdir -p "$FIG" "$WORK/data" "$OUT"
CONFIG="$ROOT/config"

if [ "$QUICK" = 1 ]; then
  SPACING=0.02; RAMP_SPACING=0.04; SIZE=640x450; HSIZE=640x400
else
  SPACING=0.01; RAMP_SPACING=0.01; SIZE=880x600; HSIZE=880x520
fi
say() { printf 'results: %s\n' "$*"; }
run() { "$UPD" "$@" > /dev/null; }  # the commands' own one-line summaries are not needed here
render() { local in="$1" png="$2"; shift 2; run render "$in" --output "$FIG/$png" --size "$SIZE" "$@"; }

# Case study 1: the paper's corner (two perpendicular 1 x 1 m planes), scored exactly as the
# paper computes it: every point, no pre-processing, the exact (brute-force-equal) path.
say "case study 1: the corner"
cat > "$WORK/corner.ini" <<EOF
[PreprocessParams]
voxel_enabled = false
outlier_enabled = false
[UpdParams]
method = exact
EOF
run scene corner --spacing-m "$SPACING" --output "$WORK/corner.ply"
for d in 0.1 0.3 0.5 1.0; do
  run analyze "$WORK/corner.ply" --config "$WORK/corner.ini" --radius-m "$d" \
    --output "$WORK/corner-$d.ply" --stats-json "$WORK/corner-$d.json"
done
# The same at d_m = 1.0 with normals from the 4-neighbourhood only (exact planes up to the
# edge): what separates the PCA normals' rounding of the edge from the descriptor itself.
run analyze "$WORK/corner.ply" --config "$WORK/corner.ini" --radius-m 1.0 \
  --normal-radius-m "$(python3 -c "print(1.5 * $SPACING)")" --output "$WORK/corner-ideal-1.0.ply"
# The same file with its viewpoint removed: the origin falls back to (0, 0, 0), in the wall.
python3 "$ROOT/scripts/results_report.py" --strip-origin "$WORK/corner.ply" "$WORK/corner-noorigin.ply"
for d in 0.1 1.0; do
  run analyze "$WORK/corner-noorigin.ply" --config "$WORK/corner.ini" --radius-m "$d" \
    --output "$WORK/corner-noorigin-$d.ply"
done
for d in 0.1 0.5 1.0; do
  render "$WORK/corner-$d.ply" "corner-zeta-$d.png" --title "corner, d_m = $d m: zeta" \
    --view-from 3,2.2,1.8 --look-at 0.45,0.5,0.3
done
render "$WORK/corner-0.1.ply" corner-normals-0.1.png --color label --normals \
  --title "corner, d_m = 0.1 m: label and normals" --view-from 3,2.2,1.8 --look-at 0.45,0.5,0.3
run histogram "$WORK/corner.ply" --config "$WORK/corner.ini" --radii 0.3,1.0 --bins 30 \
  --size "$HSIZE" --title "corner: zeta at d_m = 0.3 and 1.0 m" --output "$FIG/corner-histogram.png"

# Fig. 5: the 20 deg ramp, UPD against the roughness index, both at d_m = 0.5 m with the
# default pre-processing (2 cm voxels, outlier filter).
say "Fig. 5: the 20 deg ramp, UPD and roughness index"
run scene ramp --spacing-m "$RAMP_SPACING" --output "$WORK/ramp.ply"
run analyze "$WORK/ramp.ply" --radius-m 0.5 --output "$WORK/ramp-upd.ply" --stats-json "$WORK/ramp-upd.json"
run baseline "$WORK/ramp.ply" --radius-m 0.5 --output "$WORK/ramp-roughness.ply" \
  --stats-json "$WORK/ramp-roughness.json"
RAMP_VIEW=(--view-from -1.2,-5.8,3.6 --look-at 1.0,0,0.2)
render "$WORK/ramp-upd.ply" ramp-zeta.png --title "20 deg ramp, d_m = 0.5 m: zeta" "${RAMP_VIEW[@]}"
render "$WORK/ramp-upd.ply" ramp-upd-label.png --color label \
  --title "20 deg ramp: UPD label (zeta < 0.95 or slope > 25 deg)" "${RAMP_VIEW[@]}"
render "$WORK/ramp-roughness.ply" ramp-roughness-label.png --color label \
  --title "20 deg ramp: roughness index label (> 0.05 m)" "${RAMP_VIEW[@]}"

# Real frames from ../shared/data (see its SOURCES.md for each file's frame and up vector).
# name|file|up|config|d_m|extra analyze options|camera (from;at, in the file's frame)|what
# A camera frame is seen from just behind and above the sensor, as the camera saw it.
FRAMES=(
  "office1|pcl/office1.pcd|0,-1,0|dune-kinect.ini|0.5||0,-1.0,-3.6;0,0.3,3.0|Kinect, office (level camera)"
  "bottles|pcl-data/region_growing_rgb_tutorial.pcd|0.06,-0.85,-0.53|dune-kinect.ini|0.5||0,-0.5,-2.6;0,0.2,2.2|Kinect, floor with bottles (camera 32 deg down)"
  "lab|rtabmap/rgbd/depth/17.png|0,0,1|dune-kinect.ini|0.5|--intrinsics DATA/rtabmap/rgbd/calib/17.yaml|-2.8,0,2.6;2.8,0,0.4|Kinect on a robot, lab (robot frame)"
  "mug|pcl/table_scene_mug_stereo_textured.pcd|0.02,-0.84,-0.55|dune-kinect.ini|0.2|--voxel-m 0.005|0,-0.8,-0.9;0,0.25,1.3|textured-light stereo, tabletop with a mug"
  "campus|fast_gicp/251370668.pcd|0,0,1|lidar.ini|1.0||-22,-16,16;3,0,-2|rotating LiDAR, outdoor campus"
  "hillside|pcl-data/samp11-utm.pcd|0,0,1|lidar.ini|3.0|--knn 16 --no-preprocess||airborne laser scan, hillside (ISPRS sample 11)"
)
[ "$QUICK" = 1 ] && FRAMES=("${FRAMES[0]}")
: > "$WORK/frames.txt"
if [ ! -d "$DATA" ]; then
  say "SKIPPED the real frames: no shared data at $DATA (give --data DIR)"
else
  for spec in "${FRAMES[@]}"; do
    IFS='|' read -r name file up cfg d extra cam what <<< "$spec"
    view=(); normals=(--normals)
    [ -n "$cam" ] && view=(--view-from "${cam%;*}" --look-at "${cam#*;}")
    [ "$cfg" = lidar.ini ] && normals=()  # at this density the segments hide the points
    if [ ! -f "$DATA/$file" ]; then say "SKIPPED $name: $DATA/$file is missing"; continue; fi
    say "real data: $name ($file)"
    # shellcheck disable=SC2086  # extra holds several options
    run analyze "$DATA/$file" --config "$CONFIG/$cfg" --up "$up" --radius-m "$d" ${extra//DATA/$DATA} \
      --output "$WORK/data/$name.ply" --stats-json "$WORK/data/$name.json"
    # Seen from behind the sensor (the origin of a camera frame), upright along up.
    render "$WORK/data/$name.ply" "$name-zeta.png" --up "$up" "${view[@]}" --title "$name, d_m = $d m: zeta"
    render "$WORK/data/$name.ply" "$name-label.png" --up "$up" "${view[@]}" --color label "${normals[@]}" \
      --title "$name: label${normals:+ and normals}"
    if python3 "$ROOT/scripts/results_report.py" --has-colour "$WORK/data/$name.ply"; then
      render "$WORK/data/$name.ply" "$name-rgb.png" --up "$up" "${view[@]}" --color rgb --title "$name: camera colour"
    fi
    printf '%s|%s|%s|%s|%s|%s\n' "$name" "$file" "$up" "$cfg" "$d" "$what" >> "$WORK/frames.txt"
  done
  if [ -f "$DATA/pcl-data/samp11-utm-ground.pcd" ] && grep -q '^hillside|' "$WORK/frames.txt"; then
    # The bare-earth reference subset, read through the same pre-processing: the truth.
    run analyze "$DATA/pcl-data/samp11-utm-ground.pcd" --no-preprocess --knn 16 \
      --output "$WORK/data/hillside-ground.ply"
  fi
fi

# The labelled evaluation, when this build has `upd evaluate`.
EVAL_STATUS="absent"
if "$UPD" help | grep '^  evaluate ' > /dev/null; then
  if [ "$QUICK" = 1 ]; then
    EVAL_STATUS="quick"
  else
    say "labelled evaluation: upd evaluate"
    if "$UPD" evaluate --output "$FIG/evaluation" > "$WORK/evaluate.log" 2>&1; then
      EVAL_STATUS="done"
    else
      EVAL_STATUS="failed"
      say "upd evaluate FAILED: $(tail -n 1 "$WORK/evaluate.log")"
    fi
  fi
else
  say "no labelled evaluation: this build's upd has no 'evaluate' command"
fi

python3 "$ROOT/scripts/results_report.py" --work "$WORK" --figures "$FIG_REL" --out "$STAGE" \
  --eval "$EVAL_STATUS" --quick "$QUICK" --data "$DATA"
COUNT="$(find "$FIG" -type f | wc -l)"
rm -rf "${OUT:?}/$FIG_REL"
mkdir -p "$(dirname "$OUT/$FIG_REL")"
mv "$FIG" "$OUT/$FIG_REL"
mv "$STAGE/RESULTS.md" "$OUT/RESULTS.md"
say "wrote $OUT/RESULTS.md and $COUNT files in $OUT/$FIG_REL"
