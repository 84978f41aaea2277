#!/usr/bin/env bash
# Screenshots of the study app's two views for docs/study.md, taken under Xvfb: a simulated
# participant answers the first 45 trials of data/studies/default.json headless, then the session
# is resumed in the windows and both are captured at the next stimulus.
#   scripts/study-screenshots.sh [build-dir]   -> docs/images/study-participant.png, study-admin.png
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
exe=$build/study/penumbra-study
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$exe" run --config data/studies/default.json --observer psychometric:c=3.0,beta=3.5,lapse=0.02 --headless \
  --stop-after 45 --participant demo -o "$work/session" >/dev/null
xvfb-run -a -s "-screen 0 2560x900x24" "$exe" run --resume "$work/session" --windowed 1280x720 \
  --refresh-hz 60 --screenshot "$work/shots"
cp "$work/shots/participant.png" docs/images/study-participant.png
cp "$work/shots/admin.png" docs/images/study-admin.png
ls -l docs/images/study-participant.png docs/images/study-admin.png
