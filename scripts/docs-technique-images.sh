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
# Every technique of the registry (penumbra-render's --technique choices, less "all"); screen-space
# ones are those whose render ran a G-buffer pass. hard, pcf and pcss head both grids.
techniques=$("$render" --help | sed -n 's/.*--technique TEXT:{\([^}]*\)}.*/\1/p' | tr ',' ' ' | sed 's/ all$//')
[[ -n $techniques ]] || { echo "docs-technique-images: no technique list in $render --help" >&2; exit 1; }
for res in 512 2048; do
  screen=() map=()
  lit() { local png=("$work/$1-$res"/*/lit.png); echo "$1 $res=${png[0]}"; }  # pcf writes pcf-poisson/
  for t in $techniques; do
    "$render" --scene demo --technique "$t" --resolution "$res" --frames 1 --warmup 0 -o "$work/$t-$res" >/dev/null
    case $t in hard|pcf|pcss) screen+=("$(lit "$t")"); map+=("$(lit "$t")"); continue ;; esac
    if grep -q '"gbuffer"' "$work/$t-$res"/*/report.json; then screen+=("$(lit "$t")"); else map+=("$(lit "$t")"); fi
  done
  /usr/bin/python3 scripts/technique_crops.py "docs/images/screen-space-$res.png" 3 "${crop[@]}" "${screen[@]}"
  /usr/bin/python3 scripts/technique_crops.py "docs/images/map-side-$res.png" 4 "${crop[@]}" "${map[@]}"
done
ls -l docs/images/screen-space-*.png docs/images/map-side-*.png
