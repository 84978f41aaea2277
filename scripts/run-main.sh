#!/usr/bin/env bash
# README command 1: set up, build, and run the main job on its built-in default: along a short
# path through the large outdoor town (12 frames: four stations of three consecutive frames from
# the street walk to the overview), PCF and PCSS with the adaptive rule (rule-sized cascades)
# beside the engine family (single maps of 1024²-8192², two stabilized cascades of 2048² and
# 4096², four of 2048²) and the sun's virtual shadow map (by the rule and the footprint, drawn
# every frame, and the rule cached): first the adaptive rule and each virtual map against the
# family's Pareto front at equal perceived difference (LDR-FLIP of the lit frames; PCSS against
# converged PCSS and the ray-traced sun), the frame observer's verdict, then at equal error (RMSE)
# (speedup and memory ratio with intervals), then frame time,
# texels, error against the reference (PCF: the same filter on 8188² cascades; PCSS: ray-traced),
# thin casters, flicker; into out/demo/ (report.json, frames.csv, crops, side-by-side images,
# plots, FLIP montages). 5.5 min on 2 quiet cores without a GPU (commit 5f5167b, docs/results/adaptive.md;
# `--no-flip` leaves out the perceived difference, `--no-virtual` the virtual maps); `--sweep` measures the
# whole engine family, `--path full` walks all 360 frames.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
mkdir -p out  # outputs never create the folders above them (docs/data-safety.md)
build/renderer/penumbra-demo --headless --output out/demo "$@"
