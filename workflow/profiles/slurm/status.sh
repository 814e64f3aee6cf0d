#!/usr/bin/env bash
# Snakemake's cluster-status hook: prints running, success or failed for a Slurm job id.
# Uses scontrol (no accounting database needed), then sacct for jobs scontrol has forgotten.
set -uo pipefail
id=$1
state=$(scontrol -o show job "$id" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2)
if [ -z "$state" ]; then
  state=$(sacct -n -X -j "$id" -o State 2>/dev/null | head -1 | awk '{print $1}')
fi
case "$state" in
  PENDING|CONFIGURING|RUNNING|COMPLETING|SUSPENDED|REQUEUED|RESIZING|SIGNALING|STAGE_OUT|"") echo running ;;
  COMPLETED) echo success ;;
  *) echo failed ;;
esac
