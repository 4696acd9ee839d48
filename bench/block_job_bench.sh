#!/usr/bin/env bash
# A field block's job alone, as `--run.scheduler slurm` runs it: the train stage run on WS (a workspace up to its
# poses) until its blocks are cut, then block 1's job (`photo2nerf stage-job --part 1 --work block`) under GNU time,
# ROUNDS times for each photo2nerf program given, in turn (an A/B of builds on the same blocks; default: this build's).
# The train options after `--` (as --train.NAME VALUE pairs; they must include --train.blocks) make the run and the job.
# Usage: bench/block_job_bench.sh WS ROUNDS [PHOTO2NERF...] [-- train options]
#   e.g. bench/block_job_bench.sh /tmp/ws 3 /tmp/old/photo2nerf build/cli/photo2nerf -- --train.blocks 2 --train.time_budget 40
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: bench/block_job_bench.sh WS ROUNDS [PHOTO2NERF...] [-- train options]"
ws=$(realpath "${1:?$usage}")
rounds=${2:?$usage}
shift 2
programs=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do programs+=("$(realpath "$1")"); shift; done
[ $# -gt 0 ] && shift
[ ${#programs[@]} -gt 0 ] || programs=("$PWD/build/cli/photo2nerf")
resume=$ws/30_train.resume
out=$(mktemp -d)
# The whole part, stopped (Ctrl-C) once the blocks are cut: its checkpoint and blocks.json stay in the resume folder.
rm -rf "$resume" "$ws/30_train.partial"
"${programs[-1]}" train -w "$ws" --force --run.progress none "$@" > "$out/whole.log" 2>&1 &
pid=$!
while [ ! -f "$resume/blocks.json" ]; do
  kill -0 "$pid" 2>/dev/null || { cat "$out/whole.log" >&2; echo "the run ended before cutting blocks" >&2; exit 1; }
  sleep 0.2
done
kill -INT "$pid"
wait "$pid" || true
# The job file the submitting run would write: the blocks' key, the options given.
python3 - "$resume/blocks.json" "$out" "$@" > "$out/job.json" <<'PY'
import json, sys
blocks, out, args = sys.argv[1], sys.argv[2], sys.argv[3:]
config = {"run.progress": "none"}
for name, value in zip(args[::2], args[1::2]):
    for kind in (int, float, str):
        try:
            config[name.removeprefix("--")] = kind(value)
            break
        except ValueError:
            pass
print(json.dumps({"stage": "train", "key": json.load(open(blocks))["key"], "summary": out + "/summary.json",
                  "config": config}))
PY
for round in $(seq "$rounds"); do
  for program in "${programs[@]}"; do
    rm -f "$resume"/block1.json "$resume"/block1_model.bin "$resume"/checkpoint_block1.bin
    /usr/bin/time -f '%e %M' -o "$out/time" "$program" stage-job -w "$ws" --job "$out/job.json" --part 1 --work block \
      > "$out/part.log" 2>&1 || { cat "$out/part.log" >&2; exit 1; }
    read -r wall kb < "$out/time"
    steps=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["steps"])' "$resume/block1.json")
    views=$(grep -o 'block 1 of [0-9]*: [0-9]* training views' "$out/part.log" || true)
    echo "$program, round $round: $wall s, $((kb / 1024)) MB, $steps steps ($views)"
  done
done
rm -rf "$resume" "$ws/30_train.partial" "$out"
