#!/usr/bin/env bash
# The demo: installs what is needed, builds, renders the built-in synthetic scene into demo_photos/ and runs
# photo2nerf on it into demo_workspace/ (photos to report: demo_workspace/60_report/report.html), shows the
# stages' status and how close the recovered cameras are to the true ones.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j"$(nproc)" --target photo2nerf make_synthetic_scene compare_cameras
# Rendered every time (1 s): the rendering is deterministic, so unchanged photos leave every stage fresh.
build/examples/make_synthetic_scene demo_photos 24
build/cli/photo2nerf run demo_photos -w demo_workspace --train.preset fast "$@"
build/cli/photo2nerf status -w demo_workspace
echo "recovered cameras against the truth (after a similarity alignment):"
build/bench/compare_cameras demo_workspace/20_poses/transforms.json demo_photos/ground_truth_cameras.json
