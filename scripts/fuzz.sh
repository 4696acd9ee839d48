#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, AddressSanitizer + UndefinedBehaviorSanitizer) and runs each for a fixed
# time on a copy of its seed corpus (tests/fuzz/corpus/TARGET), as many at once as there are cores; prints
# executions and findings per target.
# Crashing inputs are kept in build-fuzz/artifacts/. Usage: scripts/fuzz.sh [SECONDS_PER_TARGET (default 60)]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
bash scripts/install_deps.sh
if ! dpkg-query -W -f='${Status}' clang libclang-rt-14-dev 2>/dev/null | grep -q "install ok installed"; then
  ${SUDO:-} apt-get install -y -qq --no-install-recommends clang libclang-rt-14-dev
fi
flags="-O1 -gline-tables-only -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
cmake -S . -B build-fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None -DP2N_NATIVE=OFF \
  -DCMAKE_UNITY_BUILD=ON -DP2N_BUILD_TESTS=OFF -DP2N_FUZZ=ON -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" > /dev/null
targets=(colmap_database colmap_model image manifest mesh_glb model npy ply ply_write sparse_tracks splat_gltf splat_ply spz stage_job stage_reports train_report transforms video)
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]/%/_fuzz}"
mkdir -p build-fuzz/artifacts
rm -f build-fuzz/*.result

# Fuzzes one target; writes its line of the summary to build-fuzz/TARGET.result.
fuzz_target() {
  local target="$1" work log result
  work=$(mktemp -d)
  cp tests/fuzz/corpus/"$target"/* "$work"/
  log=build-fuzz/"$target".log
  if LSAN_OPTIONS=suppressions=tests/fuzz/lsan_suppressions.txt build-fuzz/tests/fuzz/"$target"_fuzz "$work" -max_total_time="$seconds" -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix=build-fuzz/artifacts/"$target"- > "$log" 2>&1; then
    result="no findings"
  else
    result="FINDING (see $log and build-fuzz/artifacts/)"
  fi
  printf '%-14s %12s executions in %ss, corpus %s: %s\n' "$target" \
    "$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | awk '{print $2}')" "$seconds" \
    "$(ls "$work" | wc -l)" "$result" > build-fuzz/"$target".result
  rm -rf "$work"
}

# Each fuzzer runs on one core: as many at once as there are cores, the summary in the targets' order.
for target in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do wait -n || true; done
  fuzz_target "$target" &
done
wait
status=0
for target in "${targets[@]}"; do
  cat build-fuzz/"$target".result
  grep -q "no findings" build-fuzz/"$target".result || status=1
done
exit $status
