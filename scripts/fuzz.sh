#!/usr/bin/env bash
# Builds the libFuzzer targets (`fuzz` preset: clang, ASan + UBSan, build-fuzz/) and runs each for
# SECONDS (default 20) on one core, one after another, starting from tests/fuzz/corpus/<target>/.
# Fails on any finding: the crashing input is left in build-fuzz/findings/<target>/ (add it to the
# corpus once fixed, so fuzz_corpus_replay checks it in every normal build). New coverage inputs go
# to build-fuzz/corpus/<target>/, never into the tracked seeds.
# FUZZ_SEED=N fixes libFuzzer's seed (CI sets 1 so that a finding there replays here with the same
# command); without it each run draws a new seed, which a longer local run wants. The seed is
# printed either way.
#   [FUZZ_SEED=N] scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-20}"
shift || true
targets=("$@")
if [[ ${#targets[@]} -eq 0 ]]; then
  targets=(scene_file model_obj model_gltf study_config session_json trials_csv calibration counts_csv comma_list)
fi
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "${FUZZ_BUILD_JOBS:-$(nproc)}"
# Leaks inside the libraries listed in tests/lsan.supp (with the reasons) are not findings.
export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
seed_args=()
if [[ -n "${FUZZ_SEED:-}" ]]; then seed_args=(-seed="$FUZZ_SEED"); fi
status=0
for target in "${targets[@]}"; do
  exe="build-fuzz/tests/fuzz/fuzz_${target}"
  work="build-fuzz/corpus/${target}" findings="build-fuzz/findings/${target}"
  mkdir -p "$work" "$findings"
  log="build-fuzz/fuzz-${target}.log"
  # -rss_limit_mb / -timeout: an input that needs more than 2 GB or 10 s is a finding too.
  seed=""
  if "$exe" "$work" "tests/fuzz/corpus/${target}" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
       -rss_limit_mb=2048 -artifact_prefix="$findings/" -print_final_stats=1 "${seed_args[@]}" >"$log" 2>&1; then
    seed=$(sed -n 's/^INFO: Seed: *//p' "$log" | head -1)
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    echo "fuzz ${target}: ${execs:-?} execs in ${seconds} s (${rate:-?}/s), seed ${seed}, no findings"
  else
    seed=$(sed -n 's/^INFO: Seed: *//p' "$log" | head -1)
    echo "fuzz ${target}: FINDING with seed ${seed} (see $log and $findings/)" >&2
    tail -n 40 "$log" >&2  # the report and the input's file name, for a CI log
    status=1
  fi
done
exit $status
