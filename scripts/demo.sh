#!/usr/bin/env bash
# The main job: install what is missing, build, and render the built-in plaza under the built-in
# clear sky into out/demo/. Extra arguments go to `dynsky render` (e.g. --spp 256 --res 1920x1080).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
mkdir -p out/demo
build/cli/dynsky render builtin --res 960x540 --spp 64 --out out/demo/plaza.exr "$@"
echo "demo: open out/demo/plaza.png (linear HDR in out/demo/plaza.exr)"
