#!/usr/bin/env bash
# A manifest baked through a real single-node Slurm (slurmctld, slurmd and munge started here, state
# and spool in a temporary folder, no accounting, no cgroups) as `burnish bake --slurm` plans it:
# 21 sets from the two real maps of tests/data (ten presets each) and one truncated PNG. Checks that
# the corrupt set's task fails and the check job names it, that every other set is whole, that
# rerunning the failed task alone (input mended) bakes only that set, and that the outputs are byte
# for byte a local `burnish bake --manifest` of the same manifest.
# Exit 77 (skipped) where Slurm cannot start here: not root, packages missing, daemons not coming up.
# Usage: run_slurm_check.sh BURNISH_BINARY
set -uo pipefail
burnish=$(realpath "$1")
data=$(cd "$(dirname "$0")/../data" && pwd)

skip() {
  echo "SKIPPED: $*" >&2
  exit 77
}
die() {
  echo "FAILED: $*" >&2
  exit 1
}

[ "$(id -u)" = 0 ] || skip "starting slurmd needs root here (this test runs as $(id -un))"
for c in slurmctld slurmd munged munge sbatch squeue sinfo scontrol; do
  command -v "$c" >/dev/null || PATH="$PATH:/usr/sbin" command -v "$c" >/dev/null ||
    skip "'$c' is not installed (.ci/deps installs slurm-wlm and munge)"
done
export PATH="$PATH:/usr/sbin"

work=$(mktemp -d /tmp/burnish-slurm.XXXXXX)
chmod 711 "$work"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  [ -f "$work/munge/munged.pid" ] && kill "$(cat "$work/munge/munged.pid")" 2>/dev/null
  sleep 0.5
  rm -rf "$work"
}
trap cleanup EXIT

# Two free ports (a connection refused means nobody listens there).
free_port() {
  local p
  for p in $(seq "$1" "$(($1 + 200))"); do
    (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || { echo "$p"; return; }
  done
}
base=$((20000 + ($$ % 500) * 40))
ctld_port=$(free_port "$base")
slurmd_port=$(free_port "$((ctld_port + 1))")

# munge with a key of its own, on a socket of its own (the system's munged, if any, is left alone).
mkdir -p "$work/munge" "$work/state" "$work/spool" && chmod 711 "$work/munge"
head -c 1024 /dev/urandom >"$work/munge/munge.key" && chmod 600 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" --seed-file="$work/munge/seed" ||
  skip "munged does not start: $(tail -n 3 "$work/munge/munged.log" 2>/dev/null)"

cat >"$work/slurm.conf" <<EOF
ClusterName=burnishtest
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge/socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=100
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
DependencyParameters=kill_invalid_depend
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/filetxt
JobCompLoc=$work/jobcomp.txt
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
MinJobAge=300
SlurmdParameters=config_overrides
NodeName=node1 NodeAddr=127.0.0.1 NodeHostname=localhost CPUs=4 RealMemory=2000 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$work/slurm.conf"
setsid slurmctld -D -f "$SLURM_CONF" </dev/null >"$work/slurmctld.out" 2>&1 &
pids+=($!)
setsid slurmd -D -N node1 -f "$SLURM_CONF" </dev/null >"$work/slurmd.out" 2>&1 &
pids+=($!)
state=""
for _ in $(seq 1 150); do
  state=$(sinfo -h -o %T 2>/dev/null)
  [ "$state" = idle ] && break
  sleep 0.2
done
if [ "$state" != idle ]; then
  tail -n 5 "$work/slurmctld.log" "$work/slurmd.log" >&2 2>/dev/null
  skip "slurmctld and slurmd did not bring the node up within 30 s (state '$state'; logs above)"
fi
echo "Slurm up: node idle (ports $ctld_port, $slurmd_port)"

# The library: 2 real maps x 10 presets, and job 7 a PNG cut short after its header.
lib="$work/lib"
mkdir -p "$lib/maps"
cp "$data/trak-rust1_nm.png" "$data/trak-treadplate1_nm.png" "$lib/maps/"
head -c 30000 "$data/trak-rust1_nm.png" >"$lib/maps/cut.png"
{
  echo '{"version": 1, "jobs": ['
  n=0
  for m in trak-rust1 trak-treadplate1; do
    for p in gltf unreal unity godot filament blackops mixture lean clean toksvig-map; do
      n=$((n + 1))
      [ $n -gt 1 ] && echo ","
      printf '  {"input": "maps/%s_nm.png", "out": "out/%s-%s", "preset": "%s"}' "$m" "$m" "$p" "$p"
      [ $n = 6 ] && printf ',\n  {"input": "maps/cut.png", "out": "out/cut", "preset": "gltf"}'
    done
  done
  echo ']}'
} >"$lib/library.json"
cd "$lib" || die "no library folder"

start=$(date +%s.%N)
plan=$("$burnish" bake --manifest library.json --slurm slurm --tasks 5 --mem-per-task auto) || die "plan: $plan"
echo "$plan"
submit=$(echo "$plan" | sed -n 2p)
[[ "$submit" == *"sbatch --parsable"*"--dependency=afterany:"* ]] || die "no submit line in the plan's output"

wait_queue() {
  for _ in $(seq 1 900); do
    [ -z "$(squeue -h 2>/dev/null)" ] && return 0
    sleep 0.2
  done
  squeue >&2
  die "the queue did not empty within 180 s"
}
eval "$submit" >/dev/null || die "submitting failed: $submit"
array_id=${jid%%;*}
wait_queue
echo "array $array_id and its check done in $(awk "BEGIN { printf \"%.1f\", $(date +%s.%N) - $start }") s"

summary="slurm/summary.json"
[ -f "$summary" ] || die "the check job wrote no summary.json ($(cat slurm/logs/check-*.out 2>/dev/null))"
cat slurm/summary.txt
read -r current failed task reason < <(python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
f = [x for x in s["sets"] if x["state"] == "failed"]
print(s["counts"]["current"], s["counts"]["failed"], f[0]["task"] if f else "-",
      (str(f[0]["job"]) + " " + f[0]["reason"]) if f else "-")' "$summary")
[ "$current" = 20 ] && [ "$failed" = 1 ] || die "expected 20 current and 1 failed, the summary says $current and $failed"
[[ "$reason" == "7 "*"truncated"* ]] || die "the failed set named is not job 7 with its decode error: $reason"
grep -q "20 current, 1 failed" slurm/logs/check-*.out || die "the check job's log does not give the counts"
grep -q "job 7 (task $task)" slurm/logs/check-*.out || die "the check job's log does not name job 7"
task_state=$(scontrol -o show job "$array_id" | grep -E "ArrayTaskId=$task " | grep -o 'JobState=[A-Z]*')
[ "$task_state" = JobState=FAILED ] || die "array task $task (job 7's) did not end FAILED: '$task_state'"
[ ! -e out/cut/bake.json ] || die "the corrupt set left a bake.json"
whole=0
for d in out/*/; do
  [ "$d" = out/cut/ ] && continue
  [ -f "$d/bake.json" ] && whole=$((whole + 1))
done
[ "$whole" = 20 ] || die "$whole of 20 other sets hold a bake.json"

# Mend the input and rerun that task alone: only job 7 is baked, every other set is left as it was.
stamps() { stat -c '%n %i %Y' out/*/bake.json | grep -v '^out/cut/'; }
before=$(stamps)
cp "$data/trak-rust1_nm.png" maps/cut.png
rerun=$(grep -o 'jid=$(sbatch --parsable --array=.*' slurm/summary.txt)
[[ "$rerun" == *"--array=$task "* ]] || die "the summary's rerun line is not task $task alone: $rerun"
eval "$rerun" >/dev/null || die "resubmitting failed: $rerun"
wait_queue
cat slurm/summary.txt
grep -q "21 sets: 21 current" slurm/summary.txt || die "after the rerun not every set is current"
[ "$before" = "$(stamps)" ] || die "the rerun rewrote sets that were current"
rerun_log="slurm/logs/bake-${jid%%;*}_$task.out"
grep -q "out/cut: preset gltf" "$rerun_log" || die "the rerun task did not bake job 7: $(cat "$rerun_log")"
[ "$(grep -c 'current, skipped' "$rerun_log")" -ge 1 ] || die "the rerun task did not skip its current sets"

# The same manifest baked locally: byte for byte the array's outputs.
mv out out-slurm
"$burnish" bake --manifest library.json >/dev/null || die "the local bake failed"
diff -r out out-slurm >/dev/null || die "the local bake differs from the Slurm bake: $(diff -rq out out-slurm | head -3)"
echo "PASSED: 21 sets baked by a 5-task Slurm array, job 7 failed and named, rerun alone, identical to a local bake ($(find out -type f | wc -l) files)"
