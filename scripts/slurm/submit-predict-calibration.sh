#!/usr/bin/env bash
# scripts/predict-calibration.sh on a Slurm cluster (docs/cluster.md): plans the shards
# (predict-calibration.sh --plan: WORK/jobs.txt), submits them as one job array of
# predict-calibration.sbatch with at most LIMIT tasks running at once, and queues the merge
# (predict-calibration-merge.sbatch) with --dependency=afterok on the array. Run it from the
# source tree on the login node, with the build (or the installed tools) on a file system the
# nodes share.
#   scripts/slurm/submit-predict-calibration.sh [--limit L] [--resume] [--sbatch 'ARGS']
#       --shards S [--work DIR] [--grid 'ARGS'] [OUTPUT] [TECHNIQUE-SPEC...]
#   --limit L        the array's throttle, %L (default 16)
#   --resume         submit only the tasks whose part is missing (after failed or timed-out
#                    tasks; the merge job of the first submission was cancelled by Slurm)
#   --sbatch 'ARGS'  extra sbatch options for both jobs (--partition=..., --account=...)
# The rest are predict-calibration.sh's (--shards is required: the shards per technique).
set -euo pipefail
cd "$(dirname "$0")/../.."
name=submit-predict-calibration
source scripts/slurm/submit-common.sh
limit=16 resume=0 extra=() pass=() work="out/predict-calibration" shards=""
while [[ $# -gt 0 && "$1" == --* ]]; do
  case "$1" in
    --limit) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "--limit: expected a whole number of tasks, got '${2:-}'"; limit="$2"; shift 2 ;;
    --resume) resume=1; shift ;;
    --sbatch) read -ra extra <<<"${2:-}"; shift 2 ;;
    --work) work="${2:-}"; pass+=("$1" "${2:-}"); shift 2 ;;
    --shards) shards="${2:-}"; pass+=("$1" "${2:-}"); shift 2 ;;
    --grid) pass+=("$1" "${2:-}"); shift 2 ;;
    --) shift; break ;;
    *) die "$1: unknown option (see the comment at the top of $0)" ;;
  esac
done
[[ -n "$shards" ]] || die "--shards: required (the shards per technique: the array has that many tasks per technique)"
require_sbatch
if [[ $resume -eq 1 ]]; then
  [[ -f "$work/jobs.txt" ]] || die "--resume: $work/jobs.txt does not exist (submit without --resume first)"
  cp "$work/jobs.txt" "$work/jobs.txt.submitted"
fi
scripts/predict-calibration.sh --plan "${pass[@]}" "$@"
if [[ $resume -eq 1 ]]; then
  cmp -s "$work/jobs.txt" "$work/jobs.txt.submitted" ||
    { mv "$work/jobs.txt.submitted" "$work/jobs.txt"; die "--resume: other techniques, grid or --shards than the submission in $work"; }
  rm -f "$work/jobs.txt.submitted"
fi
total=$(wc -l <"$work/jobs.txt")
if [[ $resume -eq 1 ]]; then  # the tasks whose part is missing
  tasks=()
  for ((k = 0; k < total; ++k)); do
    part="$(sed -n "$((k + 1))p" "$work/jobs.txt" | grep -o -- '--part [^ ]*' | cut -d' ' -f2)"
    [[ -f "$part" ]] || tasks+=("$k")
  done
  array="$(IFS=,; echo "${tasks[*]}")"
else
  array="0-$((total - 1))"
fi
array_job=(scripts/slurm/predict-calibration.sbatch "$work")
merge_job=(scripts/slurm/predict-calibration-merge.sbatch --merge "${pass[@]}" "$@")
submit_array_then_merge "$array" "$total" "${1:-data/calibration/predicted.json}"
