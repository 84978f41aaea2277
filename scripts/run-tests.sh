#!/usr/bin/env bash
# README command 2: set up, build, and run every test (CTest). Under CI=true the `slow` label
# is skipped to keep the suite within CI's budget; pass extra ctest arguments after the script.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
args=(--preset default -j "$(nproc)")
if [[ "${CI:-}" == "true" ]]; then
  args+=(-LE slow)
fi
ctest "${args[@]}" "$@"
