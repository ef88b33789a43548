#!/usr/bin/env bash
# Runs a raypath evaluation as a Slurm job array of N shards, then merges them into the
# report a single run writes (docs/results/<eval>.md, target/eval/<eval>.json):
#
#   docs/cluster/run-slurm.sh <eval> <N> [--quick]
#
# From the workspace root, on a file system the compute nodes share; blocks until the merge
# job has finished. Extra sbatch options (partition, account, time) go in SBATCH_* variables
# (for example SBATCH_PARTITION=cpu), which sbatch reads itself.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 <eval> <shards> [--quick]" >&2
  exit 2
fi
name=$1
shards=$2
quick=${3:-}
here=$(cd "$(dirname "$0")" && pwd)
xtask=${XTASK:-target/release/xtask}
export EVAL="$name" XTASK="$xtask"
if [ "$quick" = "--quick" ]; then export QUICK=1; else unset QUICK; fi
# Old shard files of another N would make the merge refuse; start clean.
rm -rf "${RAYPATH_EVAL_OUT:-.}/target/eval/shards/$name"
array=$(sbatch --parsable --array=1-"$shards" --export=ALL "$here/slurm-eval.sh")
echo "job array $array: $shards shards of $name"
sbatch --parsable --wait --job-name=raypath-merge --output=slurm-%j.out \
  --dependency=afterok:"$array" --kill-on-invalid-dep=yes --export=ALL \
  --wrap "\"$xtask\" eval merge \"$name\" $quick"
echo "merged: ${RAYPATH_EVAL_OUT:-.}/docs/results/$name.md"
