#!/usr/bin/env bash
# A throw-away single-node Slurm cluster on 127.0.0.1 (Debian 12's Slurm 22.05), for trying the
# Slurm engine on one machine and for scripts/sweep/test_slurm.sh. Everything (configuration,
# state, spool, logs, process ids) lives in DIR; nothing else on the machine is touched, and
# `stop` stops only the two daemons `start` started, by their process ids. Needs root (slurmd
# launches the tasks) and the packages (scripts/setup.sh --slurm).
#   local_cluster.sh start DIR [MAX_ARRAY_SIZE]   then: export SLURM_CONF=DIR/slurm.conf
#   local_cluster.sh stop DIR
# No authentication (AuthType=auth/none): for a test machine only.
set -euo pipefail
cmd=${1:-} dir=${2:-}
if [ -z "$cmd" ] || [ -z "$dir" ]; then echo "usage: local_cluster.sh start|stop DIR [MAX_ARRAY_SIZE]" >&2; exit 2; fi
case $cmd in
  start)
    for p in slurmctld slurmd sinfo; do
      command -v "$p" >/dev/null || { echo "local_cluster: $p not found: run scripts/setup.sh --slurm" >&2; exit 1; }
    done
    mkdir -p "$dir"
    dir=$(cd "$dir" && pwd)
    if [ -s "$dir/pids" ]; then echo "local_cluster: $dir already has a cluster (stop it first)" >&2; exit 1; fi
    mkdir -p "$dir/state" "$dir/spool" "$dir/log"
    : >"$dir/plugstack.conf"
    port=$((20000 + $$ % 20000))
    hardware=$(slurmd -C | head -n 1)  # NodeName=... CPUs=... RealMemory=... (without it any --mem fails)
    cat >"$dir/slurm.conf" <<CONF
ClusterName=rtutest
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/none
CredType=cred/none
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
PlugStackConfig=$dir/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
MaxArraySize=${3:-1001}
$hardware NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=rtutest Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF=$dir/slurm.conf
    slurmctld -D -c -f "$SLURM_CONF" >"$dir/log/slurmctld.out" 2>&1 &
    echo $! >"$dir/pids"
    slurmd -D -f "$SLURM_CONF" >"$dir/log/slurmd.out" 2>&1 &
    echo $! >>"$dir/pids"
    for _ in $(seq 60); do
      if sinfo -h -o %T 2>/dev/null | grep -q idle; then
        echo "local_cluster: up: $(sinfo -h -o '%N, %c CPUs, %m MB'); export SLURM_CONF=$SLURM_CONF" >&2
        exit 0
      fi
      sleep 0.5
    done
    echo "local_cluster: the cluster did not come up in 30 s; its logs:" >&2
    tail -n 20 "$dir"/log/* >&2
    "$0" stop "$dir"
    exit 1 ;;
  stop)
    [ -f "$dir/pids" ] || exit 0
    pids=$(cat "$dir/pids")
    for pid in $pids; do kill "$pid" 2>/dev/null || true; done
    for pid in $pids; do
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
    done
    rm -f "$dir/pids" ;;
  *) echo "usage: local_cluster.sh start|stop DIR [MAX_ARRAY_SIZE]" >&2; exit 2 ;;
esac
