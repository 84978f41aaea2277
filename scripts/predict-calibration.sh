#!/usr/bin/env bash
# Makes data/calibration/predicted.json: the image observer's implied c (a model prediction, not
# human data) for every technique the study can draw, over stair and step at full and half
# contrast and artifacts of 5, 10 and 20 px (penumbra-observer-curve --json per technique, merged
# into one calibration.json of image-observer entries). Long: each technique renders every
# radius of the grid twice per condition; the filtered-moments techniques draw their partner on a
# map of up to 4096² texels (docs/study.md).
#   scripts/predict-calibration.sh [OPTIONS] [OUTPUT] [TECHNIQUE-SPEC...]
# A TECHNIQUE-SPEC is "pcf:pcf.kernel=grid" or "vsm"; without any, all of them
# (penumbra-observer-curve --list-techniques). Entries of other
# techniques already in OUTPUT are kept, so one technique can be re-predicted alone.
#
# Without options one process renders everything, technique after technique. With --jobs each
# technique's grid is cut into shards (penumbra-observer-curve --shard I/N --part) that GNU
# parallel runs on N slots, here or on the machines of --sshloginfile, and the parts are merged
# (penumbra-observer-curve merge) into exactly what the serial run writes (docs/cluster.md):
#   --jobs N             run the shards through GNU parallel on N slots (per machine with --sshloginfile)
#   --shards S           shards per technique (default: N; more shards lose less to a killed job)
#   --sshloginfile FILE  parallel's list of machines; each needs the same build of
#                        penumbra-observer-curve at the same path (the merge checks the version)
#                        and WORK on a file system they all share
#   --work DIR           the jobs, the joblog, the parts and their logs (default out/predict-calibration);
#                        kept, so that a killed sweep continues
#   --resume             continue the sweep in WORK: parallel --resume-failed skips the shards the
#                        joblog has as done and runs the rest, the killed and failed ones included
#   --plan               only write WORK/jobs.txt, one shell command per shard (a Slurm array runs
#                        line SLURM_ARRAY_TASK_ID + 1: scripts/slurm/predict-calibration.sbatch)
#   --merge              only merge the parts in WORK into OUTPUT (after the array)
#   --grid 'ARGS'        penumbra-observer-curve's grid options instead of the calibration's (tests, trials)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="" shards="" sshloginfile="" work="out/predict-calibration" resume=0 mode=run grid_text=""
die() { echo "predict-calibration: $*" >&2; exit 2; }
while [[ $# -gt 0 && "$1" == --* ]]; do
  case "$1" in
    --jobs) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "--jobs: expected a whole number of slots, got '${2:-}'"; jobs="$2"; shift 2 ;;
    --shards) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "--shards: expected a whole number of shards, got '${2:-}'"; shards="$2"; shift 2 ;;
    --sshloginfile) [[ -f "${2:-}" ]] || die "--sshloginfile: '${2:-}' is not a file"; sshloginfile="$2"; shift 2 ;;
    --work) [[ -n "${2:-}" ]] || die "--work: expected a directory"; work="$2"; shift 2 ;;
    --grid) [[ -n "${2:-}" ]] || die "--grid: expected penumbra-observer-curve's grid options"; grid_text="$2"; shift 2 ;;
    --resume) resume=1; shift ;;
    --plan) mode=plan; shift ;;
    --merge) mode=merge; shift ;;
    --) shift; break ;;
    *) die "$1: unknown option (see the comment at the top of $0)" ;;
  esac
done
[[ -z "$sshloginfile" || -n "$jobs" ]] || die "--sshloginfile: needs --jobs N (slots per machine)"
[[ $resume -eq 0 || -n "$jobs" ]] || die "--resume: needs --jobs N (a serial run has nothing to resume)"
[[ -z "$shards" || -n "$jobs" || "$mode" != run ]] || die "--shards: needs --jobs N, --plan or --merge"
out="${1:-data/calibration/predicted.json}"
shift || true
specs=("$@")
curve="${PENUMBRA_OBSERVER_CURVE:-build/study/penumbra-observer-curve}"
[[ -x "$curve" ]] || { echo "predict-calibration: $curve not built (scripts/build.sh)" >&2; exit 1; }
if [[ ${#specs[@]} -eq 0 ]]; then
  mapfile -t specs < <("$curve" --list-techniques)  # the registry's techniques the study can draw
  [[ ${#specs[@]} -gt 0 ]] || { echo "predict-calibration: $curve --list-techniques listed nothing" >&2; exit 1; }
fi
grid=(--pattern stair,step --contrast 1,0.5 --artifact-px 5,10,20 --ratio-min 0.7 --ratio-max 6 --ratio-step 1.15 --seeds 3)
[[ -z "$grid_text" ]] || read -ra grid <<<"$grid_text"

# The curve's arguments for one spec, into `args`.
technique_args() {
  local spec="$1" s sets
  args=(--technique "${spec%%:*}")
  if [[ "$spec" == *:* ]]; then
    IFS=',' read -ra sets <<<"${spec#*:}"
    for s in "${sets[@]}"; do args+=(--set "$s"); done
  fi
}
name_of() { local spec="$1"; echo "${spec//[:=,.]/-}"; }

# The per-technique calibration.jsons `parts` into OUTPUT, keeping OUTPUT's other techniques.
combine() {
  /usr/bin/python3 - "$out" "$@" <<'PY'
import json, sys, datetime, os, re
out, parts = sys.argv[1], sys.argv[2:]
entries = [json.load(open(p))["entries"][0] for p in parts]
for e in entries:  # the part's temporary path is no part of the recipe
    e["command"] = re.sub(r"--json \S+", "--json OUT.json", e["command"])
key = lambda e: (e["technique"], e.get("kernel") or "")
if os.path.exists(out):
    new = {key(e) for e in entries}
    entries = [e for e in json.load(open(out))["entries"] if key(e) not in new] + entries
    entries.sort(key=key)
doc = {
    "schema_version": 2,
    "created_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
    "source": "image-observer predictions (a model of the observer, not human data), made by scripts/predict-calibration.sh: "
              "per technique the largest condition's c; a condition's c is the geometric mean over artifact sizes of the r / a "
              "beyond which the model's 2afc P(correct) stays below 0.82; ci95 is a percentile bootstrap over the stimuli "
              "(phase and orientation) rendered per radius, widened to contain c. Each entry's command reproduces it.",
    "entries": entries,
}
os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
tmp = out + ".tmp"
with open(tmp, "w") as f:
    json.dump(doc, f, indent=2)
    f.write("\n")
os.replace(tmp, out)
print("wrote " + out + ": " + ", ".join("%s%s c = %.2f (%s)" % (e["technique"], (" " + e["kernel"]) if e["kernel"] else "", e["c"], e["condition"]) for e in entries))
PY
}

if [[ -z "$jobs" && "$mode" == run ]]; then  # serial: one process, technique after technique
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
  parts=()
  for spec in "${specs[@]}"; do
    technique_args "$spec"
    part="$tmp/$(name_of "$spec").json"
    start=$SECONDS
    "$curve" "${grid[@]}" "${args[@]}" --json "$part" >"$part.log"
    echo "predict-calibration: $spec: $(tail -n 1 "$part.log") ($((SECONDS - start)) s)"
    parts+=("$part")
  done
  combine "${parts[@]}"
  exit 0
fi

# Sharded: WORK/jobs.txt (one command per shard, the same list on every resume), run by GNU
# parallel or a Slurm array, then one merge per technique.
shards="${shards:-${jobs:-1}}"
mkdir -p "$work/parts"
plan="$work/jobs.txt.new"
: >"$plan"
for spec in "${specs[@]}"; do
  technique_args "$spec"
  for ((i = 0; i < shards; ++i)); do
    part="$work/parts/$(name_of "$spec").$i-of-$shards"
    printf '%q ' "$curve" "${grid[@]}" "${args[@]}" --shard "$i/$shards" --part "$part.json" >>"$plan"
    printf '> %q 2>&1\n' "$part.log" >>"$plan"
  done
done
if [[ "$mode" == plan ]]; then
  mv "$plan" "$work/jobs.txt"
  echo "predict-calibration: wrote $work/jobs.txt: $(wc -l <"$work/jobs.txt") shards"
  exit 0
elif [[ "$mode" == run ]]; then
  if [[ $resume -eq 1 ]]; then
    [[ -f "$work/joblog" ]] || die "--resume: $work/joblog does not exist; nothing to resume (run without --resume)"
    cmp -s "$plan" "$work/jobs.txt" ||
      die "--resume: $work/jobs.txt is another sweep's (other techniques, grid, shards or curve); resume it with its own options or use another --work"
  elif [[ -f "$work/joblog" ]]; then
    die "$work/joblog: a sweep was started there; --resume to continue it, or another --work (or remove $work)"
  fi
  mv "$plan" "$work/jobs.txt"
  command -v parallel >/dev/null || { echo "predict-calibration: --jobs needs GNU parallel (scripts/setup.sh installs it)" >&2; exit 1; }
  remote=()
  [[ -z "$sshloginfile" ]] || remote=(--sshloginfile "$sshloginfile" --workdir "$PWD")
  total=$(wc -l <"$work/jobs.txt")
  start=$SECONDS
  status=0
  # --resume-failed: the joblog's finished shards are skipped; killed and failed ones run again.
  parallel --will-cite --jobs "$jobs" "${remote[@]}" --joblog "$work/joblog" --resume-failed <"$work/jobs.txt" || status=$?
  if [[ $status -ne 0 ]]; then
    # parallel's exit status: 1-100 the number of failed jobs, 101 more than 100, 255 an error of
    # its own (it was killed, or refused its arguments): then no count of shards is known.
    if ((status <= 100)); then what="$status of $total shards failed"
    elif ((status == 101)); then what="more than 100 of $total shards failed"
    else what="GNU parallel stopped with status $status (killed, or its own error above) before every shard ran"
    fi
    echo "predict-calibration: $what (logs in $work/parts); rerun with --resume to run only the shards not done" >&2
    exit 1
  fi
  echo "predict-calibration: $total shards on $jobs slots in $((SECONDS - start)) s"
else
  [[ -f "$work/jobs.txt" ]] || die "--merge: $work/jobs.txt does not exist (--plan or --jobs first)"
  cmp -s "$plan" "$work/jobs.txt" ||
    die "--merge: $work/jobs.txt was planned with other techniques, grid or --shards; merge with the plan's own options"
  rm -f "$plan"
fi
merged=()
for spec in "${specs[@]}"; do
  name="$(name_of "$spec")"
  technique_parts=()
  for ((i = 0; i < shards; ++i)); do technique_parts+=("$work/parts/$name.$i-of-$shards.json"); done
  "$curve" merge "${technique_parts[@]}" -o "$work/$name.json" >"$work/$name.log"
  echo "predict-calibration: $spec: $(tail -n 1 "$work/$name.log")"
  merged+=("$work/$name.json")
done
combine "${merged[@]}"
