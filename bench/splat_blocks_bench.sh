#!/usr/bin/env bash
# Splats optimised whole against by blocks (splat.blocks) on a workspace whose field is trained: the splat stage alone
# under GNU time for each block count, each block for the same budget (as blocks on as many machines would run at
# once), and the held-out PSNR of the (merged) splats. The workspace's splat stage is rerun each time, with the
# photo2nerf options after `--` (with --run.scheduler slurm the memory is the submitting process's alone).
# Usage: bench/splat_blocks_bench.sh WS SECONDS [BLOCKS...] [-- options]   e.g. bench/splat_blocks_bench.sh /tmp/ws 60 1 2 4
set -euo pipefail
cd "$(dirname "$0")/.."
ws=${1:?usage: bench/splat_blocks_bench.sh WS SECONDS [BLOCKS...]}
seconds=${2:?usage: bench/splat_blocks_bench.sh WS SECONDS [BLOCKS...]}
shift 2
counts=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do counts+=("$1"); shift; done
[ $# -gt 0 ] && shift
[ ${#counts[@]} -gt 0 ] || counts=(1 2)
bin=$PWD/build/cli/photo2nerf
[ -x "$bin" ] || { echo "build first: $bin is missing" >&2; exit 1; }
log=$(mktemp)
for blocks in "${counts[@]}"; do
  /usr/bin/time -f '%e %M' -o "$log.time" "$bin" splat -w "$ws" --force --run.progress none --splat.time_budget "$seconds" \
    --splat.blocks "$blocks" "$@" > "$log" 2>&1 || { cat "$log" >&2; exit 1; }
  read -r wall kb < "$log.time"
  python3 - "$ws/35_splat/splat_report.json" "$blocks" "$wall" "$kb" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print(f"blocks {sys.argv[2]}: {r['steps']} steps in {r['seconds']:.1f} s of optimisation, stage {sys.argv[3]} s, "
      f"{int(sys.argv[4]) // 1024} MB; {r['splats']} splats; held-out PSNR {r['heldout_psnr']:.2f} dB, "
      f"SSIM {r['heldout_ssim']:.3f} ({r['heldout_views']} views)")
PY
  { grep -E "splat: block [0-9]+ of" "$log" || true; } | sed 's/^/  /'
done
rm -f "$log" "$log.time"
