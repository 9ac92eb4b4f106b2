#!/usr/bin/env bash
# The main job: install what is missing, build, and render the Tower scene under a moving cloudy
# sky (procedural cumulus over a Hosek-Wilkie clear sky, Paris, 2026-06-21 16:00 UTC, its clouds
# moved every 30 s by the shipped advect-residual network, networks/models/advect_residual, under
# the default wind: from 270 degrees at 12 m/s, clouds at 1500 m) into out/demo/:
# numbered EXR/PNG frames, animation.mp4, sky.mp4 and contact_sheet.png.
# Extra arguments go to `dynsky animate` (e.g. --spp 64 --res 1280x720, --wind-from 200
# --wind-speed 8, --model paper for the paper's FlowNet + CloudNet, or --model procedural to move
# the clouds by the procedural sky's own exact motion instead).
# Rerunning resumes: finished frames are kept.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
build/cli/dynsky animate scenes/tower/tower.gltf --duration 60 --fps 0.5 --spp 16 --res 480x270 --out out/demo "$@"
echo "demo: open out/demo/animation.mp4 and out/demo/contact_sheet.png"
