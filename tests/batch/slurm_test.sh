#!/usr/bin/env bash
# Integration test of deploy/slurm/ on a real single-node Slurm cluster started on this machine:
# munged + slurmctld + slurmd from Debian (slurmctld, slurmd, slurm-client, munge), a minimal
# slurm.conf (linuxproc process tracking, no cgroups, cons_tres, one node with 2 CPUs) on private
# ports and paths. Submits a batch of 6 mesh jobs as a 3-task array plus the collect job that
# depends on it (deploy/slurm/submit.sh), waits, checks the collected summary, and shuts the
# daemons down. Needs root to start the daemons: without it the test is SKIPPED (exit 77).
#
#   slurm_test.sh SKETCHDRAPE_BINARY SOURCE_DIR
set -uo pipefail
binary=$(realpath "$1")
source_dir=$(realpath "$2")
skip() { echo "SKIPPED: Slurm integration test: $*" >&2; exit 77; }
fail() { echo "FAILED: Slurm integration test: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || skip "starting slurmctld, slurmd and munged needs root (running as uid $(id -u))"
need=(slurmctld slurmd munged mungekey sbatch scontrol squeue)
missing=()
for tool in "${need[@]}"; do command -v "$tool" >/dev/null || missing+=("$tool"); done
if ((${#missing[@]})); then
  echo "Slurm test: ${missing[*]} not found; installing slurmctld slurmd slurm-client munge" >&2
  if command -v apt-get >/dev/null; then
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
      --no-install-recommends slurmctld slurmd slurm-client munge) >&2 ||
      skip "could not install Slurm from Debian"
  else
    skip "${missing[*]} missing and no apt-get"
  fi
fi

work=$(mktemp -d /tmp/sd-slurm-test.XXXXXX)
export SLURM_CONF=$work/slurm.conf
cleanup() {
  status=$?
  scontrol shutdown >/dev/null 2>&1
  for i in $(seq 1 50); do
    alive=0
    for pidfile in "$work/slurmctld.pid" "$work/slurmd.pid"; do
      [ -f "$pidfile" ] && kill -0 "$(cat "$pidfile")" 2>/dev/null && alive=1
    done
    [ $alive -eq 0 ] && break
    sleep 0.1
  done
  for pidfile in "$work/slurmctld.pid" "$work/slurmd.pid"; do
    [ -f "$pidfile" ] && kill -9 "$(cat "$pidfile")" 2>/dev/null
  done
  munged --stop --socket="$work/munge/munge.socket" >/dev/null 2>&1
  if [ $status -eq 0 ]; then
    rm -rf "$work"
  else
    echo "Slurm test: left $work for inspection (logs in $work/log)" >&2
    tail -n 20 "$work"/log/*.log >&2 2>/dev/null
  fi
}
trap cleanup EXIT

# Two free TCP ports for slurmctld and slurmd.
free_port() {
  local p
  for _ in $(seq 1 200); do
    p=$((20000 + RANDOM % 20000))
    (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || { echo "$p"; return; }
  done
  return 1
}
ctld_port=$(free_port) || fail "no free port"
slurmd_port=$(free_port) || fail "no free port"
[ "$ctld_port" != "$slurmd_port" ] || slurmd_port=$((ctld_port + 1))

mkdir -p "$work/munge" "$work/state" "$work/spool" "$work/log"
mungekey --create --keyfile="$work/munge/munge.key" --bits=1024 --force >/dev/null ||
  fail "mungekey could not create a key"
chmod 0400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/munge.socket" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/log/munged.log" \
  --seed-file="$work/munge/munged.seed" || skip "munged would not start (see $work/log/munged.log)"

host=$(hostname -s)
cat >"$SLURM_CONF" <<CONF
ClusterName=sdtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
ReturnToService=2
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=batch Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF

slurmctld -f "$SLURM_CONF" || skip "slurmctld would not start (see $work/log/slurmctld.log)"
slurmd -f "$SLURM_CONF" || skip "slurmd would not start (see $work/log/slurmd.log)"
for i in $(seq 1 100); do
  sinfo -h -o "%T" 2>/dev/null | grep -q idle && break
  sleep 0.2
done
sinfo -h -o "%T" | grep -q idle || skip "the node did not become idle: $(sinfo 2>&1)"
echo "Slurm test: single-node cluster up (ports $ctld_port/$slurmd_port, $work)"

# 3 sketches x 2 fabrics = 6 jobs, small images so the test stays quick.
cat >"$work/wardrobe.json" <<MANIFEST
{
  "format": "sketchdrape-batch/1",
  "set": {"/output/images": [{"view": "front", "size": [120, 180]}]},
  "jobs": [
    {"sketch": ["$source_dir/data/examples/a-line-skirt.json",
                "$source_dir/data/examples/sleeveless-dress.json",
                "$source_dir/data/examples/tshirt.json"],
     "matrix": {"/fabric": ["jersey", "denim"]}}
  ]
}
MANIFEST
out=$work/out
ids=$(SKETCHDRAPE=$binary "$source_dir/deploy/slurm/submit.sh" -n 3 "$work/wardrobe.json" "$out" \
  --stage mesh | tail -n 1) || fail "submit.sh failed"
read -r array_id collect_id <<<"$ids"
echo "Slurm test: array job $array_id, collect job $collect_id"

state=""
for i in $(seq 1 600); do  # at most 120 s
  state=$(scontrol show job "$collect_id" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | head -n 1)
  case $state in
    JobState=COMPLETED | JobState=FAILED | JobState=CANCELLED | JobState=TIMEOUT | JobState=NODE_FAIL) break ;;
  esac
  sleep 0.2
done
echo "Slurm test: collect job $state"
scontrol show job "$array_id" | grep -E 'JobId=|JobState=' >&2
[ "$state" = "JobState=COMPLETED" ] || fail "collect job ended as '$state' (expected COMPLETED); $(cat "$out/slurm/collect.out" 2>/dev/null)"

# Every array task ran its own shard, and the collect job found all 6 jobs done.
for i in 1 2 3; do
  [ -f "$out/shards/shard-$i-of-3.json" ] || fail "no shards/shard-$i-of-3.json: task $i did not run its shard"
  grep -q "shard $i/3" "$out/slurm/shard-$i.out" || fail "task $i log does not say shard $i/3"
  n=$(grep -c '"inputs_hash"' "$out/shards/shard-$i-of-3.json")
  [ "$n" -eq 2 ] || fail "shard $i ran $n jobs, expected 2"
done
states=$(scontrol show job "$array_id" | grep -o 'JobState=[A-Z_]*' | sort | uniq -c | tr -s ' ')
[ "$(echo "$states" | tr -d '\n')" = " 3 JobState=COMPLETED" ] || fail "array tasks: $states"
grep -q '"jobs": 6,' "$out/batch.json" || fail "batch.json does not list 6 jobs"
grep -q '"done": 6,' "$out/batch.json" || fail "batch.json does not count 6 done jobs: $(head -c 600 "$out/batch.json")"
[ "$(grep -c '"status": "done"' "$out/batch.json")" -eq 6 ] || fail "not every job is done"
[ "$(grep -c '<tr class="job done"' "$out/index.html")" -eq 6 ] || fail "index.html has not 6 done rows"
[ "$(ls "$out"/jobs/*/done | wc -l)" -eq 6 ] || fail "not 6 done markers"
[ "$(ls "$out"/jobs/*/garment-front.png | wc -l)" -eq 6 ] || fail "not 6 front images"
echo "PASSED: Slurm integration test: 6 jobs in a 3-task array, collected by a dependent job"
