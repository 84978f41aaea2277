#!/usr/bin/env bash
# penumbra-bench on a Slurm cluster (docs/cluster.md): submits the bench's rows as one job array
# of bench.sbatch (task K measures shard K/N) with at most LIMIT tasks running at once, and queues
# the merge (bench-merge.sbatch) with --dependency=afterok on the array. Run it from the source
# tree on the login node, with the build (or PENUMBRA_BENCH, the installed tool) on a file system
# the nodes share.
#   scripts/slurm/submit-bench.sh --shards N [--limit L] [--resume] [--work DIR] [--sbatch 'ARGS']
#       -o OUT -- BENCH-ARGS...
#   --shards N       the array's tasks, each every N-th row of the bench's grid
#   --limit L        the array's throttle, %L (default 16)
#   --work DIR       the parts (DIR/parts) and the arguments they were made with (default out/bench-shards)
#   --resume         submit only the tasks whose part is missing, with the same arguments
#   --sbatch 'ARGS'  extra sbatch options for both jobs (--partition=..., --account=..., --exclusive)
#   -o OUT           the merged directory (bench.csv, report.json, plots)
# BENCH-ARGS are penumbra-bench's options without -o (--quick, --scenes, --techniques, ...).
set -euo pipefail
cd "$(dirname "$0")/../.."
name=submit-bench
source scripts/slurm/submit-common.sh
work="out/bench-shards"
parse_sharded_options penumbra-bench "$@"
submit_sharded_run bench bench "a bench"
