#!/usr/bin/env bash
# The depth loss on captures of few photos: for each count of training views kept (poses.train_views; 0: all) and
# each depth-loss weight (train.depth; 0: off), trains DATASET for BUDGET seconds and prints the held-out PSNR of
# the train stage's final evaluation, the steps and the depth points used. OUT/views_N/depth_W/ keeps each run's
# train_report.json and log.
#
#   bash bench/depth_bench.sh DATASET BUDGET OUT VIEWS... -- WEIGHTS... [-- EXTRA TRAIN OPTIONS]
#   e.g.  bash bench/depth_bench.sh ../shared/data/fern 120 /tmp/depth 5 10 0 -- 0 0.1 1
set -euo pipefail
dataset=$1 budget=$2 out=$3
shift 3
views=() weights=()
while [[ $# -gt 0 && $1 != -- ]]; do views+=("$1"); shift; done
[[ ${1:-} == -- ]] && shift
while [[ $# -gt 0 && $1 != -- ]]; do weights+=("$1"); shift; done
[[ ${1:-} == -- ]] && shift
extra=("$@")
bin=$(cd "$(dirname "$0")/.." && pwd)/build/cli/photo2nerf
mkdir -p "$out"
printf "%-6s %-7s %-9s %-6s %s\n" views depth psnr_db steps depth_points
for n in "${views[@]}"; do
  ws=$out/ws_views_$n
  rm -rf "$ws"
  "$bin" run "$dataset" -w "$ws" --until poses --poses.train_views "$n" --run.progress none > /dev/null 2>&1
  for w in "${weights[@]}"; do
    dir=$out/views_$n/depth_$w
    mkdir -p "$dir"
    "$bin" train -w "$ws" --train.time_budget "$budget" --train.depth "$w" "${extra[@]}" --run.progress none \
      > "$dir/log.txt" 2>&1
    cp "$ws/30_train/train_report.json" "$dir/"
    python3 - "$dir" "$n" "$w" <<'PY'
import json, re, sys
d, n, w = sys.argv[1:]
r = json.load(open(d + "/train_report.json"))
points = re.findall(r"(\d+) depth points", open(d + "/log.txt").read())
print(f"{n:<6} {w:<7} {r['heldout_psnr']:<9.2f} {r['steps']:<6} {points[0] if points else '-'}")
PY
  done
done
