#!/usr/bin/env bash
# Screenshots of the participant's flow for docs/study.md, taken under Xvfb with
# data/studies/default-lab.json (practice before every round, with feedback):
#   the first instruction screen with its examples (1920x1080, the config's display: examples 1:1),
#   a practice trial's feedback (xdotool answers it), the next round's screen (xdotool answers
#   round 1 in the window: a person's session is never continued from a simulated one), and the
#   intake screen (no --participant).
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
# xdotool drives the window under one Xvfb: Space at the first screen, then F at every trial until
# the app has written the screenshot and exited.
drive() {  # drive OUT_DIR SCREEN ARGS... : runs the app, presses Space and F until it wrote the screenshot
  local out=$1 screen=$2
  shift 2
  xvfb-run -a -s "-screen 0 2560x900x24" bash -c '
    "$@" --windowed 1280x720 --iti-ms 50 --screenshot "'"$out"'" --screenshot-at '"$screen"' > "'"$out"'.log" 2>&1 &
    app=$!
    for i in $(seq 100); do grep -q "welcome screen" "'"$out"'.log" 2>/dev/null && break; sleep 0.1; done
    xdotool search --sync --name "^Penumbra study$" windowfocus --sync key space
    answered=0
    while kill -0 $app 2>/dev/null; do
      shown=$(grep -c " on screen" "'"$out"'.log" || true)
      if [ "$shown" -gt "$answered" ]; then
        xdotool search --name "^Penumbra study$" key f 2>/dev/null || true
        answered=$shown
      fi
      sleep 0.05
    done
    wait $app' _ "$@"
}
drive "$work/feedback" feedback "$exe" run --config "$cfg" --participant demo -o "$work/s2"
# The next round's screen: round 1 answered in the window (4 practice trials, 3 staircases of 10).
drive "$work/round" round "$exe" run --config "$cfg" --participant demo -o "$work/s3"
cp "$work/instructions/participant.png" docs/images/study-instructions.png
cp "$work/feedback/participant.png" docs/images/study-feedback.png
cp "$work/round/participant.png" docs/images/study-round.png
cp "$work/intake/participant.png" docs/images/study-intake.png
ls -l docs/images/study-instructions.png docs/images/study-feedback.png docs/images/study-round.png docs/images/study-intake.png
