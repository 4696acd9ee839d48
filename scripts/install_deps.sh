#!/usr/bin/env bash
# Installs everything photo2nerf needs to build, test and run, from Debian 12's packages.
# Idempotent: when every package is already installed it only checks and returns (no apt-get update).
# Works as root or, for another user, through sudo.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  colmap                                   # structure from motion (the `colmap` program)
  libeigen3-dev libopencv-dev libtbb-dev
  libopenimageio-dev openimageio-tools
  catch2 nlohmann-json3-dev libcli11-dev zlib1g-dev
  libsqlite3-dev                           # COLMAP's database: descriptors read, matches written
  libmetis-dev                             # the photos cut into clusters mapped apart on Slurm
  libmeshoptimizer-dev libtinygltf-dev     # the exported mesh: simplified, written as glTF
  libopenvdb-dev libblosc-dev libboost-dev      # marching cubes (OpenVDB's headers need Boost's)
  libassimp-dev                            # tests: an independent reader of our PLY and OBJ files
  libjpeg-dev                              # tests: writes a CMYK JPEG
  chromium fonts-dejavu-core               # tests: the report and viewer pages opened in a real browser
  slurm-client munge                       # --run.scheduler slurm: sbatch, squeue, scancel
  slurmctld slurmd                         # tests: a one-machine Slurm cluster (scripts/local_slurm.sh)
)
# The viewer page is bundled at build time with npm (viewer/package-lock.json): Debian's Node.js and npm, unless the
# machine has its own.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then packages+=(nodejs npm); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages already installed"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install_deps: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "install_deps: installing ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
