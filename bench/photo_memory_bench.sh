#!/usr/bin/env bash
# The training photos in memory or through a window (train.photo_memory, or splat.photo_memory with STAGE=splat) on a
# workspace whose poses (splats: whose field) are done: the stage alone under GNU time for each budget (MB), each
# REPEATS times in turn, with the photo2nerf options after `--`; its wall time and peak memory, the steps it made, the
# held-out PSNR and the photos in memory.
# BIN=a:b compares binaries (each budget run with each in turn; the build's by default).
# Usage: [STAGE=train|splat] [BIN=photo2nerf[:photo2nerf...]] bench/photo_memory_bench.sh WS REPEATS MB [MB...]
#        [-- options]
#   e.g. bench/photo_memory_bench.sh /tmp/ws 3 2048 256 -- --train.time_budget 60
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: bench/photo_memory_bench.sh WS REPEATS MB [MB...] [-- options]"
stage=${STAGE:-train}
case $stage in train | splat) ;; *) echo "STAGE is train or splat" >&2; exit 2 ;; esac
ws=${1:?$usage}
repeats=${2:?$usage}
shift 2
budgets=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do budgets+=("$1"); shift; done
[ $# -gt 0 ] && shift
[ ${#budgets[@]} -gt 0 ] || { echo "$usage" >&2; exit 1; }
IFS=: read -r -a bins <<< "${BIN:-$PWD/build/cli/photo2nerf}"
for bin in "${bins[@]}"; do
  [ -x "$bin" ] || { echo "build first: $bin is missing" >&2; exit 1; }
done
log=$(mktemp)
for ((run = 1; run <= repeats; ++run)); do
  for mb in "${budgets[@]}"; do
    for bin in "${bins[@]}"; do
      /usr/bin/time -f '%e %M' -o "$log.time" "$bin" "$stage" -w "$ws" --force --run.progress none \
        "--$stage.photo_memory" "$mb" "$@" > "$log" 2>&1 || { cat "$log" >&2; exit 1; }
      read -r wall kb < "$log.time"
      python3 - "$ws" "$stage" "$mb" "$run" "$wall" "$kb" "$bin" <<'PY'
import json, os, sys
ws, stage, mb, run, wall, kb, bin = sys.argv[1:]
if stage == "train":
    r = json.load(open(os.path.join(ws, "30_train", "train_report.json")))
    seconds, of = r["wall_seconds"], f" of {r['training_views']}"
else:
    r = json.load(open(os.path.join(ws, "35_splat", "splat_report.json")))
    seconds, of = r["seconds"], ""
window = r.get("training_views_in_memory")
held_out = "in memory" if r.get("heldout_views_in_memory", True) else "read at each evaluation"
print(f"{bin}: {mb} MB, run {run}: stage {wall} s, {int(kb) // 1024} MB peak; {r['steps']} steps in {seconds:.1f} s; "
      f"held-out PSNR {r['heldout_psnr']:.2f} dB ({r['heldout_views']} views); photos in memory: "
      f"{window if window is not None else 'all'}{of}; held-out photos {held_out}")
PY
    done
  done
done
rm -f "$log" "$log.time"
