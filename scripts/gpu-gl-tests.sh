#!/usr/bin/env bash
# The GL tests from the GPU bundle (docs/gpu.md), as `ctest -L gl` runs them in the build tree:
# each test binary of gl-tests.txt once, with that binary's `gl` tests as its --gtest_filter,
# JOBS binaries at a time (default: the number of cores). Writes DIR/<binary>.xml (GoogleTest XML),
# .log and .rc; prints one line per binary. Exit 0 when every binary passed, 1 otherwise.
# Runs from the bundle folder (scripts/gpu-bundle.sh copies it there): bundle/gpu-gl-tests.sh DIR
set -uo pipefail
export PATH="${PATH:-/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin}"
here=$(cd "$(dirname "$0")" && pwd)
if [[ $# -ne 1 || ! -f "$here/gl-tests.txt" ]]; then
  echo "usage: BUNDLE/gpu-gl-tests.sh DIR (from a bundle made by scripts/gpu-bundle.sh)" >&2
  exit 2
fi
out=$1
mkdir -p "$out" || exit 2
parallel=${JOBS:-$(nproc)}

one() {
  local bin=$1 filter=$2
  "$here/run" "$bin" --gtest_filter="$filter" --gtest_output="xml:$out/$bin.xml" >"$out/$bin.log" 2>&1
  local rc=$?
  echo "$rc" >"$out/$bin.rc"
  echo "$bin: $(grep -m1 -E '^\[  (PASSED|FAILED)  \]' "$out/$bin.log" || echo 'no result line') (exit $rc)"
}

while IFS=$'\t' read -r bin count filter; do
  [[ -z "$bin" || "$bin" == \#* ]] && continue
  while (($(jobs -rp | wc -l) >= parallel)); do wait -n; done
  one "$bin" "$filter" &
done <"$here/gl-tests.txt"
wait

status=0
for f in "$out"/*.rc; do [[ "$(cat "$f")" == 0 ]] || status=1; done
exit $status
