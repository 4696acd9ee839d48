#!/usr/bin/env bash
# The splat stage's held-out score against its length: reruns the splat stage of a trained WORKSPACE (which is
# never touched: each run works on a copy) for each STEPS given and prints one line per run. A fixed number of
# steps makes a run deterministic, so that two builds or two options compare exactly at each length; STEPS 0 runs
# the workspace's time budget instead (by default the preset's, as `photo2nerf run` does: as many steps as the
# machine makes in it).
#
#   bash bench/splat_sweep.sh WORKSPACE STEPS... [-- EXTRA SPLAT OPTIONS]
#   e.g. bash bench/splat_sweep.sh /tmp/fox_ws 320 350 370 400 -- --splat.coarse 0.75
set -euo pipefail
workspace=$1
shift
counts=()
while [[ $# -gt 0 && $1 != -- ]]; do counts+=("$1"); shift; done
[[ ${1:-} == -- ]] && shift
extra=("$@")
bin=$(cd "$(dirname "$0")/.." && pwd)/build/cli/photo2nerf
[[ -f $workspace/30_train/manifest.json ]] || { echo "splat_sweep: $workspace has no trained field (30_train)" >&2; exit 1; }
copy=$(mktemp -d)
trap 'rm -rf "$copy"' EXIT
for steps in "${counts[@]}"; do
  rm -rf "${copy:?}"/*
  cp -r "$workspace"/. "$copy"/
  rm -rf "$copy"/35_splat "$copy"/40_render "$copy"/50_export "$copy"/60_report
  if [[ $steps == 0 ]]; then length=(--splat.steps 0); else length=(--splat.steps "$steps" --splat.time_budget 0); fi
  "$bin" splat -w "$copy" --force --run.progress none "${length[@]}" "${extra[@]}" > "$copy/sweep.log" 2>&1 ||
    { tail -5 "$copy/sweep.log" >&2; exit 1; }
  python3 - "$copy/35_splat/splat_report.json" "$steps" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
print(f"steps {sys.argv[2]:>5} (ran {r['steps']}): held-out PSNR {r['heldout_psnr']:.3f} dB, SSIM {r['heldout_ssim']:.4f}, "
      f"{r['splats']} splats, {r['seconds']:.1f} s, {r['seconds_per_view']:.3f} s a held-out view")
EOF
done
