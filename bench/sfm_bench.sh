#!/usr/bin/env bash
# Issue 3's figures: runs ingest -> sfm -> poses on a photo folder with the default options, prints the sfm
# report (registered, reprojection error, time per COLMAP step), compares the cameras with a reference
# transforms.json when one is given, then replays the same COLMAP commands bare (taken from the stage's step
# logs, on a fresh database) and prints the ratio of our stage's wall time to theirs, measured in one run.
# Usage: bench/sfm_bench.sh PHOTOS [REFERENCE_TRANSFORMS_JSON]
set -euo pipefail
cd "$(dirname "$0")/.."
photos=$1
reference=${2:-}
bin=build/cli/photo2nerf
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$bin" run "$photos" -w "$work/ws" --until ingest --run.progress none > /dev/null 2>&1
start=$(date +%s.%N)
"$bin" run -w "$work/ws" --until poses --run.progress none 2>&1 | grep -E "sfm:|poses:" | grep -v "(.*/.*)$" || true
ours=$(awk -v s="$start" -v e="$(date +%s.%N)" 'BEGIN {print e - s}')
python3 - "$work/ws/10_sfm/sfm_report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print("registered %d/%d (%.1f%%), %d points, mean reprojection error %.3f px, mean track length %.2f, "
      "axis-to-focus median %.2f deg" % (r["registered"], r["images_given"], r["registered_percent"], r["points"],
      r["mean_reprojection_error_px"], r["mean_track_length"], r.get("median_axis_to_focus_angle_deg", float("nan"))))
for step in r["steps"]:
    print("  %-22s %8.2f s" % (step["step"], step["wall_seconds"]))
PY
if [ -n "$reference" ]; then build/bench/compare_cameras "$work/ws/20_poses/transforms.json" "$reference"; fi

# The same COLMAP commands, bare: the first line of each step log is the command, as run.
bare="$work/bare"
mkdir -p "$bare"
stage="$work/ws/10_sfm.partial"
start=$(date +%s.%N)
for log in feature_extraction exhaustive_matching sequential_matching mapping bundle_adjustment undistortion; do
  file="$work/ws/10_sfm/logs/$log.log"
  [ -f "$file" ] || continue
  command=$(head -n 1 "$file" | sed 's/^\$ //' | sed "s#$stage#$bare#g")
  mkdir -p "$bare/sparse" "$bare/refined"
  step_start=$(date +%s.%N)
  eval "$command" > "$bare/$log.log" 2>&1
  printf '  bare %-22s %8.2f s\n' "$log" "$(awk -v s="$step_start" -v e="$(date +%s.%N)" 'BEGIN {print e - s}')"
done
theirs=$(awk -v s="$start" -v e="$(date +%s.%N)" 'BEGIN {print e - s}')
printf 'sfm + poses through photo2nerf: %.2f s; the bare COLMAP commands: %.2f s; ratio %.3f\n' "$ours" "$theirs" \
  "$(awk -v a="$ours" -v b="$theirs" 'BEGIN {print a / b}')"
