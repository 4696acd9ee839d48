#!/usr/bin/env bash
# Error against run time of training: trains on DATASET for BUDGET seconds with each preset (and field) given,
# evaluating the held-out views every 15 s of training, and writes OUT/curves.csv (held-out PSNR at 15 s, 30 s,
# 60 s, 2, 5, 10 and 15 min, as far as the budget goes), OUT/<run>/metrics.csv, train_report.json and a plot
# OUT/curves.png. Peak memory (max RSS) of each run goes into OUT/<run>/time.txt. Every run trains on a copy of one
# workspace made up to its poses (OUT/ws_poses): the same cameras for each, structure from motion run once.
#
#   bash bench/train_bench.sh DATASET BUDGET OUT RUN... [-- EXTRA OPTIONS]
#   RUN is PRESET or PRESET:FIELD, e.g.  bash bench/train_bench.sh ../shared/data/lego_200/lego_200x200.npz 600 \
#                                          /tmp/bench fast default quality default:vanilla
set -euo pipefail
dataset=$1 budget=$2 out=$3
shift 3
runs=()
while [[ $# -gt 0 && $1 != -- ]]; do runs+=("$1"); shift; done
[[ ${1:-} == -- ]] && shift
extra=("$@")
here=$(cd "$(dirname "$0")/.." && pwd)
bin=$here/build/cli/photo2nerf
mkdir -p "$out"
rm -rf "$out/ws_poses"
"$bin" run "$dataset" -w "$out/ws_poses" --until poses --run.progress none > /dev/null
for run in "${runs[@]}"; do
  preset=${run%%:*} field=ngp
  [[ $run == *:* ]] && field=${run#*:}
  name=${preset}_${field}
  ws=$out/ws_$name
  rm -rf "$ws"
  cp -r "$out/ws_poses" "$ws"
  /usr/bin/time -v -o "$out/time_$name.txt" "$bin" train -w "$ws" --train.preset "$preset" --train.field "$field" \
    --train.time_budget "$budget" --train.eval_interval 15 "${extra[@]}" --run.progress none 2>&1 | grep "train:" || true
  mkdir -p "$out/$name"
  cp "$ws/30_train/metrics.csv" "$ws/30_train/train_report.json" "$out/$name/"
  mv "$out/time_$name.txt" "$out/$name/time.txt"
  grep "Maximum resident" "$out/$name/time.txt"
done
python3 "$here/bench/train_curves.py" "$out" "${runs[@]}"
