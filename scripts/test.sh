#!/usr/bin/env bash
# Sets everything up and runs all tests: installs the Debian packages, builds (Release, warnings as errors),
# and runs every test with CTest. Safe to run again: the build is incremental.
#   scripts/test.sh              the normal build, in build/
#   scripts/test.sh --sanitize   every test under AddressSanitizer + UndefinedBehaviorSanitizer (clang), in build-sanitize/
#   scripts/test.sh --tsan       the training and rendering tests under ThreadSanitizer (clang), in build-tsan/, with
#                                oneTBB built for it; further arguments go to ctest instead (e.g. -E COLMAP: all
#                                but those)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
mode="${1:-}"
[ $# -gt 0 ] && shift
if [ -n "$mode" ] && [ "$mode" != "--sanitize" ] && [ "$mode" != "--tsan" ]; then
  echo "usage: scripts/test.sh [--sanitize | --tsan]" >&2
  exit 2
fi
if [ -z "$mode" ]; then
  # A unity build (a target's sources compiled a batch at a time): a clean build, as CI's, in less compiler time.
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DP2N_WERROR=ON -DP2N_BUILD_TESTS=ON -DCMAKE_UNITY_BUILD=ON
  cmake --build build -j"$(nproc)"
  ctest --test-dir build -j"$(nproc)" --output-on-failure --timeout 900
  exit 0
fi

if ! dpkg-query -W -f='${Status}' clang libclang-rt-14-dev 2>/dev/null | grep -q "install ok installed"; then
  ${SUDO:-} apt-get install -y -qq --no-install-recommends clang libclang-rt-14-dev
fi
# Builds with clang and the given sanitizer flags in the given folder.
sanitizer_build() {
  local dir="$1" flags="$2 -fno-omit-frame-pointer"
  cmake -S . -B "$dir" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DP2N_BUILD_TESTS=ON \
    -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$2"
  cmake --build "$dir" -j"$(nproc)"
}

if [ "$mode" = "--sanitize" ]; then
  # The ignore list (tests/sanitizer_ignorelist.txt) leaves Eigen's kernels and a known oneTBB bug out.
  sanitizer_build build-sanitize \
    "-fsanitize=address,undefined -fno-sanitize-recover=undefined -fsanitize-ignorelist=$PWD/tests/sanitizer_ignorelist.txt"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-sanitize -j"$(nproc)" --output-on-failure --timeout 3600
  exit 0
fi

# ThreadSanitizer sees only what is built with it: Debian's oneTBB is not, so every hand-off of its scheduler
# would look like a race. The same oneTBB version (Debian's source, from Debian's mirror) is built with
# ThreadSanitizer once and put first on the library path; its SONAME is the same, so OpenVDB uses it too.
tbb_version=2021.8.0
tbb_sha256=7e9111b8bb59c8800bf6d0b06afe7b0891937443d2dae1ee1101c8e2ede6a7ef
tbb="$PWD/build-tsan/onetbb"
if [ ! -f "$tbb/lib/libtbb.so.12" ]; then
  mkdir -p build-tsan/onetbb-src
  tarball="build-tsan/onetbb-src/onetbb_$tbb_version.orig.tar.xz"
  curl -fsSL -o "$tarball" "http://deb.debian.org/debian/pool/main/o/onetbb/onetbb_$tbb_version.orig.tar.xz"
  echo "$tbb_sha256  $tarball" | sha256sum -c --quiet
  tar -xJf "$tarball" -C build-tsan/onetbb-src
  cmake -S "build-tsan/onetbb-src/oneTBB-$tbb_version" -B build-tsan/onetbb-build -G Ninja \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DTBB_TEST=OFF -DTBBMALLOC_BUILD=OFF -DTBB_SANITIZE=thread -DCMAKE_INSTALL_PREFIX="$tbb" -DCMAKE_INSTALL_LIBDIR=lib
  cmake --build build-tsan/onetbb-build --target install -j"$(nproc)"
fi
sanitizer_build build-tsan "-fsanitize=thread"
# Suppressions (tests/tsan_suppressions.txt) cover libraries that are not built with ThreadSanitizer.
tsan_ctest() {
  LD_LIBRARY_PATH="$tbb/lib" TSAN_OPTIONS="second_deadlock_stack=1 suppressions=$PWD/tests/tsan_suppressions.txt" \
    ctest --test-dir build-tsan -j"$(nproc)" --output-on-failure --timeout 3600 "$@"
}
if [ $# -gt 0 ]; then
  tsan_ctest "$@"
else
  # The training and rendering tests: the engine's (label engine), then the stages and commands that train or render.
  status=0
  tsan_ctest -L engine || status=1
  tsan_ctest -R "^(train stage|render stage|export stage|cli: fit-image|faults: Ctrl-C)" || status=1
  exit $status
fi
