#!/usr/bin/env bash
# README command 1: set up, build, and run the main job on its built-in default:
# adaptive vs fixed 2048² shadow maps for PCF and PCSS along a camera path through the default
# scene, beside the engine baselines (one 4096² map, four cascades of 2048²): frame time, texels,
# resolution and image difference into out/demo/ (report.json, frames.csv, side-by-side images,
# demo.png), and the tables on stdout.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
build/renderer/penumbra-demo --headless --output out/demo "$@"
