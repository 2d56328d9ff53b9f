#!/bin/sh
# Regenerates the shipped learned classifier share/models/traversability.yml.gz with `upd train`
# from data the project generates itself: the training split of the generated scenes and
# simulated Kinect views (docs/EVALUATION.md). Random trees were picked by measurement (held-out
# F1 and AUC against boosting and an SVM: `upd train --model rtrees,boost,svm`). The held-out
# scores are printed and kept in share/models/traversability.log.
# usage: scripts/train-classifier.sh [BUILD_DIR]   (default: build)
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
upd="${1:-$root/build}/apps/upd/upd"
[ -x "$upd" ] || { echo "train-classifier.sh: $upd not found (build the upd target first)" >&2; exit 1; }
"$upd" train --no-shared --model rtrees --trees 60 --max-depth 12 \
  --output "$root/share/models/traversability.yml.gz" | tee "$root/share/models/traversability.log.tmp"
mv "$root/share/models/traversability.log.tmp" "$root/share/models/traversability.log"
