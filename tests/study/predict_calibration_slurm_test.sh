#!/usr/bin/env bash
# scripts/slurm/submit-predict-calibration.sh on a real single-node Slurm (issue 50): munged,
# slurmctld and slurmd (Debian's munge, slurmctld, slurmd, slurm-client) started on localhost by
# this script with their own key, config, ports and state in a temporary folder, and stopped at
# its end. A tiny grid in 3 shards runs as a job array throttled to 2 tasks, then the merge job
# that waits on it (--dependency=afterok); OUTPUT equals the serial run's apart from created_utc.
# Skipped (77) where the daemons are not installed, the user is not root, or they do not start
# (a container without the privileges): CTest label `slurm`. With PENUMBRA-BENCH, the same daemons
# then run scripts/slurm/submit-bench.sh: a tiny bench in 3 shards and its merge, equal to the
# unsharded run in every column but the frame times; with PENUMBRA-DEMO after it,
# scripts/slurm/submit-demo-sweep.sh: a tiny sweep of two techniques in 2 tasks and its merge,
# equal to the unsharded run but for the timing fields.
#   predict_calibration_slurm_test.sh PENUMBRA-OBSERVER-CURVE [PENUMBRA-BENCH [PENUMBRA-DEMO]]
set -euo pipefail
curve="$1"
bench="${2:-}"
demo="${3:-}"
repo="$(cd "$(dirname "$0")/../.." && pwd)"
skip() { echo "skipped: $*"; exit 77; }
fail() { echo "FAIL: $*" >&2; exit 1; }
# Waits for the queue to empty: fails when merge job $1 can never run (a task of its array failed:
# afterok), with the last lines of the logs matching glob $3, or after 180 s; $2 names the jobs
# ("" or "bench ") in the message.
wait_for_queue() {
  local merge=$1 what=$2 logs=$3
  for _ in $(seq 900); do
    [[ -z "$(squeue -h -o %i)" ]] && return 0
    [[ "$(squeue -h -j "$merge" -o %r 2>/dev/null)" != DependencyNeverSatisfied ]] ||
      fail "a ${what}task failed, so the merge never runs (afterok): $(tail -n 3 $logs 2>/dev/null | tr '\n' ' ')"
    sleep 0.2
  done
  [[ -z "$(squeue -h -o %i)" ]] || fail "${what}jobs still queued after 180 s: $(squeue)"
}
for tool in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
  command -v "$tool" >/dev/null || PATH="$PATH:/usr/sbin" command -v "$tool" >/dev/null ||
    skip "$tool is not installed (apt install munge slurmctld slurmd slurm-client)"
done
export PATH="$PATH:/usr/sbin"
[[ $(id -u) -eq 0 ]] || skip "slurmd must run as root to start the jobs"
tmp="$(mktemp -d)"
chmod 700 "$tmp"
pids=()
cleanup() {
  local pid
  if [[ -f "$tmp/slurm.conf" ]]; then SLURM_CONF="$tmp/slurm.conf" scancel --quiet --user root 2>/dev/null || true; fi
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
  done
  rm -rf "$tmp"
}
trap cleanup EXIT
host="$(hostname -s)"
port=$((20000 + $$ % 20000))
mkdir -p "$tmp/state" "$tmp/spool" "$tmp/logs"
dd if=/dev/urandom of="$tmp/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge.key"
munged --force --key-file="$tmp/munge.key" --socket="$tmp/munge.socket" --pid-file="$tmp/munged.pid" \
  --log-file="$tmp/munged.log" --seed-file="$tmp/munged.seed" ||
  skip "munged does not start here: $(tail -n 2 "$tmp/munged.log" 2>/dev/null)"
pids+=("$(cat "$tmp/munged.pid")")
cat >"$tmp/slurm.conf" <<CONF
ClusterName=penumbra-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge.socket
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
PlugStackConfig=$tmp/plugstack.conf
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
: >"$tmp/plugstack.conf"
export SLURM_CONF="$tmp/slurm.conf"
slurmctld -D -i -f "$SLURM_CONF" >"$tmp/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N "$host" -f "$SLURM_CONF" >"$tmp/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 150); do
  [[ "$(sinfo -h -n "$host" -o %t 2>/dev/null)" == idle ]] && break
  kill -0 "${pids[1]}" 2>/dev/null && kill -0 "${pids[2]}" 2>/dev/null ||
    skip "slurmctld or slurmd exited: $(tail -n 3 "$tmp/slurmctld.log" "$tmp/slurmd.log" 2>/dev/null | tr '\n' ' ')"
  sleep 0.2
done
[[ "$(sinfo -h -n "$host" -o %t)" == idle ]] || skip "the node is not idle after 30 s: $(sinfo -h -n "$host" -o '%t %E')"

grid="--pattern stair,step --artifact-px 10 --ratio-min 1 --ratio-max 3 --ratio-step 1.5 --seeds 2"
spec=pcf:pcf.kernel=grid
export PENUMBRA_OBSERVER_CURVE="$curve"
"$repo/scripts/predict-calibration.sh" --grid "$grid" "$tmp/serial.json" "$spec" >"$tmp/serial.log" 2>&1 || fail "serial: $(cat "$tmp/serial.log")"
"$repo/scripts/slurm/submit-predict-calibration.sh" --limit 2 --sbatch "--cpus-per-task=1 --mem=200M --output=$tmp/logs/%x-%j.out" \
  --shards 3 --work "$tmp/work" --grid "$grid" "$tmp/slurm.json" "$spec" >"$tmp/submit.log" 2>&1 || fail "submit: $(cat "$tmp/submit.log")"
cat "$tmp/submit.log"
array_id="$(sed -n 's/.*array \([0-9]*\):.*/\1/p' "$tmp/submit.log")"
merge_id="$(sed -n 's/.*merge \([0-9]*\) after.*/\1/p' "$tmp/submit.log")"
[[ -n "$array_id" && -n "$merge_id" ]] || fail "no job ids in: $(cat "$tmp/submit.log")"
# The merge waits on the whole array: its dependency names it, and it cannot start before.
scontrol show job "$merge_id" | grep -q "Dependency=afterok:${array_id}" ||
  [[ -f "$tmp/slurm.json" ]] || fail "the merge job's dependency: $(scontrol show job "$merge_id" | grep -o 'Dependency=[^ ]*')"
scontrol show job "$array_id" 2>/dev/null | grep -q "ArrayTaskThrottle=2" || echo "note: the array finished before its throttle could be read"
wait_for_queue "$merge_id" "" "$tmp/logs/*"
[[ -f "$tmp/slurm.json" ]] || fail "the merge wrote nothing: $(cat "$tmp"/logs/* 2>/dev/null | tail -n 20)"
for i in 0 1 2; do [[ -f "$tmp/work/parts/pcf-pcf-kernel-grid.$i-of-3.json" ]] || fail "task $i left no part"; done
[[ $(ls "$tmp/logs" | wc -l) -eq 4 ]] || fail "not 3 tasks and a merge: $(ls "$tmp/logs")"
diff <(grep -v '"created_utc"' "$tmp/serial.json") <(grep -v '"created_utc"' "$tmp/slurm.json") >"$tmp/diff" ||
  fail "the Slurm run differs from the serial one: $(head -20 "$tmp/diff")"
echo "ok: array $array_id (3 tasks, at most 2 at once) and merge $merge_id after it; equal to the serial run"

[[ -n "$bench" ]] || exit 0
# The bench's array and merge. Frame times, the floor and the Pareto marks drawn from them are
# measurements: every other column is compared.
bench_grid=(--scenes two-planes --techniques hard,pcss --resolutions 64,256 --reference-resolution 256 --area-samples 4
            --area-resolution 256 --width 64 --height 36 --frames 2 --warmup 1 --no-plot)
"$bench" "${bench_grid[@]}" -o "$tmp/bench-serial" >"$tmp/bench-serial.log" 2>&1 || fail "bench serial: $(tail -n 3 "$tmp/bench-serial.log")"
PENUMBRA_BENCH="$bench" "$repo/scripts/slurm/submit-bench.sh" --shards 3 --limit 2 \
  --sbatch "--cpus-per-task=1 --mem=500M --output=$tmp/logs/%x-%j.out" --work "$tmp/bench-work" -o "$tmp/bench-slurm" \
  -- "${bench_grid[@]}" >"$tmp/bench-submit.log" 2>&1 || fail "submit-bench: $(cat "$tmp/bench-submit.log")"
cat "$tmp/bench-submit.log"
bench_merge="$(sed -n 's/.*merge \([0-9]*\) after.*/\1/p' "$tmp/bench-submit.log")"
[[ -n "$bench_merge" ]] || fail "no merge job id in: $(cat "$tmp/bench-submit.log")"
wait_for_queue "$bench_merge" "bench " "$tmp/logs/penumbra-bench-*"
[[ -f "$tmp/bench-slurm/bench.csv" ]] || fail "the bench merge wrote nothing: $(cat "$tmp"/logs/penumbra-bench-* 2>/dev/null | tail -n 20)"
/usr/bin/python3 - "$tmp/bench-serial/bench.csv" "$tmp/bench-slurm/bench.csv" <<'PY' || fail "the Slurm bench differs from the serial one"
import csv, sys
timing = {"frame_ms_median", "frame_ms_min", "frame_ms_max", "floor_ms", "pareto", "pareto_spread"}
a, b = (list(csv.DictReader(open(p))) for p in sys.argv[1:])
assert len(a) == len(b) > 0, (len(a), len(b))
for k, (x, y) in enumerate(zip(a, b)):
    for column in x:
        if column not in timing and x[column] != y[column]:
            sys.exit("row %d, %s: %s, not %s" % (k, column, y[column], x[column]))
PY
echo "ok: the bench's 3 tasks and merge $bench_merge equal the unsharded run apart from the frame times"
[[ -n "$demo" ]] || exit 0
# The demo's sweep (scripts/slurm/submit-demo-sweep.sh): two techniques, one per task, and the
# merge. The images are compared byte for byte; report.json and frames.csv in every field but the
# frame times and what is read from them (docs/cluster.md).
demo_run=(--headless --scene demo --frames 1 --width 32 --height 18 --techniques pcf,hard --sweep --no-plot)
"$demo" "${demo_run[@]}" -o "$tmp/demo-serial" >"$tmp/demo-serial.log" 2>&1 || fail "demo serial: $(tail -n 3 "$tmp/demo-serial.log")"
PENUMBRA_DEMO="$demo" "$repo/scripts/slurm/submit-demo-sweep.sh" --shards 2 --limit 2 \
  --sbatch "--cpus-per-task=1 --mem=900M --output=$tmp/logs/%x-%j.out" --work "$tmp/demo-work" -o "$tmp/demo-slurm" \
  -- "${demo_run[@]}" >"$tmp/demo-submit.log" 2>&1 || fail "submit-demo-sweep: $(cat "$tmp/demo-submit.log")"
cat "$tmp/demo-submit.log"
demo_merge="$(sed -n 's/.*merge \([0-9]*\) after.*/\1/p' "$tmp/demo-submit.log")"
[[ -n "$demo_merge" ]] || fail "no merge job id in: $(cat "$tmp/demo-submit.log")"
wait_for_queue "$demo_merge" "demo " "$tmp/logs/penumbra-demo-*"
[[ -f "$tmp/demo-slurm/report.json" ]] || fail "the demo merge wrote nothing: $(cat "$tmp"/logs/penumbra-demo-* 2>/dev/null | tail -n 20)"
/usr/bin/python3 - "$tmp/demo-serial" "$tmp/demo-slurm" <<'PY' || fail "the Slurm sweep differs from the serial one"
import json, os, re, sys
a, b = sys.argv[1:]
files = sorted(os.listdir(a))
assert files == sorted(os.listdir(b)), (files, sorted(os.listdir(b)))
assert sum(f.endswith(".png") for f in files) >= 4, files
for f in files:
    if f.endswith(".png") and open(os.path.join(a, f), "rb").read() != open(os.path.join(b, f), "rb").read():
        sys.exit(f + " differs")
def timeless(j):
    if isinstance(j, list):
        return [timeless(x) for x in j]
    if not isinstance(j, dict):
        return j
    return {k: timeless(v) for k, v in j.items()
            if not (k.endswith("_ms") or k.endswith("_ms_mean") or k.startswith("speedup")
                    or k in ("time", "shadow_cost", "headline", "line", "cheapest_by_time"))}
x, y = (timeless(json.load(open(os.path.join(d, "report.json")))) for d in (a, b))
if x != y:
    sys.exit("report.json differs beyond the timing fields")
csv = lambda d: re.sub(r",[0-9]+\.[0-9]{4},", ",T,", open(os.path.join(d, "frames.csv")).read())
if csv(a) != csv(b):
    sys.exit("frames.csv differs beyond frame_ms")
PY
echo "ok: the demo sweep's 2 tasks and merge $demo_merge equal the unsharded run apart from the frame times"
