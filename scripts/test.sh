#!/usr/bin/env bash
# Sets everything up and runs all tests: installs the Debian packages, builds (Release, warnings as errors),
# and runs every test with CTest. Safe to run again: the build is incremental.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DP2N_WERROR=ON -DP2N_BUILD_TESTS=ON
cmake --build build -j"$(nproc)"
ctest --test-dir build -j"$(nproc)" --output-on-failure --timeout 900
