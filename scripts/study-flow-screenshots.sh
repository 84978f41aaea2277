#!/usr/bin/env bash
# Screenshots of the participant's flow for docs/study.md, taken under Xvfb with
# data/studies/default-lab.json (practice before every round, with feedback):
#   the first instruction screen with its examples (1920x1080, the config's display: examples 1:1),
#   a practice trial's feedback (xdotool answers it), the next round's screen (a simulated
#   participant runs round 1 headless, the session is resumed and its last trial answered), and
#   the intake screen (no --participant).
#   scripts/study-flow-screenshots.sh [build-dir]
#     -> docs/images/study-instructions.png, study-feedback.png, study-round.png, study-intake.png
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
exe=$(realpath "$build/study/penumbra-study")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
/usr/bin/python3 - "$work/demo.json" <<'PY'
import json, sys
c = json.load(open("data/studies/default-lab.json"))
c["stopping"] = {"min_trials": 10, "max_trials": 10, "sd_below": 0.1}  # round 1 ends after a known trial, whatever is answered
json.dump(c, open(sys.argv[1], "w"), indent=1)
PY
cfg=$work/demo.json
xvfb-run -a -s "-screen 0 3200x1200x24" "$exe" run --config "$cfg" --participant demo -o "$work/s1" --windowed 1920x1080 \
  --screenshot "$work/instructions" --screenshot-at welcome >/dev/null
xvfb-run -a -s "-screen 0 2560x900x24" "$exe" run --config "$cfg" -o "$work/root" --windowed 1280x720 \
  --screenshot "$work/intake" --screenshot-at intake >/dev/null
# xdotool drives the window under one Xvfb: Space at the first screen, then an answer.
drive() {  # drive OUT_DIR SCREEN ARGS... : runs the app, presses Space and F until it wrote the screenshot
  local out=$1 screen=$2
  shift 2
  xvfb-run -a -s "-screen 0 2560x900x24" bash -c '
    "$@" --windowed 1280x720 --screenshot "'"$out"'" --screenshot-at '"$screen"' > "'"$out"'.log" 2>&1 &
    app=$!
    for i in $(seq 100); do grep -q "welcome screen" "'"$out"'.log" 2>/dev/null && break; sleep 0.1; done
    xdotool search --sync --name "^Penumbra study$" windowfocus --sync key space
    for i in $(seq 100); do grep -q "on screen" "'"$out"'.log" && break; sleep 0.1; done
    xdotool search --sync --name "^Penumbra study$" windowfocus --sync key f || true
    wait $app' _ "$@"
}
drive "$work/feedback" feedback "$exe" run --config "$cfg" --participant demo -o "$work/s2"
# Round 1 headless up to its last trial (the first row of the next round, less one), then resumed.
"$exe" run --config "$cfg" --participant demo --headless -o "$work/full" >/dev/null
last=$(awk -F, 'NR == 2 {r = $4} NR > 2 && $4 != r {print NR - 3; exit}' "$work/full/trials.csv")
"$exe" run --config "$cfg" --participant demo --headless --stop-after "$last" -o "$work/s3" >/dev/null
drive "$work/round" round "$exe" run --resume "$work/s3"
cp "$work/instructions/participant.png" docs/images/study-instructions.png
cp "$work/feedback/participant.png" docs/images/study-feedback.png
cp "$work/round/participant.png" docs/images/study-round.png
cp "$work/intake/participant.png" docs/images/study-intake.png
ls -l docs/images/study-instructions.png docs/images/study-feedback.png docs/images/study-round.png docs/images/study-intake.png
