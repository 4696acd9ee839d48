#!/usr/bin/env bash
# Issue 6's figures: PSNR of fit-image at 10 s, 30 s, 60 s and 2 min of training for the pe and hashgrid models
# on one fox photo downsized to 512 pixels wide and on one lego view at 200x200 (composited over white).
# Usage: bench/fit_image_bench.sh [OUT_DIR (default /tmp/fit_image_bench)] [SECONDS (default 120)]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/fit_image_bench}
seconds=${2:-120}
bin=build/cli/photo2nerf
data=${P2N_DATA_DIR:-../shared/data}
[ -x "$bin" ] || { echo "build first: $bin is missing" >&2; exit 1; }
mkdir -p "$out"
oiiotool "$data/fox/images/0001.jpg" --resize 512x0 -o "$out/fox_0001_512.png"
oiiotool "$data/lego/val/r_0.png" --resize 200x200 -o "$out/lego_val_r_0_200.png"
printf 'image,model,steps,psnr_10s,psnr_30s,psnr_60s,psnr_120s,final_psnr\n' > "$out/summary.csv"
for image in fox_0001_512 lego_val_r_0_200; do
  for model in pe hashgrid; do
    run="$out/${image}_${model}"
    rm -rf "$run"
    "$bin" fit-image "$out/$image.png" -o "$run" --fit.model "$model" --fit.time_budget "$seconds" \
      --run.progress none --run.log_level warning
    python3 - "$run/fit_report.json" "$image" "$model" >> "$out/summary.csv" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
at = r["psnr_at_seconds"]
print(",".join([sys.argv[2], sys.argv[3], str(r["steps"])] +
               ["%.2f" % at[t] if t in at else "" for t in ("10", "30", "60", "120")] + ["%.2f" % r["psnr"]]))
PY
  done
done
column -s, -t "$out/summary.csv"
