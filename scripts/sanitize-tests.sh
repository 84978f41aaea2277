#!/usr/bin/env bash
# Builds the `sanitize` preset (gcc, Debug, AddressSanitizer + UndefinedBehaviorSanitizer, the
# first report ends the process; build-sanitize/) and runs its tests with the `sanitize` test
# preset (ASAN_OPTIONS, UBSAN_OPTIONS and LSAN_OPTIONS with tests/lsan.supp). The apps the e2e
# tests start are sanitized too and inherit the options.
#   scripts/sanitize-tests.sh [CTEST ARGS...]
# Without arguments the `slow`, `docs` and `slurm` labels are left out (as in CI; the docs tests
# compare the docs with what the programs print, which the plain suite checks, and under ASan their
# fits and renders would only add minutes; the Slurm test runs under a scheduler the observer-curve
# shards that study.ObserverCurveShards.* and study.predict_calibration_parallel_resume run here
# without one); give ctest arguments to choose
# (e.g. `-L unit`, `-R fuzz.replay`). SANITIZE_BUILD_JOBS sets the build's parallelism (default:
# all cores).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset sanitize >/dev/null
cmake --build --preset sanitize -j "${SANITIZE_BUILD_JOBS:-$(nproc)}"
# Mesa's DRI driver is loaded by the first GL context and unloaded (dlclose) before LeakSanitizer's
# exit check, so the driver's own allocations, still held by its globals, are reported as leaks in
# a module that is gone (every GL process: 2 x 56 bytes, no stack to suppress). Kept resident by
# LD_PRELOAD, they are reachable; verify_asan_link_order=0 (test preset) lets ASan start after it.
driver="/usr/lib/$(gcc -print-multiarch)/dri/swrast_dri.so"
if [[ -f "$driver" ]]; then
  export LD_PRELOAD="$driver${LD_PRELOAD:+ $LD_PRELOAD}"
fi
args=("$@")
if [[ ${#args[@]} -eq 0 ]]; then
  args=(-LE "slow|docs|slurm")
fi
ctest --preset sanitize -j "$(nproc)" "${args[@]}"
