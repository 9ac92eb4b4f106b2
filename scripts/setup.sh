#!/usr/bin/env bash
# Installs every Debian package dynsky needs that is missing. Safe to run again: it installs
# nothing when all are present. Needs root (or sudo) only when something is missing.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config
  libembree-dev libtinygltf-dev libdraco-dev libmeshoptimizer-dev nlohmann-json3-dev libstb-dev
  libopenimageio-dev openimageio-tools libopenexr-dev
  libopencv-dev libeigen3-dev libtbb-dev
  libgtest-dev libbenchmark-dev libcli11-dev zlib1g-dev
  ffmpeg python3-matplotlib python3-numpy
  python3-torch python3-onnx
  munge slurmctld slurmd slurm-client
  clang libclang-rt-14-dev llvm
)
# clang and libclang-rt-14-dev: the libFuzzer targets (scripts/fuzz.sh; libFuzzer and clang's
# sanitizer runtimes); llvm: llvm-symbolizer, so sanitizer reports name files and lines.
# python3-torch and python3-onnx: the cloud networks' training code and its tests (NetworksTraining)
# run under /usr/bin/python3; the program itself runs the networks through OpenCV and needs neither.
# (--training is still accepted: everything is installed either way.)
# munge slurmctld slurmd slurm-client: the render-farm test (SlurmFarm) starts a single-node Slurm
# cluster of its own from them (docs/render-farm.md); dynsky itself needs none of them. Debian
# starts no daemon of theirs here without systemd; the test runs its own with its own key.
# --cycles also installs Blender (optional, large): the Cycles cross-checks in tools/cycles and
# bench/cycles_equal_error.sh call it when present; no test needs it.
for arg in "$@"; do
  if [[ $arg == --cycles ]]; then packages+=(blender); fi
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi
echo "setup: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
