#!/usr/bin/env bash
# COLMAP's incremental mapper against its hierarchical one (sfm.hierarchical_min_images) on the synthetic scene's
# N views (make_synthetic_scene, 320 x 240): the sfm stage alone under GNU time (wall time, peak memory of it and
# COLMAP), the time of its mapping, triangulation and bundle adjustment steps, the views registered, and the
# cameras against the scene's true ones (bench/compare_cameras). Under Slurm the feature extraction is in blocks
# and our descriptor matching with COLMAP's verification in blocks of pairs (sfm.block_images): their times, the
# merging and COLMAP's matcher after them (finding every pair verified) are printed.
# Usage: bench/mapper_bench.sh OUT N|PHOTOS [photo2nerf options]   e.g. bench/mapper_bench.sh /tmp/mapper 300
# (PHOTOS: a folder of photos with the true cameras in a transforms.json beside it, as ../shared/data/fox/images)
# MAPPERS="hierarchical" in the environment runs that mapper alone (default: "incremental hierarchical"); "slurm" is
# the hierarchical mapper's clusters as parts of the sfm stage's Slurm job (SLURM_CONF set; the stage's job and its
# array's elements: their memory is not measured, only the submitting process's). P2N in the environment names
# another photo2nerf program to measure (an earlier build's copy).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: bench/mapper_bench.sh OUT N [photo2nerf options]}
n=${2:?usage: bench/mapper_bench.sh OUT N [photo2nerf options]}
shift 2
bin=${P2N:-$PWD/build/cli/photo2nerf}
compare=$PWD/build/bench/compare_cameras
[ -x "$bin" ] && [ -x "$compare" ] || { echo "build first: $bin or $compare is missing" >&2; exit 1; }
photos=$out/photos_$n
reference=$out/scene_$n/ground_truth_cameras.json
if [ -d "$n" ]; then  # a folder of photos, its cameras' truth in the transforms.json beside it (fox's layout)
  photos=$(realpath "$n")
  reference=$(dirname "$photos")/transforms.json
  n=$(find "$photos" -maxdepth 1 -type f | wc -l)
elif [ ! -d "$photos" ]; then
  build/examples/make_synthetic_scene "$out/scene_$n" "$n" > /dev/null
  mkdir -p "$photos"
  mv "$out/scene_$n"/*.png "$photos/"
fi
mkdir -p "$out"

for mapper in ${MAPPERS:-incremental hierarchical}; do
  ws=$out/ws_${n}_$mapper
  rm -rf "$ws"
  options=(--run.progress none "$@")
  case $mapper in
    incremental) options+=(--sfm.hierarchical_min_images 0) ;;
    hierarchical) options+=(--sfm.hierarchical_min_images "$n") ;;
    slurm) options+=(--sfm.hierarchical_min_images "$n") ;;
    *) echo "unknown mapper $mapper (incremental, hierarchical or slurm)" >&2; exit 1 ;;
  esac
  "$bin" ingest "$photos" -w "$ws" "${options[@]}" > "$out/log_${n}_$mapper" 2>&1
  sfm_options=("${options[@]}")
  [ "$mapper" = slurm ] && sfm_options+=(--run.scheduler slurm)
  /usr/bin/time -f '%e %M' -o "$out/time_${n}_$mapper" "$bin" sfm -w "$ws" "${sfm_options[@]}" >> "$out/log_${n}_$mapper" 2>&1 ||
    { echo "sfm failed with the $mapper mapper: $out/log_${n}_$mapper" >&2; exit 1; }
  "$bin" poses -w "$ws" "${options[@]}" >> "$out/log_${n}_$mapper" 2>&1
  read -r seconds kb < "$out/time_${n}_$mapper"
  steps=$(python3 -c 'import json, sys
r = json.load(open(sys.argv[1]))
times = {s["step"]: s["wall_seconds"] for s in r["steps"]}
merging = sum(t for k, t in times.items() if k.startswith("merging models"))
if merging: times["merging"] = merging
steps = ", ".join(f"{k} {times[k]:.1f} s" for k in ("feature extraction", "merging features", "descriptor matching", "descriptor matching and verification", "vocabulary tree", "retrieval", "exhaustive matching", "sequential matching", "vocab_tree matching", "loop matching", "mapping", "merging", "triangulation", "bundle adjustment") if k in times)
print(steps + "; " + str(r["registered"]) + "/" + str(r["images_given"]) + " registered")' "$ws/10_sfm/sfm_report.json")
  memory="$((kb / 1024)) MB"
  [ "$mapper" = slurm ] && memory="memory in the jobs not measured"
  echo "$mapper: sfm $seconds s, $memory; $steps"
  "$compare" "$ws/20_poses/transforms.json" "$reference" | grep -E "rotations aligned|centre error"
done
