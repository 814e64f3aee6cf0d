#!/usr/bin/env bash
# Submits one Snakemake job script to Slurm; prints the job id (for status.sh).
#   submit.sh RULE THREADS MEM_MB RUNTIME_MIN EXCLUSIVE JOBSCRIPT
# Timing cells (EXCLUSIVE=1) get a whole node: another job sharing the node's cores, memory
# bandwidth and last-level cache would change their times. Everything else shares nodes.
set -euo pipefail
rule=$1 threads=$2 mem=$3 runtime=$4 exclusive=$5 jobscript=$6
logs=${RAYLAB_SLURM_LOGS:-out/slurm-logs}
mkdir -p "$logs"
args=(--parsable --job-name="raylab-$rule" --cpus-per-task="$threads" --mem="$mem" --time="$runtime"
      --output="$logs/$rule-%j.log")
if [ "$exclusive" = 1 ]; then args+=(--exclusive); fi
# shellcheck disable=SC2086  # site options, word-split on purpose
exec sbatch "${args[@]}" ${RAYLAB_SBATCH_ARGS:-} "$jobscript"
