#!/usr/bin/env bash
# scripts/predict-calibration.sh --jobs 2 (GNU parallel, issue 50): a sweep of a tiny grid in 4
# shards on 2 local slots, once uninterrupted and once with one shard's penumbra-observer-curve
# killed (SIGKILL) mid-run. The killed sweep fails and says --resume; --resume runs that one shard
# alone (the joblog's finished ones are skipped) and the merge equals the uninterrupted sweep's,
# byte for byte apart from created_utc; so does a sweep sent through --sshloginfile (ssh a stand-in
# that runs the remote side here). A sweep whose GNU parallel stops with its own status 255
# says so, not "255 of 4 shards failed". Skipped (77) without GNU parallel (scripts/setup.sh).
#   predict_calibration_parallel_test.sh PENUMBRA-OBSERVER-CURVE
set -euo pipefail
curve="$1"
repo="$(cd "$(dirname "$0")/../.." && pwd)"
command -v parallel >/dev/null || { echo "skipped: GNU parallel is not installed (scripts/setup.sh installs it)"; exit 77; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
# Whether calibration.json FILE equals the uninterrupted sweep's but created_utc (the diff in $tmp/diff).
equals_whole() { diff <(grep -v '"created_utc"' "$tmp/whole.json") <(grep -v '"created_utc"' "$1") >"$tmp/diff"; }
# 2 conditions x 2 sizes x 3 radii x 2 seeds = 24 renders; a shard prints a line after each of its
# 4 blocks (condition x size), so a kill after the first line lands with three blocks to go.
grid="--pattern stair,step --artifact-px 10,20 --ratio-min 1 --ratio-max 3 --ratio-step 1.5 --seeds 2"
sweep() { "$repo/scripts/predict-calibration.sh" --jobs 2 --shards 4 --grid "$grid" "$@" pcf:pcf.kernel=grid; }

PENUMBRA_OBSERVER_CURVE="$curve" sweep --work "$tmp/whole" "$tmp/whole.json" >"$tmp/whole.log" 2>&1 ||
  fail "the uninterrupted sweep: $(cat "$tmp/whole.log")"

# The curve as every shard of the second sweep runs it: shard 2/4's first run is killed once it
# has rendered its first block (its first progress line is in the job's log, its stdout).
cat >"$tmp/curve-killed-once.sh" <<WRAPPER
#!/usr/bin/env bash
if [[ " \$* " == *" --shard 2/4 "* && ! -e "$tmp/killed" ]]; then
  touch "$tmp/killed"
  log="\$(readlink /proc/\$\$/fd/1)"
  "$curve" "\$@" &
  pid=\$!
  until grep -q ' renders\$' "\$log" || ! kill -0 \$pid 2>/dev/null; do sleep 0.01; done
  kill -KILL \$pid 2>/dev/null
  wait \$pid
  exit \$?
fi
exec "$curve" "\$@"
WRAPPER
chmod +x "$tmp/curve-killed-once.sh"
export PENUMBRA_OBSERVER_CURVE="$tmp/curve-killed-once.sh"
if sweep --work "$tmp/killed-sweep" "$tmp/resumed.json" >"$tmp/killed.log" 2>&1; then
  fail "the sweep with a killed shard succeeded: $(cat "$tmp/killed.log")"
fi
grep -q -- "1 of 4 shards failed .*rerun with --resume" "$tmp/killed.log" || fail "the failed sweep does not say 1 of 4 and --resume: $(cat "$tmp/killed.log")"
parts="$tmp/killed-sweep/parts"
[[ ! -e "$parts/pcf-pcf-kernel-grid.2-of-4.json" ]] || fail "shard 2/4 wrote its part: it was not killed mid-run"
grep -q ' renders$' "$parts/pcf-pcf-kernel-grid.2-of-4.log" || fail "shard 2/4 was killed before it rendered"
for i in 0 1 3; do [[ -f "$parts/pcf-pcf-kernel-grid.$i-of-4.json" ]] || fail "shard $i/4 has no part"; done
[[ ! -e "$tmp/resumed.json" ]] || fail "the failed sweep wrote its output"
joblog="$tmp/killed-sweep/joblog"
[[ $(tail -n +2 "$joblog" | wc -l) -eq 4 ]] || fail "the joblog has not 4 jobs: $(cat "$joblog")"

sweep --work "$tmp/killed-sweep" --resume "$tmp/resumed.json" >"$tmp/resumed.log" 2>&1 || fail "--resume: $(cat "$tmp/resumed.log")"
# The resume ran shard 2/4 alone: one more joblog row, for it, exit 0.
[[ $(tail -n +2 "$joblog" | wc -l) -eq 5 ]] || fail "--resume ran other than the one killed shard: $(cat "$joblog")"
tail -n 1 "$joblog" | awk -F'\t' '$7 != 0 || $9 !~ /--shard 2\/4 / { exit 1 }' || fail "--resume's row: $(tail -n 1 "$joblog")"
equals_whole "$tmp/resumed.json" ||
  fail "the resumed sweep differs from the uninterrupted one: $(head -20 "$tmp/diff")"
grep -q '"c": [0-9]' "$tmp/resumed.json" || fail "no c in $(cat "$tmp/resumed.json")"

# --sshloginfile: the shards go through parallel's remote path (its perl wrapper, --workdir's cd,
# the commands' quoting and redirections) to a machine named in the file. ssh is a stand-in
# (PARALLEL_SSH) that runs the remote side here as a login would: in the home directory, with
# none of this shell's variables; the tool is named by a path relative to the source tree, so the
# jobs find it only through --workdir. Not covered: the network and a second file system.
cat >"$tmp/ssh" <<'FAKE'
#!/bin/bash
while [[ $# -gt 0 && "$1" == -* && "$1" != -- ]]; do case "$1" in -l | -p | -o | -i) shift 2 ;; *) shift ;; esac; done
echo "$1" >>"${0%/*}/ssh-hosts"
shift
[[ "${1:-}" == -- ]] && shift
# The sanitizers' settings, as a machine running a sanitized build would have them (the sanitize
# test preset's, and LD_PRELOAD of scripts/sanitize-tests.sh); nothing else of the caller's.
keep=()
for v in ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS LD_PRELOAD; do [[ -n "${!v:-}" ]] && keep+=("$v=${!v}"); done
cd /tmp
exec env -i PATH=/usr/bin:/bin HOME=/tmp SHELL=/bin/bash "${keep[@]}" bash -c "$*"
FAKE
chmod +x "$tmp/ssh"
printf '2/lab-pc-1\n' >"$tmp/logins"
PARALLEL_SSH="$tmp/ssh" PENUMBRA_OBSERVER_CURVE="$(realpath --relative-to="$repo" "$curve")" sweep --sshloginfile "$tmp/logins" --work "$tmp/remote" "$tmp/remote.json" \
  >"$tmp/remote.log" 2>&1 || fail "--sshloginfile: $(cat "$tmp/remote.log")"
[[ $(grep -c '^lab-pc-1$' "$tmp/ssh-hosts") -eq 4 ]] || fail "not every shard went to lab-pc-1: $(cat "$tmp/ssh-hosts" 2>/dev/null)"
tail -n +2 "$tmp/remote/joblog" | awk -F'\t' '$2 != "lab-pc-1" || $7 != 0 { exit 1 }' || fail "--sshloginfile's joblog: $(cat "$tmp/remote/joblog")"
equals_whole "$tmp/remote.json" ||
  fail "the sweep through --sshloginfile differs from the local one: $(head -20 "$tmp/diff")"

# GNU parallel itself stopped (status 255: killed, or an error of its own) counts no shards: the
# sweep says so instead of "255 of 4 shards failed" (what a killed sweep printed before).
mkdir "$tmp/bin"
printf '#!/bin/sh\nexit 255\n' >"$tmp/bin/parallel"
chmod +x "$tmp/bin/parallel"
if PATH="$tmp/bin:$PATH" sweep --work "$tmp/stopped" "$tmp/stopped.json" >"$tmp/stopped.log" 2>&1; then
  fail "a sweep whose parallel exited 255 succeeded: $(cat "$tmp/stopped.log")"
fi
grep -q "GNU parallel stopped with status 255 .*rerun with --resume" "$tmp/stopped.log" || fail "parallel's 255: $(cat "$tmp/stopped.log")"
! grep -q "255 of" "$tmp/stopped.log" || fail "parallel's 255 read as a count of shards: $(cat "$tmp/stopped.log")"
[[ ! -e "$tmp/stopped.json" ]] || fail "the stopped sweep wrote its output"
echo "ok: shard 2/4 killed mid-run, --resume ran it alone, the merge equals the uninterrupted sweep; the same through --sshloginfile; parallel's own 255 is said as such"
