#!/usr/bin/env bash
# Runs a GUI test binary under a virtual X server. Exit 77 (CTest's skip code here) when xvfb-run
# or xdotool is missing; scripts/setup.sh installs both, so on CI and dev machines it runs.
command -v xvfb-run >/dev/null 2>&1 || { echo "SKIP: xvfb-run is not installed (scripts/setup.sh)"; exit 77; }
command -v xdotool >/dev/null 2>&1 || { echo "SKIP: xdotool is not installed (scripts/setup.sh)"; exit 77; }
exec xvfb-run -a -s "-screen 0 1280x800x24" "$@"
