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
name=submit-demo-sweep
source scripts/slurm/submit-common.sh
work="out/demo-sweep"
parse_sharded_options penumbra-demo "$@"
headless=0
for a in "${tool_args[@]}"; do [[ "$a" == --headless ]] && headless=1; done
[[ $headless -eq 1 ]] || die "--headless: the demo's options need it (a shard walks the headless comparison)"
submit_sharded_run demo-sweep demo "a sweep"
