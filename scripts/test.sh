#!/usr/bin/env bash
# Sets everything up and runs all tests: installs the Debian packages, builds (Release, warnings as errors),
# and runs every test with CTest. Safe to run again: the build is incremental.
#   scripts/test.sh              the normal build, in build/
#   scripts/test.sh --sanitize   every test under AddressSanitizer + UndefinedBehaviorSanitizer (clang), in build-sanitize/
#   scripts/test.sh --tsan       the training and rendering tests under ThreadSanitizer (clang), in build-tsan/
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
# The sanitizer builds use clang (its ignore list keeps Eigen's kernels uninstrumented, see
# tests/sanitizer_ignorelist.txt) and its runtime libraries.
clang_build() {  # clang_build DIR SANITIZERS [EXTRA CMAKE ARGS...]
  if ! dpkg-query -W -f='${Status}' clang libclang-rt-14-dev 2>/dev/null | grep -q "install ok installed"; then
    ${SUDO:-} apt-get install -y -qq --no-install-recommends clang libclang-rt-14-dev
  fi
  local dir=$1 sanitizers=$2
  shift 2
  cmake -S . -B "$dir" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DP2N_BUILD_TESTS=ON \
    -DCMAKE_CXX_FLAGS="-fsanitize=$sanitizers -fno-omit-frame-pointer $*" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=$sanitizers"
  cmake --build "$dir" -j"$(nproc)"
}

case "${1:-}" in
  --sanitize)  # every test under AddressSanitizer and UndefinedBehaviorSanitizer
    clang_build build-sanitize address,undefined -fno-sanitize-recover=undefined \
      -fsanitize-ignorelist="$PWD/tests/sanitizer_ignorelist.txt"
    ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
      ctest --test-dir build-sanitize -j"$(nproc)" --output-on-failure --timeout 3600
    exit 0 ;;
  --tsan)  # the tests that train and render (TBB's threads) under ThreadSanitizer
    clang_build build-tsan thread
    TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" ctest --test-dir build-tsan -j"$(nproc)" \
      --output-on-failure --timeout 3600 -R "train|render|occupancy|rays|resum|sphere|gradient|image"
    exit 0 ;;
  "") ;;
  *) echo "usage: scripts/test.sh [--sanitize | --tsan]" >&2; exit 2 ;;
esac

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DP2N_WERROR=ON -DP2N_BUILD_TESTS=ON
cmake --build build -j"$(nproc)"
ctest --test-dir build -j"$(nproc)" --output-on-failure --timeout 900
