#!/usr/bin/env bash
# README command 2: set up, build, and run the plain suite (CTest without the `slow` label: the
# minutes a newcomer waits for; CI runs the same). SLOW=1 adds the slow tests (the coverage study of
# 160 simulated studies alone takes about 20 CPU-minutes). Under CI=true the hardening checks of
# issue 14 follow (docs/data-safety.md): every libFuzzer target for FUZZ_SECONDS (default 20,
# FUZZ_SEED 1) and the suite built with ASan + UBSan (scripts/sanitize-tests.sh). HARDENING=1 adds
# them outside CI, HARDENING=0 leaves them out in CI. Extra arguments go to the first ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --test
scripts/build.sh
args=(--preset default -j "$(nproc)")
if [[ "${SLOW:-0}" != "1" ]]; then
  args+=(-LE slow)
fi
ctest "${args[@]}" "$@"
if [[ "${HARDENING:-$([[ "${CI:-}" == "true" ]] && echo 1 || echo 0)}" == "1" ]]; then
  # Both run even when the first fails, so that one CI run reports everything; each says its time.
  status=0
  start=$SECONDS
  FUZZ_SEED="${FUZZ_SEED:-1}" scripts/fuzz.sh "${FUZZ_SECONDS:-20}" || status=1
  echo "hardening: fuzzing took $((SECONDS - start)) s (build included)"
  start=$SECONDS
  scripts/sanitize-tests.sh || status=1
  echo "hardening: the sanitized suite took $((SECONDS - start)) s (build included)"
  exit $status
fi
