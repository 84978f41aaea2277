#!/usr/bin/env bash
# The technique comparison images of docs/alternatives.md: the demo scene rendered with each
# technique at 512^2 and 2048^2 (default parameters), cropped around the sphere's shadow.
#   scripts/docs-technique-images.sh [build-dir]
#     -> docs/images/screen-space-{512,2048}.png, docs/images/map-side-{512,2048}.png
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
render=$build/renderer/penumbra-render
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
crop=(317 250 504 330)  # x y w h in the 1280x720 image
for res in 512 2048; do
  for t in hard pcf pcss edtsm edtssm erosion rbsm rpcf msm evsm; do
    "$render" --scene demo --technique "$t" --resolution "$res" --frames 1 --warmup 0 -o "$work/$t-$res" >/dev/null
  done
  lit() { local png=("$work/$1-$res"/*/lit.png); echo "$1 $res=${png[0]}"; }  # pcf writes pcf-poisson/
  /usr/bin/python3 scripts/technique_crops.py "docs/images/screen-space-$res.png" 3 "${crop[@]}" \
    "$(lit hard)" "$(lit pcf)" "$(lit pcss)" "$(lit edtsm)" "$(lit edtssm)" "$(lit erosion)"
  /usr/bin/python3 scripts/technique_crops.py "docs/images/map-side-$res.png" 4 "${crop[@]}" \
    "$(lit hard)" "$(lit pcf)" "$(lit pcss)" "$(lit rbsm)" "$(lit rpcf)" "$(lit msm)" "$(lit evsm)"
done
ls -l docs/images/screen-space-*.png docs/images/map-side-*.png
