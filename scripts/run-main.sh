#!/usr/bin/env bash
# README command 1: set up, build, and run the main job on its built-in default:
# render the default scene with every technique into out/ and print the timing table.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
build/renderer/penumbra-render --scene demo --technique all --output out/render "$@"
