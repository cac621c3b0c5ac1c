#!/usr/bin/env bash
# The cluster path run for real: a single-node Slurm (slurmctld, slurmd and
# munged on this machine, in a temporary folder, on ports of their own) runs
# scripts/cluster/shadowbench.sbatch as a 3-task job array over
# tests/cluster/cluster.bench; one task is requeued mid-run (scontrol
# requeue kills it and queues it again) and must resume where it stopped;
# scripts/cluster/merge.sh then joins the shards, and the merge must equal an
# unsharded run of the batch, timings aside, and pass `compare`.
#   tests/cluster/slurm.sh SHADOWBENCH SOURCE_ROOT
# Exit 0 pass, 1 fail, 77 skip (only where Slurm cannot start: the reason is printed).
set -uo pipefail
sb=$(realpath "${1:?shadowbench binary}")
root=$(realpath "${2:?source root}")
bench=$root/tests/cluster/cluster.bench

skip() { echo "SKIP: $*"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }
say() { echo "[$(date +%T)] $*"; }

for d in slurmctld slurmd munged mungekey sbatch squeue scontrol; do
  command -v "$d" >/dev/null || PATH=$PATH:/usr/sbin:/sbin
  command -v "$d" >/dev/null || skip "$d is not installed (scripts/setup installs slurm-wlm and munge)"
done
[[ $(id -u) -eq 0 ]] || skip "slurmd must run as root to start jobs, and this test runs as $(id -un)"

T=$(mktemp -d /tmp/sbslurm.XXXXXX)
chmod 755 "$T"
cleanup() {
  for p in slurmd slurmctld munged; do
    [[ -f $T/$p.pid ]] && kill "$(cat "$T/$p.pid")" 2>/dev/null
  done
  sleep 0.5
  for p in slurmd slurmctld munged; do
    [[ -f $T/$p.pid ]] && kill -9 "$(cat "$T/$p.pid")" 2>/dev/null
  done
  if [[ ${SB_KEEP_SLURM_TMP:-} ]]; then echo "kept $T"; else rm -rf "$T"; fi
}
trap cleanup EXIT
mkdir -p "$T"/{key,munge,state,spool,log,logs,out}
chmod 700 "$T/key"

# munge: a key and a socket of our own
mungekey --create --keyfile="$T/key/munge.key" || skip "mungekey cannot create a key"
chmod 600 "$T/key/munge.key"
munged -f --socket="$T/munge/sock" --key-file="$T/key/munge.key" --pid-file="$T/munged.pid" \
  --log-file="$T/log/munged.log" --seed-file="$T/key/seed" ||
  skip "munged does not start: $(tail -n 3 "$T/log/munged.log" 2>/dev/null)"

# Slurm: this host as the controller and the only node, no cgroups
host=$(hostname -s)
port=$((20000 + $$ % 20000))
mem=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 2048))
# cred_expire: Slurm holds a requeued job this long (default 120 s) before it may start again; sched_interval:
# then the main scheduler's next pass starts it (default every 60 s: the requeued task waited 10 to 26 s)
cat >"$T/slurm.conf" <<CONF
ClusterName=sbtest
SlurmctldHost=$host
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$(id -un)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge/sock,cred_expire=5
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobRequeue=1
SchedulerParameters=sched_interval=1
MinJobAge=600
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$T/slurm.conf
slurmctld -i || skip "slurmctld does not start: $(tail -n 3 "$T/log/slurmctld.log" 2>/dev/null)"
slurmd || skip "slurmd does not start: $(tail -n 3 "$T/log/slurmd.log" 2>/dev/null)"
for _ in $(seq 100); do
  [[ $(sinfo -h -o %t 2>/dev/null) == idle ]] && break
  sleep 0.2
done
[[ $(sinfo -h -o %t 2>/dev/null) == idle ]] ||
  skip "the Slurm node did not come up in 20 s: $(sinfo 2>&1 | tail -n 1); $(tail -n 2 "$T/log/slurmd.log")"
say "Slurm up: node $host, $(nproc) CPUs, controller port $port"

# the whole batch, unsharded, for reference
whole=$("$sb" batch "$bench" --out "$T/whole" --quiet | tail -n 1) || fail "the unsharded batch failed"
say "unsharded: $whole"

# the job array, as the README says, with this machine's resources: no GPU
# gres, one CPU a task (the script's own --requeue lets scontrol requeue it)
out=$T/out
job=$(cd "$T" && SHADOWBENCH=$sb sbatch --parsable --array=1-3 --cpus-per-task=1 --gres=none \
  --output="$T/logs/%A_%a.log" "$root/scripts/cluster/shadowbench.sbatch" "$bench" "$out") ||
  fail "sbatch refused the job array"
say "submitted job array $job"

state() { squeue -h -j "$1" -o %T 2>/dev/null; }
# task 2, mid-run: once it has finished a run and is still running
victim=${job}_2
done_csv=
for _ in $(seq 600); do
  done_csv=$(ls "$out"/shard-2/*/*/????????????????.csv 2>/dev/null | head -n 1)
  [[ -n $done_csv && $(state "$victim") == RUNNING ]] && break
  done_csv=
  sleep 0.1
done
[[ -n $done_csv ]] || fail "task 2 never had a finished run while running (state: $(state "$victim"))"
before=$(stat -c '%i %Y' "$done_csv")
todo=$(($(ls "$out"/shard-2/*/*/????????????????.csv | wc -l)))
scontrol requeue "$victim" || fail "scontrol requeue $victim failed"
say "requeued $victim after $todo finished run(s)"

for _ in $(seq 900); do
  [[ -z $(squeue -h -j "$job" 2>/dev/null) ]] && break
  sleep 0.2
done
[[ -z $(squeue -h -j "$job") ]] || fail "the job array did not finish in 3 minutes: $(squeue -j "$job")"
for k in 1 2 3; do
  st=$(scontrol show job "${job}_$k" | grep -o 'JobState=[A-Z_]*')
  [[ $st == JobState=COMPLETED ]] || fail "task $k ended $st: $(tail -n 3 "$T"/logs/*_$k.log)"
done
restarts=$(scontrol show job "$victim" | grep -o 'Restarts=[0-9]*')
[[ $restarts == Restarts=1 ]] || fail "task 2 was not requeued ($restarts)"

# the requeued task resumed: one results folder, the run finished before the
# kill not rendered again
folders=$(ls -d "$out"/shard-2/*/*/ | wc -l)
[[ $folders -eq 1 ]] || fail "task 2 wrote $folders results folders: the requeue started over instead of resuming"
[[ $(stat -c '%i %Y' "$done_csv") == "$before" ]] ||
  fail "$done_csv was written again after the requeue: the resume redid a finished run"
say "task 2 resumed into $(ls -d "$out"/shard-2/*/*/)"

merged=$(SHADOWBENCH=$sb "$root/scripts/cluster/merge.sh" "$out" | tail -n 1) || fail "merge.sh failed"
say "merged: $merged"

# same runs and rows as the unsharded batch, timings aside
python3 - "$whole" "$merged" <<'PY' || fail "the merged results differ from the unsharded run"
import csv, os, re, sys
whole, merged = sys.argv[1], sys.argv[2]
# timings, and the reference's cost (runs share its rays within one process: a shard shares less)
timing = re.compile(r"(_ms|_s$|^start_s$|^warmup$|wall|^cpu|gpu|calib|harness|per_s$|stable|clock|throttle|^ref_)")
def load(d, name):
    with open(os.path.join(d, name)) as f:
        return list(csv.DictReader(f))
a, b = load(whole, "summary.csv"), load(merged, "summary.csv")
ids = lambda rows: [r["run_id"] for r in rows]
if ids(a) != ids(b):
    sys.exit(f"run_ids differ: unsharded {ids(a)}, merged {ids(b)}")
def same(x, y, where):
    for k in x:
        if timing.search(k):
            continue
        if x[k] != y.get(k):
            sys.exit(f"{where}: {k} is {x[k]!r} unsharded, {y.get(k)!r} merged")
for ra, rb in zip(a, b):
    same(ra, rb, f"summary run {ra['run_id']}")
    if ra["status"] != "ok":
        continue
    fa, fb = load(whole, ra["run_id"] + ".csv"), load(merged, ra["run_id"] + ".csv")
    if len(fa) != len(fb):
        sys.exit(f"{ra['run_id']}.csv: {len(fa)} rows unsharded, {len(fb)} merged")
    for i, (x, y) in enumerate(zip(fa, fb)):
        same(x, y, f"{ra['run_id']}.csv row {i + 1}")
print(f"{len(a)} runs: same run_ids, summary rows and per-frame rows (timings aside)")
PY
"$sb" compare "$whole" "$merged" --metric err_rate,draw_calls,shadow_triangles ||
  fail "compare of the merge against the unsharded run did not pass"
say "pass"
