#!/usr/bin/env bash
# The training photos in memory or through a window (train.photo_memory) on a workspace whose poses are done: the
# train stage alone under GNU time for each budget (MB), each REPEATS times in turn, with the photo2nerf options
# after `--`; its wall time and peak memory, the steps it trained, the held-out PSNR and the photos in memory.
# Usage: bench/photo_memory_bench.sh WS REPEATS MB [MB...] [-- options]
#   e.g. bench/photo_memory_bench.sh /tmp/ws 3 2048 256 -- --train.time_budget 60
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: bench/photo_memory_bench.sh WS REPEATS MB [MB...] [-- options]"
ws=${1:?$usage}
repeats=${2:?$usage}
shift 2
budgets=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do budgets+=("$1"); shift; done
[ $# -gt 0 ] && shift
[ ${#budgets[@]} -gt 0 ] || { echo "$usage" >&2; exit 1; }
bin=$PWD/build/cli/photo2nerf
[ -x "$bin" ] || { echo "build first: $bin is missing" >&2; exit 1; }
log=$(mktemp)
for ((run = 1; run <= repeats; ++run)); do
  for mb in "${budgets[@]}"; do
    /usr/bin/time -f '%e %M' -o "$log.time" "$bin" train -w "$ws" --force --run.progress none \
      --train.photo_memory "$mb" "$@" > "$log" 2>&1 || { cat "$log" >&2; exit 1; }
    read -r wall kb < "$log.time"
    python3 - "$ws/30_train/train_report.json" "$mb" "$run" "$wall" "$kb" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
window = r.get("training_views_in_memory")
print(f"{sys.argv[2]} MB, run {sys.argv[3]}: stage {sys.argv[4]} s, {int(sys.argv[5]) // 1024} MB peak; "
      f"{r['steps']} steps in {r['wall_seconds']:.1f} s; held-out PSNR {r['heldout_psnr']:.2f} dB "
      f"({r['heldout_views']} views); photos in memory: "
      f"{window if window is not None else 'all'} of {r['training_views']}")
PY
  done
done
rm -f "$log" "$log.time"
