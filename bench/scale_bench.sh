#!/usr/bin/env bash
# Issue 57's curve: the synthetic scene's N views (make_synthetic_scene, 320 x 240) as a folder of photos through
# every stage, each stage run alone under GNU time: its wall time and peak memory (the largest resident set of
# photo2nerf and of the programs it ran, COLMAP's among them). With `--run.scheduler slurm` among the options the
# stages run as Slurm jobs and the memory column is the submitting process's alone. A capture (a folder of photos
# or a video) in place of N runs through the same stages, its row named by the file.
# Usage: bench/scale_bench.sh OUT N|CAPTURE [N|CAPTURE ...] [-- photo2nerf options]
#   e.g. bench/scale_bench.sh /tmp/scale 100 300 -- --train.time_budget 60 --splat.time_budget 30
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: bench/scale_bench.sh OUT N|CAPTURE [N|CAPTURE ...] [-- photo2nerf options]}
shift
counts=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do counts+=("$1"); shift; done
[ $# -gt 0 ] && shift
options=("$@")
bin=$PWD/build/cli/photo2nerf
scene=$PWD/build/examples/make_synthetic_scene
[ -x "$bin" ] && [ -x "$scene" ] || { echo "build first: $bin or $scene is missing" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "needs GNU time (Debian: time)" >&2; exit 1; }
mkdir -p "$out"

stages=(ingest sfm poses train splat render export report)
header="| views |" rule="| --- |"
for stage in "${stages[@]}"; do header+=" $stage s | $stage MB |" rule+=" --- | --- |"; done
printf '%s\n%s\n' "$header" "$rule"
for n in "${counts[@]}"; do
  photos=$out/photos_$n
  if [ -e "$n" ]; then photos=$(realpath "$n") n=$(basename "$n"); fi
  ws=$out/ws_$n
  if [ ! -e "$photos" ]; then
    "$scene" "$out/scene_$n" "$n" > /dev/null
    mkdir -p "$photos"
    mv "$out/scene_$n"/*.png "$photos/"
  fi
  rm -rf "$ws"
  row="| $n |"
  for stage in "${stages[@]}"; do
    args=("$stage" -w "$ws" --run.progress none "${options[@]}")
    [ "$stage" = ingest ] && args=(ingest "$photos" -w "$ws" --run.progress none "${options[@]}")
    /usr/bin/time -f '%e %M' -o "$out/time_${n}_$stage" "$bin" "${args[@]}" > "$out/log_${n}_$stage" 2>&1 ||
      { echo "$stage failed on $n views: $out/log_${n}_$stage" >&2; exit 1; }
    read -r seconds kb < "$out/time_${n}_$stage"
    row+=$(printf ' %s | %d |' "$seconds" $((kb / 1024)))
  done
  echo "$row"
  grep -h "held-out" "$out/log_${n}_render" | tail -1
done
