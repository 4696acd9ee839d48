#!/usr/bin/env bash
# Sets everything up and runs all tests: installs the Debian packages, builds (Release, warnings as errors),
# and runs every test with CTest. Safe to run again: the build is incremental.
#   scripts/test.sh              the normal build, in build/
#   scripts/test.sh --sanitize   every test under AddressSanitizer + UndefinedBehaviorSanitizer (clang), in build-sanitize/
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
if [ "${1:-}" = "--sanitize" ]; then
  # clang, whose ignore list (tests/sanitizer_ignorelist.txt) leaves Eigen's kernels and a known oneTBB bug out.
  if ! dpkg-query -W -f='${Status}' clang libclang-rt-14-dev 2>/dev/null | grep -q "install ok installed"; then
    ${SUDO:-} apt-get install -y -qq --no-install-recommends clang libclang-rt-14-dev
  fi
  flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
  cmake -S . -B build-sanitize -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DP2N_BUILD_TESTS=ON \
    -DCMAKE_CXX_FLAGS="$flags -fsanitize-ignorelist=$PWD/tests/sanitizer_ignorelist.txt" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined"
  cmake --build build-sanitize -j"$(nproc)"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-sanitize -j"$(nproc)" --output-on-failure --timeout 3600
  exit 0
elif [ -n "${1:-}" ]; then
  echo "usage: scripts/test.sh [--sanitize]" >&2
  exit 2
fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DP2N_WERROR=ON -DP2N_BUILD_TESTS=ON
cmake --build build -j"$(nproc)"
ctest --test-dir build -j"$(nproc)" --output-on-failure --timeout 900
