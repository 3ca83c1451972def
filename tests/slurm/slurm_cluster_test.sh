#!/usr/bin/env bash
# canopy-bench slurm on a real Slurm: starts a single-node cluster (munged, slurmctld, slurmd) in
# a temporary folder, runs a small config as a 3-shard job array with its merge job, compares the
# merged records with a single run of the same config, then cancels one task of a second array,
# checks that the merge refuses naming that shard, reruns the task alone and merges again.
# Every daemon it started is stopped by pid on exit.
#
# Usage: slurm_cluster_test.sh CANOPY_BENCH   (ctest label "slurm"; exit 77 = skipped)
set -euo pipefail

bench=$(readlink -f "$1")
here=$(cd "$(dirname "$0")" && pwd)
if [[ $(id -u) -ne 0 ]]; then
  echo "SKIPPED: a private Slurm cluster runs its daemons as root; run this test as root"
  exit 77
fi
for tool in munged slurmctld slurmd sbatch squeue scontrol scancel sinfo; do
  command -v "$tool" >/dev/null || { echo "FAILED: $tool is missing (make deps installs slurm-wlm and munge)"; exit 1; }
done

work=$(mktemp -d /tmp/canopy-slurm.XXXXXX)
pids=()
stop_cluster() {
  # Jobs first (their steps are children of slurmd), then the daemons, newest first.
  scancel --quiet --user=root >/dev/null 2>&1 || true
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[i]}" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  if [[ "${keep:-0}" == 1 ]]; then echo "kept $work"; else rm -rf "$work"; fi
}
trap stop_cluster EXIT
fail() {
  echo "FAILED: $*"
  for log in "$work"/*.log "$work"/run*/logs/*; do
    [[ -s "$log" ]] && { echo "--- $log"; tail -n 20 "$log"; }
  done
  keep=1
  exit 1
}

# Ports of our own, so a cluster already running on this machine is left alone; the loopback
# address, so the test does not depend on how the host name resolves.
base_port=$((20000 + ($$ % 10000) * 2))
node=$(hostname -s)
mkdir -p "$work/state" "$work/spool"
export SLURM_CONF="$work/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=canopytest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$base_port
SlurmdPort=$((base_port + 1))
AuthType=auth/munge
AuthInfo=socket=$work/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
MpiDefault=none
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MinJobAge=600
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=canopy Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF

# munge with its own key and socket; the daemons in the foreground, so their pids are ours.
dd if=/dev/urandom of="$work/munge.key" bs=1024 count=1 status=none
chmod 0400 "$work/munge.key"
munged --foreground --force --key-file="$work/munge.key" --socket="$work/munge.socket" \
  --pid-file="$work/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munged.seed" \
  >"$work/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [[ -S "$work/munge.socket" ]] && break; sleep 0.1; done
[[ -S "$work/munge.socket" ]] || fail "munged did not start"
slurmctld -D -i >"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D >"$work/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 60); do
  state=$(sinfo -h -o %t 2>/dev/null || true)
  [[ "$state" == idle ]] && break
  sleep 0.5
done
[[ "$state" == idle ]] || fail "the node is not idle after 30 s (sinfo: '$state')"
echo "cluster up: node $node idle"

# waits for job $1 to leave the queue (at most $2 seconds) and prints its final state.
wait_job() {
  local state=""
  for _ in $(seq $(($2 * 2))); do
    state=$(scontrol show job "$1" -o 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | sort -u | tr '\n' ' ')
    [[ -n "$state" && ! "$state" =~ PENDING|RUNNING|CONFIGURING|COMPLETING ]] && break
    sleep 0.5
  done
  echo "${state% }"
}

cat >"$work/small.json" <<'EOF'
{"name": "slurm_small", "seed": 4,
 "trees": [{"preset": "sparse", "seed": 3, "leaves": 300},
           {"preset": "shrub", "seed": 2, "leaves": 400}],
 "methods": [{"method": "polygonal"}, {"method": "billboard_cloud", "params": {"clusters": 20}}],
 "views": {"resolution": [64, 64], "distances": [2, 6], "elevations": [0, 60], "azimuths": 2},
 "forests": {"sizes": [1, 3], "frames": 2, "warmup": 1, "blocks": 1, "repeats": 1,
             "min_sample_ms": 0}}
EOF

"$bench" --quiet --no-images --config "$work/small.json" --out "$work/single" ||
  fail "the single run failed"

# Pass 1: the whole array and its merge.
"$bench" slurm --config "$work/small.json" --shards 3 --out "$work/run1" --cpus-per-task 1 \
  --time 00:10:00 --submit >"$work/submit1.txt" || fail "canopy-bench slurm --submit failed"
cat "$work/submit1.txt"
array=$(sed -n 's/^array job \([0-9]*\).*/\1/p' "$work/submit1.txt")
merge=$(sed -n 's/.*merge job \([0-9]*\) after it.*/\1/p' "$work/submit1.txt")
[[ -n "$array" && -n "$merge" ]] || fail "no job ids in the output of canopy-bench slurm"
grep -q "^#SBATCH --array=0-2$" "$work/run1/canopy-array.sbatch" || fail "no 3-task array"
state=$(wait_job "$merge" 300)
[[ "$state" == COMPLETED ]] || fail "merge job $merge ended $state"
[[ "$(wait_job "$array" 10)" == COMPLETED ]] || fail "array job $array did not complete"
python3 "$here/../../tools/compare_records.py" "$work/single" "$work/run1" ||
  fail "the merged records differ from the single run's"

# Pass 2: task 1 cancelled before it runs (each task takes every CPU, so they run one by one).
"$bench" slurm --config "$work/small.json" --shards 3 --out "$work/run2" \
  --cpus-per-task "$(nproc)" --time 00:10:00 --submit >"$work/submit2.txt" ||
  fail "canopy-bench slurm --submit (pass 2) failed"
array=$(sed -n 's/^array job \([0-9]*\).*/\1/p' "$work/submit2.txt")
scancel "${array}_1" || fail "scancel ${array}_1 failed"
wait_job "$array" 300 >/dev/null
[[ ! -e "$work/run2/metrics.jsonl" ]] || fail "the merge ran although task 1 was cancelled"
# The merge run now (as a job, no dependency) refuses and names the shard and the rerun.
if sbatch --wait --quiet "$work/run2/canopy-merge.sbatch"; then
  fail "the merge succeeded with shard 1 missing"
fi
grep -q "shard 1/3" "$work/run2/logs/merge.err" || fail "the merge's error does not name shard 1/3"
grep -q "sbatch --array=1 " "$work/run2/logs/merge.err" || fail "the merge's error gives no rerun"
cat "$work/run2/logs/merge.err"
rerun=$(sbatch --parsable --array=1 "$work/run2/canopy-array.sbatch") || fail "rerun not submitted"
merge=$(sbatch --parsable --dependency="afterok:${rerun%%;*}" --kill-on-invalid-dep=yes \
  "$work/run2/canopy-merge.sbatch") || fail "second merge not submitted"
state=$(wait_job "${merge%%;*}" 300)
[[ "$state" == COMPLETED ]] || fail "merge job after the rerun ended $state"
python3 "$here/../../tools/compare_records.py" "$work/single" "$work/run2" ||
  fail "after the rerun, the merged records differ from the single run's"
echo "PASSED: 3-shard array merged equal to the single run, before and after a cancelled task"
