#!/usr/bin/env bash
# One shard of a raypath evaluation as a task of a Slurm job array. Submit it through
# run-slurm.sh (which also merges), or by hand from the workspace root:
#
#   sbatch --array=1-4 --export=ALL,EVAL=carmen-angles docs/cluster/slurm-eval.sh
#   # when all tasks are done:
#   target/release/xtask eval merge carmen-angles
#
# Task i of an array of N runs `cargo xtask eval $EVAL --shard i/N`: every N-th unit (log,
# sequence, session …), written to target/eval/shards/$EVAL/ under RAYPATH_EVAL_OUT (default:
# the workspace). The workspace, the built xtask binary and RAYPATH_DATA must be on a file
# system every node sees. QUICK=1 adds --quick; XTASK names the binary (default
# target/release/xtask, built once with `cargo build --release -p xtask`).
#SBATCH --job-name=raypath-eval
#SBATCH --cpus-per-task=2
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail
: "${EVAL:?set EVAL to an evaluation name (cargo xtask eval list)}"
: "${SLURM_ARRAY_TASK_ID:?run as a job array: sbatch --array=1-N}"
count=${SLURM_ARRAY_TASK_COUNT:?run as a job array: sbatch --array=1-N}
index=$(( SLURM_ARRAY_TASK_ID - ${SLURM_ARRAY_TASK_MIN:-1} + 1 ))
quick=()
[ -n "${QUICK:-}" ] && quick=(--quick)
exec "${XTASK:-target/release/xtask}" eval "$EVAL" "${quick[@]}" --shard "$index/$count"
