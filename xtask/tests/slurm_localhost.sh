#!/usr/bin/env bash
# Runs docs/cluster/run-slurm.sh for real on a one-node Slurm cluster on localhost (Debian's
# slurm-wlm with munge, started here in a temporary directory and stopped on exit): a job
# array of two shards of `eval carmen-angles --quick`, merged, compared with an unsharded
# run. Usage: slurm_localhost.sh <xtask binary> <workspace root>
# Exit 0: equal; 1: they differ or a step failed; 77: Slurm cannot start here (skip).
set -uo pipefail
xtask=$1
root=$2
skip() { echo "skip: $*"; exit 77; }
for tool in munged slurmctld slurmd sbatch sinfo; do
  command -v "$tool" >/dev/null 2>&1 || skip "$tool not installed (Debian: slurm-wlm munge)"
done
[ "$(id -u)" -eq 0 ] || skip "the one-node cluster is started as root only"
tmp=$(mktemp -d)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null; done
  sleep 1
  for pid in "${pids[@]}"; do kill -9 "$pid" 2>/dev/null; done
  [ -n "${KEEP:-}" ] || rm -rf "$tmp"
}
trap cleanup EXIT
mkdir -p "$tmp/state" "$tmp/spool" "$tmp/munge"
chmod 700 "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
socket="$tmp/munge/munge.socket"
munged --foreground --force --key-file="$tmp/munge/munge.key" --socket="$socket" \
  --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/munged.seed" \
  --log-file="$tmp/munge/munged.log" >/dev/null 2>&1 &
pids+=($!)
ports=$(( 20000 + RANDOM % 20000 ))
cat >"$tmp/slurm.conf" <<CONF
ClusterName=raypathtest
SlurmctldHost=localhost
SlurmctldPort=$ports
SlurmdPort=$(( ports + 1 ))
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
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
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$tmp/slurm.conf"
for _ in $(seq 50); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || skip "munged did not start: $(tail -3 "$tmp/munge/munged.log" 2>/dev/null)"
slurmctld -D -i -f "$SLURM_CONF" >"$tmp/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N localhost -f "$SLURM_CONF" >"$tmp/slurmd.out" 2>&1 &
pids+=($!)
state=""
for _ in $(seq 60); do
  state=$(sinfo -h -n localhost -o %T 2>/dev/null | head -1)
  [ "$state" = "idle" ] && break
  sleep 0.5
done
if [ "$state" != "idle" ]; then
  skip "the one-node cluster did not come up (node state '${state:-none}'): $(tail -2 "$tmp/slurmctld.log" "$tmp/slurmd.log" 2>/dev/null | tr '\n' ' ')"
fi
echo "one-node Slurm cluster up ($(sinfo -V))"
cd "$tmp" || exit 1
export XTASK="$xtask"
# The shards and the merge write under RAYPATH_EVAL_OUT, never into the checkout.
RAYPATH_EVAL_OUT="$tmp/sharded" "$root/docs/cluster/run-slurm.sh" carmen-angles 2 --quick || {
  echo "run-slurm.sh failed"; tail -20 "$tmp"/slurm-*.out; exit 1; }
RAYPATH_EVAL_OUT="$tmp/whole" "$xtask" eval carmen-angles --quick >/dev/null 2>"$tmp/whole.err" || {
  echo "unsharded run failed"; cat "$tmp/whole.err"; exit 1; }
page() { grep -v -e '^- Date (UTC):' -e '^- Run time:' "$1/docs/results/carmen-angles.md"; }
if ! diff <(page "$tmp/whole") <(page "$tmp/sharded"); then
  echo "the merged report differs from the unsharded one"
  exit 1
fi
python3 - "$tmp/whole/target/eval/carmen-angles.json" "$tmp/sharded/target/eval/carmen-angles.json" <<'PY' || exit 1
import json, sys
a, b = (json.load(open(p))["results"] for p in sys.argv[1:])
sys.exit(0 if a == b else "the merged JSON results differ from the unsharded ones")
PY
shards=$(ls "$tmp/sharded/target/eval/shards/carmen-angles")
echo "job array of 2 shards ($(echo $shards)) merged: report equal to the unsharded run"
