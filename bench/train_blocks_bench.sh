#!/usr/bin/env bash
# The field trained whole against by blocks (train.blocks) on a workspace up to its poses: the train stage under GNU
# time for each block count, the whole part and each block for their shares of the same budget (the blocks after the
# whole part as blocks on as many machines would run at once), then the splat stage on the result; the held-out PSNR
# of the (composite) field and of the splats. The stages are rerun each time, with the photo2nerf options after `--`.
# Usage: bench/train_blocks_bench.sh WS SECONDS [BLOCKS...] [-- options]   e.g. bench/train_blocks_bench.sh /tmp/ws 120 1 2 4
set -euo pipefail
cd "$(dirname "$0")/.."
ws=${1:?usage: bench/train_blocks_bench.sh WS SECONDS [BLOCKS...]}
seconds=${2:?usage: bench/train_blocks_bench.sh WS SECONDS [BLOCKS...]}
shift 2
counts=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do counts+=("$1"); shift; done
[ $# -gt 0 ] && shift
[ ${#counts[@]} -gt 0 ] || counts=(1 2)
bin=$PWD/build/cli/photo2nerf
[ -x "$bin" ] || { echo "build first: $bin is missing" >&2; exit 1; }
log=$(mktemp)
for blocks in "${counts[@]}"; do
  /usr/bin/time -f '%e %M' -o "$log.time" "$bin" train -w "$ws" --force --run.progress none \
    --train.time_budget "$seconds" --train.blocks "$blocks" "$@" > "$log" 2>&1 || { cat "$log" >&2; exit 1; }
  read -r wall kb < "$log.time"
  "$bin" splat -w "$ws" --force --run.progress none --train.time_budget "$seconds" --train.blocks "$blocks" "$@" \
    >> "$log" 2>&1 || { cat "$log" >&2; exit 1; }
  python3 - "$ws/30_train/train_report.json" "$ws/35_splat/splat_report.json" "$blocks" "$wall" "$kb" <<'PY'
import json, sys
field, splats = (json.load(open(path)) for path in sys.argv[1:3])
print(f"blocks {sys.argv[3]}: field {field['steps']} steps in {field['wall_seconds']:.1f} s of training, stage "
      f"{sys.argv[4]} s, {int(sys.argv[5]) // 1024} MB; held-out PSNR {field['heldout_psnr']:.2f} dB; splats "
      f"{splats['steps']} steps, held-out PSNR {splats['heldout_psnr']:.2f} dB, SSIM {splats['heldout_ssim']:.3f} "
      f"({splats['heldout_views']} views)")
PY
  { grep -E "train: block [0-9]+ of" "$log" || true; } | sed 's/^/  /'
done
rm -f "$log" "$log.time"
