#!/usr/bin/env bash
# The demo: installs what is needed, builds, renders the built-in synthetic scene into demo_photos/ and runs
# photo2nerf on it into demo_workspace/ (as far as the pipeline goes today), then shows the stages' status.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j"$(nproc)" --target photo2nerf make_synthetic_scene
[ -f demo_photos/ground_truth_cameras.json ] || build/examples/make_synthetic_scene demo_photos 24
build/cli/photo2nerf run demo_photos -w demo_workspace "$@"
build/cli/photo2nerf status -w demo_workspace
