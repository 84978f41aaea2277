# shellcheck shell=bash disable=SC2154  # name, limit, extra and the rest are the caller's
# What the submit-*.sh scripts of this folder share (docs/cluster.md), sourced by each from the
# source tree's root after it sets `name`, its own name, which begins every line it prints. The
# functions read and set the caller's variables: `limit` (the array's throttle) and `extra` (the
# --sbatch options, an array) for every submission, the rest as each says.

# A refusal: one line, exit 2.
die() { echo "$name: $*" >&2; exit 2; }

require_sbatch() { command -v sbatch >/dev/null || die "sbatch: not found (run this on the cluster's login node)"; }

# submit_array_then_merge TASKS COUNT OUT
# Submits the caller's `array_job` (an sbatch script and its arguments) as a job array of TASKS
# (sbatch's --array list: 0-7 or 2,5) of COUNT, at most `limit` running at once, then `merge_job`
# with --dependency=afterok on the array, both with the `extra` options. With TASKS empty (every
# part is there) the merge alone. Prints the job ids and OUT, what the merge writes.
submit_array_then_merge() {
  local tasks=$1 count=$2 out=$3 array_id merge_id dependency=()
  if [[ -n "$tasks" ]]; then
    array_id="$(sbatch --parsable "${extra[@]}" --array="$tasks%$limit" "${array_job[@]}")"
    array_id="${array_id%%;*}"
    echo "$name: array $array_id: tasks $tasks of $count, at most $limit at once"
    dependency=(--dependency="afterok:$array_id")
  else
    echo "$name: every part is there; queuing the merge alone"
  fi
  merge_id="$(sbatch --parsable "${extra[@]}" "${dependency[@]}" "${merge_job[@]}")"
  echo "$name: merge ${merge_id%%;*} after the array: writes $out"
}

# parse_sharded_options TOOL ARGS...
# The options of submit-bench.sh and submit-demo-sweep.sh (their comments list them) into
# `shards`, `limit`, `resume`, `work` (the caller's default kept without --work), `extra` and
# `out`; what follows -- into `tool_args`, TOOL's own options.
parse_sharded_options() {
  local tool=$1
  shift
  limit=16 resume=0 extra=() shards="" out=""
  while [[ $# -gt 0 && "$1" != -- ]]; do
    case "$1" in
      --shards) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "--shards: expected a whole number of tasks, got '${2:-}'"; shards="$2"; shift 2 ;;
      --limit) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "--limit: expected a whole number of tasks, got '${2:-}'"; limit="$2"; shift 2 ;;
      --work) [[ -n "${2:-}" ]] || die "--work: expected a directory"; work="$2"; shift 2 ;;
      --resume) resume=1; shift ;;
      --sbatch) read -ra extra <<<"${2:-}"; shift 2 ;;
      -o) [[ -n "${2:-}" ]] || die "-o: expected the output directory"; out="$2"; shift 2 ;;
      *) die "$1: unknown option (see the comment at the top of $0; $tool's own options go after --)" ;;
    esac
  done
  [[ "${1:-}" == -- ]] && shift
  [[ -n "$shards" ]] || die "--shards: required (the array's tasks)"
  [[ -n "$out" ]] || die "-o: required (the merged directory)"
  tool_args=("$@")
}

# submit_sharded_run JOB PART WHAT
# The submission of submit-bench.sh and submit-demo-sweep.sh after parse_sharded_options: task K
# of scripts/slurm/JOB.sbatch (WORK N TOOL-ARGS) writes WORK/parts/PART.K-of-N.json, and
# scripts/slurm/JOB-merge.sbatch (WORK N OUT) merges the parts into `out`. WORK/args.txt keeps
# --shards and the tool's options: a first submission refuses a `work` that has one (WHAT, "a
# bench", was submitted there); with `resume` they must be the same, and only the tasks whose part
# is missing are submitted.
submit_sharded_run() {
  local job=$1 part=$2 what=$3 args_file="$work/args.txt" array k tasks=()
  require_sbatch
  mkdir -p "$work/parts"
  printf '%s\n' "--shards $shards" "${tool_args[@]}" >"$args_file.new"
  if [[ $resume -eq 1 ]]; then
    [[ -f "$args_file" ]] || die "--resume: $args_file does not exist (submit without --resume first)"
    cmp -s "$args_file" "$args_file.new" || { rm -f "$args_file.new"; die "--resume: other --shards or $part options than the submission in $work"; }
    rm -f "$args_file.new"
    for ((k = 0; k < shards; ++k)); do [[ -f "$work/parts/$part.$k-of-$shards.json" ]] || tasks+=("$k"); done
    array="$(IFS=,; echo "${tasks[*]}")"
  else
    [[ ! -f "$args_file" ]] || { rm -f "$args_file.new"; die "$work: $what was submitted there; --resume to continue it, or another --work"; }
    mv "$args_file.new" "$args_file"
    array="0-$((shards - 1))"
  fi
  array_job=("scripts/slurm/$job.sbatch" "$work" "$shards" "${tool_args[@]}")
  merge_job=("scripts/slurm/$job-merge.sbatch" "$work" "$shards" "$out")
  submit_array_then_merge "$array" "$shards" "$out"
}
