#!/usr/bin/env bash
# README command 1: set up, build, and run the main job on its built-in default: along a short
# path through the large outdoor town (12 frames: four stations of three consecutive frames from
# the street walk to the overview), PCF and PCSS with the adaptive rule (rule-sized cascades)
# beside one fixed 2048² map, one 4096² map and four stabilized cascades of 2048² (the engine
# baseline): frame time, texels, error against a high-quality reference, thin casters, flicker
# into out/demo/ (report.json, frames.csv, crops, side-by-side images, plots), the tables on
# stdout. About 5 min on 2 cores without a GPU; `--path full` walks all 360 frames.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
mkdir -p out  # outputs never create the folders above them (docs/data-safety.md)
build/renderer/penumbra-demo --headless --output out/demo "$@"
