#!/usr/bin/env bash
# Runs a one-thread timing command pinned to one core: the first core this job may use (its
# Slurm allocation or the whole machine), so the OS cannot move it between cores (and caches)
# in the middle of a measurement.
set -euo pipefail
allowed=$(awk '/^Cpus_allowed_list:/ {print $2}' /proc/self/status)
first=${allowed%%[,-]*}
exec taskset -c "${first:-0}" "$@"
