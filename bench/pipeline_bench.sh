#!/usr/bin/env bash
# Issue 2's figures: the wall time of a no-op `photo2nerf run` (every stage fresh) and of the ingest stage on a
# photo folder, each the median of N runs. Build first (scripts/test.sh or scripts/demo.sh).
# Usage: bench/pipeline_bench.sh [PHOTOS (default ../shared/data/fox/images)] [RUNS (default 5)] [WORKSPACE]
# With WORKSPACE (a complete earlier run on PHOTOS, e.g. through COLMAP), the no-op rerun covers every stage;
# without it, a new workspace is made with the stages up to ingest.
set -euo pipefail
cd "$(dirname "$0")/.."
photos=${1:-../shared/data/fox/images}
runs=${2:-5}
bin=build/cli/photo2nerf
[ -x "$bin" ] || { echo "build first: $bin is missing" >&2; exit 1; }
[ -d "$photos" ] || { echo "no photo folder $photos" >&2; exit 1; }
ws=${3:-}
scope=()
if [ -z "$ws" ]; then
  scope=(--until ingest)
  ws=$(mktemp -d)/ws
  trap 'rm -rf "$(dirname "$ws")"' EXIT
  "$bin" run "$photos" -w "$ws" --until ingest --run.progress none > /dev/null 2>&1
fi

median() { sort -g | awk '{v[NR]=$1} END {print (NR%2 ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2)}'; }
seconds() { local start end; start=$(date +%s.%N); "$@" > /dev/null 2>&1; end=$(date +%s.%N); awk -v s="$start" -v e="$end" 'BEGIN {print e - s}'; }

"$bin" status -w "$ws"
noop=$(for _ in $(seq "$runs"); do seconds "$bin" run -w "$ws" "${scope[@]}" --run.progress none; done | median)
ingest_cmd=$(for _ in $(seq "$runs"); do seconds "$bin" ingest -w "$ws" --force --run.progress none; done | median)
# The stage's own time, as its manifest records it (without process start-up and cache-key hashing).
ingest_stage=$(for _ in $(seq "$runs"); do
  "$bin" ingest -w "$ws" --force --run.progress none > /dev/null 2>&1
  grep -o '"wall_seconds": [0-9.e-]*' "$ws/00_ingest/manifest.json" | awk '{print $2}'
done | median)
count=$(ls "$ws/00_ingest/images" | wc -l)
printf 'photos: %s (%s images, %s MB)\n' "$photos" "$count" "$(du -sm "$photos" | cut -f1)"
printf 'no-op run (every stage above fresh), median of %s: %.3f s\n' "$runs" "$noop"
printf 'ingest --force command, median of %s: %.3f s\n' "$runs" "$ingest_cmd"
printf 'ingest stage itself (manifest wall_seconds), median of %s: %.3f s\n' "$runs" "$ingest_stage"
