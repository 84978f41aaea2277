#!/usr/bin/env bash
# Makes data/calibration/predicted.json: the image observer's implied c (a model prediction, not
# human data) for every technique the study can draw, over stair and step at full and half
# contrast and artifacts of 5, 10 and 20 px (penumbra-observer-curve --json per technique, merged
# into one calibration.json of image-observer entries). Long: each technique renders every
# radius of the grid twice per condition; the filtered-moments techniques draw their partner on a
# map of up to 4096² texels (docs/study.md).
#   scripts/predict-calibration.sh [OUTPUT] [TECHNIQUE-SPEC...]
# A TECHNIQUE-SPEC is "pcf:pcf.kernel=grid" or "vsm"; without any, all of them
# (penumbra-observer-curve --list-techniques). Entries of other
# techniques already in OUTPUT are kept, so one technique can be re-predicted alone.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-data/calibration/predicted.json}"
shift || true
specs=("$@")
curve="${PENUMBRA_OBSERVER_CURVE:-build/study/penumbra-observer-curve}"
[[ -x "$curve" ]] || { echo "predict-calibration: $curve not built (scripts/build.sh)" >&2; exit 1; }
if [[ ${#specs[@]} -eq 0 ]]; then
  mapfile -t specs < <("$curve" --list-techniques)  # the registry's techniques the study can draw
  [[ ${#specs[@]} -gt 0 ]] || { echo "predict-calibration: $curve --list-techniques listed nothing" >&2; exit 1; }
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
grid=(--pattern stair,step --contrast 1,0.5 --artifact-px 5,10,20 --ratio-min 0.7 --ratio-max 6 --ratio-step 1.15 --seeds 3)
parts=()
for spec in "${specs[@]}"; do
  technique="${spec%%:*}"
  args=(--technique "$technique")
  if [[ "$spec" == *:* ]]; then
    IFS=',' read -ra sets <<<"${spec#*:}"
    for s in "${sets[@]}"; do args+=(--set "$s"); done
  fi
  part="$work/${spec//[:=,.]/-}.json"
  start=$SECONDS
  "$curve" "${grid[@]}" "${args[@]}" --json "$part" >"$part.log"
  echo "predict-calibration: $spec: $(tail -n 1 "$part.log") ($((SECONDS - start)) s)"
  parts+=("$part")
done
/usr/bin/python3 - "$out" "${parts[@]}" <<'PY'
import json, sys, datetime, os, re
out, parts = sys.argv[1], sys.argv[2:]
entries = [json.load(open(p))["entries"][0] for p in parts]
for e in entries:  # the part's temporary path is no part of the recipe
    e["command"] = re.sub(r"--json \S+", "--json OUT.json", e["command"])
key = lambda e: (e["technique"], e.get("kernel") or "")
if os.path.exists(out):
    new = {key(e) for e in entries}
    entries = [e for e in json.load(open(out))["entries"] if key(e) not in new] + entries
    entries.sort(key=key)
doc = {
    "schema_version": 2,
    "created_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
    "source": "image-observer predictions (a model of the observer, not human data), made by scripts/predict-calibration.sh: "
              "per technique the largest condition's c; a condition's c is the geometric mean over artifact sizes of the r / a "
              "beyond which the model's 2afc P(correct) stays below 0.82; ci95 is a percentile bootstrap over the stimuli "
              "(phase and orientation) rendered per radius, widened to contain c. Each entry's command reproduces it.",
    "entries": entries,
}
tmp = out + ".tmp"
with open(tmp, "w") as f:
    json.dump(doc, f, indent=2)
    f.write("\n")
os.replace(tmp, out)
print("wrote " + out + ": " + ", ".join("%s%s c = %.2f (%s)" % (e["technique"], (" " + e["kernel"]) if e["kernel"] else "", e["c"], e["condition"]) for e in entries))
PY
