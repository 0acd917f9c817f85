#!/usr/bin/env bash
# One task of a Slurm job array submitted by slurm.py: runs the manifest line that LIST names at
# line SLURM_ARRAY_TASK_ID + 1 (LIST holds the manifest indices of the array's runs), with RTSIM and
# SHARED from the submitting environment. sbatch runs a copy of this script from slurmd's spool
# folder, so the worker's path comes as an argument.
# Usage (by sbatch): slurm_task.sh WORKER MANIFEST LIST OUTDIR
set -uo pipefail
worker=$1 manifest=$2 list=$3 outdir=$4
index=$(sed -n "$((SLURM_ARRAY_TASK_ID + 1))p" "$list")
if [ -z "$index" ]; then echo "slurm_task: $list has no line for task $SLURM_ARRAY_TASK_ID" >&2; exit 2; fi
echo "slurm_task: job ${SLURM_ARRAY_JOB_ID:-?} task $SLURM_ARRAY_TASK_ID on $(hostname): manifest line $index" >&2
exec "$worker" "$manifest" "$index" "$outdir"
