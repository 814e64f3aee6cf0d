#!/usr/bin/env bash
# A one-node Slurm cluster on this machine (Debian's slurm-wlm and munge), for running the
# benchmark workflow through a real scheduler without a cluster.
#
#   scripts/slurm-local.sh start     # write the configuration, start munged, slurmctld, slurmd
#   scripts/slurm-local.sh stop      # stop the daemons this script started
#   scripts/slurm-local.sh status    # sinfo / squeue
#   scripts/slurm-local.sh env       # print `export SLURM_CONF=...` for sbatch/squeue by hand
#   scripts/slurm-local.sh test      # start; the quick workflow locally and through Slurm;
#                                    # compare the records cell by cell; stop (make bench-slurm-local)
#
# Everything (configuration, munge key and socket, spool, state, logs, pid files) lives in
# STATE (default /tmp/raylab-slurm-$UID); nothing in /etc is touched, the daemons listen on
# ports 6917/6918 (not Slurm's defaults) and client commands find the cluster via SLURM_CONF.
# The node gets this machine's cores and memory (`slurmd -C`). Made for containers: process
# tracking by /proc (proctrack/linuxproc), no task binding or cgroup plugins (task/none), no
# accounting database; cons_tres with cores and memory as consumable resources.
#
# Environment: BUILD (default build), STATE, OUT_LOCAL (default out/bench: a `make bench` run
# there is reused, Snakemake reruns nothing), OUT_SLURM (default out/bench-slurm).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
STATE=${STATE:-/tmp/raylab-slurm-$(id -u)}
OUT_LOCAL=${OUT_LOCAL:-out/bench}
OUT_SLURM=${OUT_SLURM:-out/bench-slurm}
CTLD_PORT=6917
SLURMD_PORT=6918
export SLURM_CONF=$STATE/slurm.conf

say() { echo "slurm-local: $*" >&2; }
die() { say "$*"; exit 1; }

write_config() {
  mkdir -p "$STATE"/{munge,ctld,slurmd,log,run}
  chmod 700 "$STATE" "$STATE/munge"
  if [ ! -s "$STATE/munge/munge.key" ]; then
    # A fresh key for this private cluster only (1024 random bytes, as mungekey makes).
    dd if=/dev/urandom of="$STATE/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$STATE/munge/munge.key"
  fi
  local node host
  host=$(hostname -s)
  # "NodeName=vm CPUs=2 Boards=1 SocketsPerBoard=1 CoresPerSocket=2 ThreadsPerCore=1 RealMemory=24105"
  node=$(slurmd -C | head -1)
  [[ $node == NodeName=* ]] || die "slurmd -C printed no node line"
  # Leave 512 MB to the OS and the daemons.
  local mem=${node##*RealMemory=}
  mem=${mem%% *}
  node=${node/RealMemory=$mem/RealMemory=$((mem - 512))}
  cat > "$SLURM_CONF" <<EOF
# Written by scripts/slurm-local.sh: a one-node cluster on $host.
ClusterName=raylab-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=$(id -un)
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$STATE/munge/munge.socket
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/slurmd
SlurmctldPidFile=$STATE/run/slurmctld.pid
SlurmdPidFile=$STATE/run/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
# A container: processes tracked through /proc, no cgroups, no CPU binding by Slurm
# (the workflow pins one-thread cells itself), no accounting database.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
SlurmdTimeout=300
InactiveLimit=0
KillWait=10
MinJobAge=3600
${node/NodeName=$host/NodeName=$host NodeAddr=127.0.0.1} State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

pid_alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

start() {
  command -v slurmctld >/dev/null && command -v munged >/dev/null ||
    die "slurm-wlm and munge are not installed (bash scripts/install-deps.sh)"
  write_config
  if ! pid_alive "$STATE/run/munged.pid"; then
    # --force: munged refuses some root-owned or shared setups by default; this key and
    # socket directory are private to this script.
    munged --force --key-file="$STATE/munge/munge.key" --socket="$STATE/munge/munge.socket" \
      --pid-file="$STATE/run/munged.pid" --log-file="$STATE/log/munged.log" \
      --seed-file="$STATE/munge/munged.seed"
  fi
  pid_alive "$STATE/run/slurmctld.pid" || slurmctld -f "$SLURM_CONF"
  pid_alive "$STATE/run/slurmd.pid" || slurmd -f "$SLURM_CONF"
  local i
  for i in $(seq 1 60); do
    if sinfo -h -o '%T' 2>/dev/null | grep -Eq '^(idle|mixed|allocated)'; then
      say "up: $(sinfo -h -o '%N %c CPUs %m MB %T')"
      return 0
    fi
    sleep 1
  done
  say "the node did not come up; logs in $STATE/log"
  tail -n 20 "$STATE"/log/*.log >&2 || true
  stop
  exit 1
}

stop_daemon() {  # name, pid file: SIGTERM, then wait up to 20 s for the process to end
  local pidfile=$2 pid i
  [ -s "$pidfile" ] || return 0
  pid=$(cat "$pidfile")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid" 2>/dev/null || true
    for i in $(seq 1 40); do kill -0 "$pid" 2>/dev/null || break; sleep 0.5; done
    kill -0 "$pid" 2>/dev/null && say "$1 (pid $pid) did not stop"
  fi
  rm -f "$pidfile"
}

stop() {
  if [ -f "$SLURM_CONF" ] && pid_alive "$STATE/run/slurmctld.pid"; then
    scancel --user="$(id -un)" 2>/dev/null || true
  fi
  stop_daemon slurmd "$STATE/run/slurmd.pid"
  stop_daemon slurmctld "$STATE/run/slurmctld.pid"
  stop_daemon munged "$STATE/run/munged.pid"
  say "stopped"
}

run_test() {
  [ -x "$BUILD/raylab" ] || die "$BUILD/raylab not built (make build)"
  start
  trap stop EXIT
  local t0 t1 t2
  t0=$(date +%s)
  say "local run: snakemake --cores $(nproc) -> $OUT_LOCAL"
  snakemake -s workflow/Snakefile --cores "$(nproc)" --config raylab="$BUILD/raylab" out="$OUT_LOCAL" -q
  t1=$(date +%s)
  say "Slurm run: snakemake --profile workflow/profiles/slurm -> $OUT_SLURM"
  snakemake -s workflow/Snakefile --profile workflow/profiles/slurm \
    --config raylab="$BUILD/raylab" out="$OUT_SLURM" -q
  t2=$(date +%s)
  say "wall times: local $((t1 - t0)) s, Slurm $((t2 - t1)) s"
  /usr/bin/python3 workflow/scripts/compare_records.py "$OUT_LOCAL" "$OUT_SLURM"
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) sinfo; squeue ;;
  env) echo "export SLURM_CONF=$SLURM_CONF" ;;
  test) run_test ;;
  *) echo "usage: scripts/slurm-local.sh start|stop|status|env|test" >&2; exit 2 ;;
esac
