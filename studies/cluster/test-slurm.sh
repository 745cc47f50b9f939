#!/usr/bin/env bash
# Tests the Slurm path on a throw-away single-node Slurm (Debian's slurm-wlm and munge; no
# systemd, no cgroups: proctrack/linuxproc, task/none, select/cons_tres), from the repository's
# root with `twin` built: the array script on a reduced Table 5.1 study (4 shards), one task
# requeued mid-run (it waits for its BeginTime, then resumes its shard), another cancelled; the
# `afterany` merge names the cancelled shard; that task alone resubmitted (`--array=3`); the merge
# again, byte-identical to a single run. Every daemon it starts is stopped by its PID, and all it
# writes is in one temporary folder. Needs root (the daemons run as root) — .ci/run runs it.
set -euo pipefail
cd "$(dirname "$0")/../.."
for tool in munged slurmctld slurmd sbatch squeue scontrol scancel sinfo; do
  command -v "$tool" >/dev/null || { echo "test-slurm: $tool not found (apt-get install slurm-wlm munge)" >&2; exit 1; }
done
[ -x target/release/twin ] || { echo "test-slurm: build twin first (cargo build --release)" >&2; exit 1; }
ROOT=$(mktemp -d /tmp/twin-slurm.XXXXXX)
PASSED=0
# Stops every daemon by its PID (and waits for it), then removes the folder if the test passed.
cleanup() {
  for pid in "$ROOT"/slurmd.pid "$ROOT"/slurmctld.pid "$ROOT"/munged.pid; do
    if [ -s "$pid" ]; then
      p=$(cat "$pid")
      kill "$p" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    fi
  done
  if [ "$PASSED" = 1 ]; then rm -rf "$ROOT"; else echo "test-slurm: logs kept in $ROOT" >&2; fi
}
trap cleanup EXIT
say() { echo "test-slurm: $*"; }
fail() { echo "test-slurm: FAILED: $*" >&2; tail -n 20 "$ROOT"/*.log >&2 || true; exit 1; }
# Waits up to $1 seconds for the command $2... to succeed.
wait_for() {
  local limit=$1; shift
  for ((i = 0; i < limit * 5; i++)); do "$@" && return 0; sleep 0.2; done
  return 1
}

# munge, with its key, socket and pid in the folder.
dd if=/dev/urandom of="$ROOT/munge.key" bs=1024 count=1 status=none
chmod 400 "$ROOT/munge.key"
munged --force --key-file="$ROOT/munge.key" --socket="$ROOT/munge.socket" \
  --pid-file="$ROOT/munged.pid" --log-file="$ROOT/munged.log" --seed-file="$ROOT/munge.seed"
HOST=$(hostname -s)
export SLURM_CONF="$ROOT/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=twin-test
SlurmctldHost=$HOST
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$ROOT/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$ROOT/state
SlurmdSpoolDir=$ROOT/spool
SlurmctldPidFile=$ROOT/slurmctld.pid
SlurmdPidFile=$ROOT/slurmd.pid
SlurmctldLogFile=$ROOT/slurmctld.log
SlurmdLogFile=$ROOT/slurmd.log
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
NodeName=$HOST CPUs=$(nproc) RealMemory=2000 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
mkdir -p "$ROOT/state" "$ROOT/spool"
slurmctld -i
slurmd
wait_for 30 sh -c 'sinfo -h -o %t | grep -q idle' || fail "the node did not come up"
say "single-node Slurm up on $HOST"

# A reduced study: 4 shards of 1,000 trials (the full one's settings otherwise).
STUDY="$ROOT/study.toml"
sed -e "s|^trials_per_rate = .*|trials_per_rate = 2000|" \
    -e "s|\"\.\./|\"$PWD/|g" studies/table-5-1.toml >"$STUDY"
export TABLE_5_1_SHARDS=4 TABLE_5_1_STUDY="$STUDY" TABLE_5_1_OUT="$ROOT/out"
mkdir -p "$ROOT/out"
target/release/twin montecarlo "$STUDY" --threads 2 --out "$ROOT/single" --quiet
submit() { sbatch --parsable --export=ALL --output="$ROOT/out/slurm-%A_%a.log" "$@"; }

JOB=$(submit --array=0-3 studies/cluster/slurm-table-5-1.sh)
say "array $JOB submitted"
# Task 3 is cancelled while it waits; task 1 is requeued once it runs.
scancel "${JOB}_3"
wait_for 60 sh -c "squeue -h -j ${JOB}_1 -o %t | grep -q R" || fail "task 1 never ran"
scontrol requeue "${JOB}_1"
say "task 1 requeued mid-run, task 3 cancelled"
MERGE=$(sbatch --parsable --export=ALL --dependency="afterany:$JOB" \
  --output="$ROOT/out/merge-%j.log" studies/cluster/slurm-table-5-1-merge.sh)
# The requeued task waits for its BeginTime (about 2.5 minutes), then resumes.
wait_for 400 sh -c "[ -z \"\$(squeue -h -j $JOB,$MERGE)\" ]" || fail "the array and merge did not end"
grep -q "shards not finished: 3 of 0-3" "$ROOT/out/merge-$MERGE.log" \
  || fail "the merge did not name the cancelled shard: $(cat "$ROOT/out/merge-$MERGE.log")"
say "the merge named the missing shard"

AGAIN=$(submit --array=3 studies/cluster/slurm-table-5-1.sh)
MERGE=$(sbatch --parsable --export=ALL --dependency="afterany:$AGAIN" \
  --output="$ROOT/out/merge-%j.log" studies/cluster/slurm-table-5-1-merge.sh)
wait_for 120 sh -c "[ -z \"\$(squeue -h -j $AGAIN,$MERGE)\" ]" || fail "the resubmitted task and merge did not end"
for file in trials.csv summary.json table.md errors.svg; do
  cmp -s "$ROOT/out/merged/$file" "$ROOT/single/$file" \
    || fail "$file merged from the array differs from a single run's"
done
grep -qi "requeue" "$ROOT/slurmd.log" || fail "task 1 was never requeued (slurmd.log)"
say "merged files equal a single run's byte for byte (requeued task resumed, cancelled one recovered)"
PASSED=1
