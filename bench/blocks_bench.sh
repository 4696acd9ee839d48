#!/usr/bin/env bash
# A stage run whole against by blocks (train.blocks or splat.blocks), on a workspace up to the stage's inputs: the
# stage under GNU time for each block count, rerun each time with the photo2nerf options after `--` (with
# --run.scheduler slurm the memory is the submitting process's alone).
# - train: the whole part and each block for their shares of SECONDS (the blocks after the whole part, as blocks on as
#   many machines would run at once), then the splat stage on the result; the held-out PSNR of the (composite) field
#   and of the splats.
# - splat: the splats of a trained field, each block for the same SECONDS; the held-out PSNR of the (merged) splats.
# Usage: bench/blocks_bench.sh train|splat WS SECONDS [BLOCKS...] [-- options]   e.g. bench/blocks_bench.sh splat /tmp/ws 60 1 2 4
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: bench/blocks_bench.sh train|splat WS SECONDS [BLOCKS...] [-- options]"
stage=${1:?$usage}
ws=${2:?$usage}
seconds=${3:?$usage}
shift 3
case $stage in train | splat) ;; *) echo "$usage" >&2; exit 2 ;; esac
counts=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do counts+=("$1"); shift; done
[ $# -gt 0 ] && shift
[ ${#counts[@]} -gt 0 ] || counts=(1 2)
bin=$PWD/build/cli/photo2nerf
[ -x "$bin" ] || { echo "build first: $bin is missing" >&2; exit 1; }
log=$(mktemp)
for blocks in "${counts[@]}"; do
  options=(--force --run.progress none "--$stage.time_budget" "$seconds" "--$stage.blocks" "$blocks" "$@")
  /usr/bin/time -f '%e %M' -o "$log.time" "$bin" "$stage" -w "$ws" "${options[@]}" > "$log" 2>&1 ||
    { cat "$log" >&2; exit 1; }
  read -r wall kb < "$log.time"
  if [ "$stage" = train ]; then
    "$bin" splat -w "$ws" "${options[@]}" >> "$log" 2>&1 || { cat "$log" >&2; exit 1; }
  fi
  python3 - "$ws" "$stage" "$blocks" "$wall" "$kb" <<'PY'
import json, os, sys
ws, stage, blocks, wall, kb = sys.argv[1:]
splats = json.load(open(os.path.join(ws, "35_splat", "splat_report.json")))
line = f"blocks {blocks}: stage {wall} s, {int(kb) // 1024} MB; "
if stage == "train":
    field = json.load(open(os.path.join(ws, "30_train", "train_report.json")))
    line += (f"field {field['steps']} steps in {field['wall_seconds']:.1f} s of training, held-out PSNR "
             f"{field['heldout_psnr']:.2f} dB; splats ")
line += (f"{splats['steps']} steps in {splats['seconds']:.1f} s of optimisation, {splats['splats']} splats, held-out "
         f"PSNR {splats['heldout_psnr']:.2f} dB, SSIM {splats['heldout_ssim']:.3f} ({splats['heldout_views']} views)")
print(line)
PY
  { grep -E "$stage: block [0-9]+ of" "$log" || true; } | sed 's/^/  /'
done
rm -f "$log" "$log.time"
