#!/usr/bin/env bash
# The demo's sweep on a Slurm cluster (docs/cluster.md): submits its techniques as one job array of
# demo-sweep.sbatch (task K walks shard K/N: the techniques whose position in --techniques is K
# modulo N) with at most LIMIT tasks running at once, and queues the merge (demo-sweep-merge.sbatch)
# with --dependency=afterok on the array. Run it from the source tree on the login node, with the
# build (or PENUMBRA_DEMO, the installed tool) on a file system the nodes share.
#   scripts/slurm/submit-demo-sweep.sh --shards N [--limit L] [--resume] [--work DIR] [--sbatch 'ARGS']
#       -o OUT -- DEMO-ARGS...
#   --shards N       the array's tasks, at most the number of techniques (a technique is walked whole)
#   --limit L        the array's throttle, %L (default 16)
#   --work DIR       the parts (DIR/parts) and the arguments they were made with (default out/demo-sweep)
#   --resume         submit only the tasks whose part is missing, with the same arguments
#   --sbatch 'ARGS'  extra sbatch options for both jobs (--partition=..., --account=..., --exclusive)
#   -o OUT           the merged directory (report.json, frames.csv, the images, the plots)
# DEMO-ARGS are penumbra-demo's options without -o, --headless among them (--headless --sweep
# --scene outdoor --techniques pcf,pcss,vsm,evsm, ...).
set -euo pipefail
cd "$(dirname "$0")/../.."
die() { echo "submit-demo-sweep: $*" >&2; exit 2; }
limit=16 resume=0 extra=() work="out/demo-sweep" shards="" out=""
while [[ $# -gt 0 && "$1" != -- ]]; do
  case "$1" in
    --shards) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "--shards: expected a whole number of tasks, got '${2:-}'"; shards="$2"; shift 2 ;;
    --limit) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || die "--limit: expected a whole number of tasks, got '${2:-}'"; limit="$2"; shift 2 ;;
    --work) [[ -n "${2:-}" ]] || die "--work: expected a directory"; work="$2"; shift 2 ;;
    --resume) resume=1; shift ;;
    --sbatch) read -ra extra <<<"${2:-}"; shift 2 ;;
    -o) [[ -n "${2:-}" ]] || die "-o: expected the output directory"; out="$2"; shift 2 ;;
    *) die "$1: unknown option (see the comment at the top of $0; penumbra-demo's own options go after --)" ;;
  esac
done
[[ "${1:-}" == -- ]] && shift
[[ -n "$shards" ]] || die "--shards: required (the array's tasks)"
[[ -n "$out" ]] || die "-o: required (the merged directory)"
headless=0
for a in "$@"; do [[ "$a" == --headless ]] && headless=1; done
[[ $headless -eq 1 ]] || die "--headless: the demo's options need it (a shard walks the headless comparison)"
command -v sbatch >/dev/null || die "sbatch: not found (run this on the cluster's login node)"
mkdir -p "$work/parts"
args_file="$work/args.txt"
printf '%s\n' "--shards $shards" "$@" >"$args_file.new"
if [[ $resume -eq 1 ]]; then
  [[ -f "$args_file" ]] || die "--resume: $args_file does not exist (submit without --resume first)"
  cmp -s "$args_file" "$args_file.new" || { rm -f "$args_file.new"; die "--resume: other --shards or demo options than the submission in $work"; }
  rm -f "$args_file.new"
  tasks=()
  for ((k = 0; k < shards; ++k)); do [[ -f "$work/parts/demo.$k-of-$shards.json" ]] || tasks+=("$k"); done
  [[ ${#tasks[@]} -gt 0 ]] || echo "submit-demo-sweep: every part is there; queuing the merge alone"
  array="$(IFS=,; echo "${tasks[*]}")"
else
  [[ ! -f "$args_file" ]] || { rm -f "$args_file.new"; die "$work: a sweep was submitted there; --resume to continue it, or another --work"; }
  mv "$args_file.new" "$args_file"
  array="0-$((shards - 1))"
fi
dependency=()
if [[ -n "$array" ]]; then
  array_id="$(sbatch --parsable "${extra[@]}" --array="$array%$limit" scripts/slurm/demo-sweep.sbatch "$work" "$shards" "$@")"
  array_id="${array_id%%;*}"
  echo "submit-demo-sweep: array $array_id: tasks $array of $shards, at most $limit at once"
  dependency=(--dependency="afterok:$array_id")
fi
merge_id="$(sbatch --parsable "${extra[@]}" "${dependency[@]}" scripts/slurm/demo-sweep-merge.sbatch "$work" "$shards" "$out")"
echo "submit-demo-sweep: merge ${merge_id%%;*} after the array: writes $out"
