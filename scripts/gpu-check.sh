#!/usr/bin/env bash
# The GPU check (docs/gpu.md). On the device machine, from the repository root, with .gpu-bundle/
# (scripts/gpu-bundle.sh) carried:
#   scripts/gpu-check.sh --require-gpu
# Runs from the bundle: the GL tests (what `ctest -L gl` runs), the main job (penumbra-demo
# --headless --no-plot), penumbra-bench --quick (gpu_timer, then --timing wall_finish) and
# penumbra-render --technique all --resolution 512,1024,2048,4096 on the default scene, plus
# nvidia-smi and the GL renderer string. Writes $OUT/summary.txt, $OUT/check.log and
# $OUT/results.tar.gz (reports, CSVs, test XML; no per-render images), 3 files: the device tool
# brings back at most 8. Also runs here (llvmpipe) and from a copy of the bundle folder
# (bundle/gpu-check.sh), where the bundle is the script's own folder.
#   --require-gpu   exit 3 when EGL gives a software renderer (llvmpipe, softpipe) or no context
#   --budget S      seconds for the whole check; a step gets what is left (default: 420 with
#                   --require-gpu, else none)
#   --bundle DIR    the bundle (default: this script's folder if it is one, else .gpu-bundle/)
# Exit: 0 all steps passed, 1 a step failed or timed out, 2 usage, 3 software or no GL.
set -uo pipefail
export PATH="${PATH:-/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin}"
started=$(date +%s)

here=$(cd "$(dirname "$0")" && pwd)
require_gpu=0
budget=""
bundle=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --require-gpu) require_gpu=1 ;;
    --budget) budget=${2:-}; shift ;;
    --bundle) bundle=${2:-}; shift ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "gpu-check: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done
if [[ -n "$budget" && ! "$budget" =~ ^[0-9]+$ ]]; then echo "gpu-check: --budget: expected seconds, got '$budget'" >&2; exit 2; fi
[[ -z "$budget" && $require_gpu -eq 1 ]] && budget=420
if [[ -z "$bundle" ]]; then
  if [[ -f "$here/gl-tests.txt" ]]; then bundle=$here; else bundle=$(cd "$here/.." && pwd)/.gpu-bundle; fi
fi
if [[ ! -f "$bundle/gl-tests.txt" || ! -x "$bundle/run" ]]; then
  echo "gpu-check: $bundle is not a bundle (no gl-tests.txt or run); make it with scripts/gpu-bundle.sh" >&2
  exit 2
fi
bundle=$(cd "$bundle" && pwd)
OUT=${OUT:-out/gpu-check}
mkdir -p "$OUT" || exit 2
OUT=$(cd "$OUT" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/penumbra-gpu-check.XXXXXX") || exit 2
trap 'rm -rf "$work"' EXIT
log=$OUT/check.log
: >"$log"
printf 'step\tstatus\texit\tseconds\tcommand\n' >"$work/steps.tsv"

say() { echo "gpu-check: $*" | tee -a "$log"; }

# Seconds a step may take: under a budget its cap, or what is left of the budget if that is
# less; without one an hour (software GL is slow).
allowed() {
  local cap=$1
  [[ -z "$budget" ]] && { echo 3600; return; }
  local left=$((budget - ($(date +%s) - started)))
  ((left < cap)) && cap=$left
  echo $((cap > 0 ? cap : 0))
}

# step NAME CAP_S COMMAND...: runs COMMAND in $work, output to check.log and $work/NAME.log.
step() {
  local name=$1 cap=$2; shift 2
  local limit; limit=$(allowed "$cap")
  if ((limit <= 0)); then
    say "$name: skipped (budget of ${budget} s spent)"
    printf '%s\tskipped\t-\t0\t%s\n' "$name" "$*" >>"$work/steps.tsv"
    return 1
  fi
  say "$name: $* (limit ${limit} s)"
  local t0 rc status; t0=$(date +%s)
  (cd "$work" && timeout -k 10 "$limit" "$@") >"$work/$name.log" 2>&1
  rc=$?
  cat "$work/$name.log" >>"$log"
  case $rc in 0) status=ok ;; 124|137) status=timeout ;; *) status=failed ;; esac
  local dt=$(($(date +%s) - t0))
  say "$name: $status (exit $rc, ${dt} s)"
  printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$status" "$rc" "$dt" "$*" >>"$work/steps.tsv"
  [[ $rc -eq 0 ]]
}

run=$bundle/run
# The apps' default data/calibration/default.json is a path into the source tree they were built
# in (PENUMBRA_SOURCE_DIR), absent where the bundle runs: every app gets the bundle's copy.
cal=$bundle/data/calibration/default.json

# --- The GL loader: libglvnd from the system; on the device machine (no libEGL.so.1) from the
# Debian packages in the bundle, unpacked into / as the device tool's README says.
if ! ldconfig -p 2>/dev/null | grep -q 'libEGL\.so\.1 '; then
  if [[ $(id -u) -eq 0 ]] && compgen -G "$bundle/gl-debs/*.deb" >/dev/null; then
    say "no libEGL.so.1 on this machine: unpacking $(ls "$bundle"/gl-debs/*.deb | xargs -n1 basename | tr '\n' ' ')into /"
    for f in "$bundle"/gl-debs/*.deb; do dpkg -x "$f" / || say "dpkg -x $f failed"; done
    ldconfig
  else
    say "no libEGL.so.1 on this machine and no way to unpack the bundle's gl-debs/ (root and dpkg -x needed)"
  fi
fi

# --- The machine: nvidia-smi, the loader's view, EGL variables (the launcher sets them).
{
  echo "# date: $(date -u +%FT%TZ)  host: $(uname -srm)  cores: $(nproc)"
  echo "# bundle: $bundle; $(tr '\n' ';' <"$bundle/VERSION" 2>/dev/null || echo 'no VERSION')"
  echo "# nvidia-smi"
  if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,pstate --format=csv 2>&1
    nvidia-smi 2>&1
  else
    echo "nvidia-smi: not found"
  fi
  echo "# ldconfig -p: EGL / GL / NVIDIA"
  ldconfig -p 2>/dev/null | grep -E 'libEGL|libGLdispatch|libGLX|libOpenGL|libnvidia-egl|libEGL_nvidia' || echo "(none)"
  echo "# EGL vendor files"
  ls -l /usr/share/glvnd/egl_vendor.d /etc/glvnd/egl_vendor.d /usr/local/nvidia/share/glvnd/egl_vendor.d 2>&1
  echo "# environment the launcher sets"
  "$run" --print-env 2>&1
} >"$work/machine.txt"
cat "$work/machine.txt" >>"$log"

# --- GL context: one tiny render names the renderer before anything long runs.
step probe 60 "$run" penumbra-render --calibration "$cal" --technique hard --resolution 64 --width 64 --height 64 --frames 1 --warmup 0 -o "$work/probe"
renderer=$(grep -m1 '"renderer"' "$work/probe/report.json" 2>/dev/null | sed 's/.*"renderer": *"\(.*\)",*$/\1/')
software=0
if [[ -z "$renderer" ]]; then
  software=2
elif grep -qiE 'llvmpipe|softpipe|swrast|SWR' <<<"$renderer"; then
  software=1
fi

if [[ $software -eq 0 || $require_gpu -eq 0 ]] && [[ $software -ne 2 ]]; then
  # The GL tests: each binary once, filtered to what `ctest -L gl` runs (gpu-gl-tests.sh).
  step gl-tests 240 "$bundle/gpu-gl-tests.sh" "$work/gl-tests"

  # The main job, as scripts/run-main.sh runs it, without the chart (no matplotlib there).
  step demo 150 "$run" penumbra-demo --headless --no-plot --calibration "$cal" -o "$work/demo"
  # Every technique at four resolutions; report.json holds gpu_timer and wall_finish per pass.
  step render 150 "$run" penumbra-render --calibration "$cal" --technique all --resolution 512,1024,2048,4096 -o "$work/render"
  # The bench: gpu_timer on a GPU; then the wall clock (on software GL the first run already is).
  step bench 120 "$run" penumbra-bench --calibration "$cal" --quick --no-plot -o "$work/bench"
  if [[ $software -eq 0 ]]; then
    step bench-wall 120 "$run" penumbra-bench --calibration "$cal" --quick --no-plot --timing wall_finish -o "$work/bench-wall"
  fi
fi

# The cost model beside the demo's measured shadow costs (gpu_cost_model.py: a model, labelled as
# one): the note compares the GPU's measured ratios with the model's.
if [[ -f "$work/demo/report.json" ]] && command -v python3 >/dev/null; then
  python3 "$bundle/gpu_cost_model.py" "$work/demo/report.json" --json "$work/demo/cost-model.json" >"$work/demo/cost-model.txt" 2>>"$log" ||
    echo "gpu_cost_model.py failed: see check.log" >"$work/demo/cost-model.txt"
  cat "$work/demo/cost-model.txt" >>"$log"
fi

elapsed=$(($(date +%s) - started))
if command -v python3 >/dev/null; then
  python3 "$bundle/gpu_summary.py" "$work" "$software" "$renderer" "$elapsed" "$require_gpu" >"$OUT/summary.txt" 2>>"$log" ||
    echo "gpu_summary.py failed: see check.log" >>"$OUT/summary.txt"
else
  { echo "renderer: ${renderer:-none}"; echo "(no python3: steps only)"; cat "$work/steps.tsv"; } >"$OUT/summary.txt"
fi
# Results without the per-render images (lit.png, visibility.exr: tens of MB); montage kept.
tar -C "$work" --exclude='*/lit.png' --exclude='*.exr' --exclude='*.partial' -czf "$OUT/results.tar.gz" . 2>>"$log"
say "wrote $OUT/summary.txt, check.log, results.tar.gz ($(du -k "$OUT/results.tar.gz" | cut -f1) KiB) in ${elapsed} s"
cat "$OUT/summary.txt"

if [[ $software -ne 0 && $require_gpu -eq 1 ]]; then exit 3; fi
if [[ $software -eq 2 ]]; then exit 3; fi
if awk -F'\t' 'NR > 1 && $2 != "ok" { bad = 1 } END { exit !bad }' "$work/steps.tsv"; then exit 1; fi
exit 0
