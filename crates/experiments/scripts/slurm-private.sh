#!/usr/bin/env bash
# A private one-node Slurm cluster under a directory of its own, for tests and for trying
# `lt submit --slurm` on a laptop. Nothing outside DIR is written: configuration, state, spool,
# logs and pid files all live in it, the ports are explicit, and the node's name (ltnode) does not
# depend on the host's name. Authentication is off (auth/none, cred/none), process tracking is by
# /proc (proctrack/linuxproc) and there is no task binding (task/none), so no munge, cgroups or
# systemd are needed. Run as root (SlurmUser=root).
#
#   slurm-private.sh start DIR [CTLD_PORT [SLURMD_PORT]]   start both daemons, wait for the node
#   slurm-private.sh stop DIR                              cancel every job, stop both daemons
#   slurm-private.sh env DIR                               print `export SLURM_CONF=…`
#
# Clients (sbatch, squeue, scontrol, scancel) find the cluster through SLURM_CONF=DIR/slurm.conf.
set -euo pipefail

cmd=${1:-}
dir=${2:-}
if [[ -z "$cmd" || -z "$dir" ]]; then
  echo "usage: $0 start|stop|env DIR [CTLD_PORT [SLURMD_PORT]]" >&2
  exit 2
fi
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
conf="$dir/slurm.conf"
export SLURM_CONF="$conf"

# A free TCP port at or above $1 (nothing listening on it).
free_port() {
  local p=$1
  while ss -ltnH 2>/dev/null | awk '{print $4}' | grep -qE "[:.]$p\$"; do
    p=$((p + 1))
  done
  echo "$p"
}

start() {
  for b in slurmctld slurmd sbatch sinfo; do
    command -v "$b" >/dev/null || { echo "slurm-private: $b is not installed (apt-get install slurmctld slurmd slurm-client)" >&2; exit 3; }
  done
  mkdir -p "$dir/state" "$dir/spool" "$dir/log"
  local ctld_port=${3:-$(free_port $((20000 + $$ % 20000)))}
  local slurmd_port=${4:-$(free_port $((ctld_port + 1)))}
  local host cpus mem
  host=$(hostname -s 2>/dev/null || cut -d. -f1 /proc/sys/kernel/hostname)
  cpus=$(nproc)
  mem=$(awk '/MemTotal/ {print int($2 / 1024 / 2)}' /proc/meminfo)
  cat >"$conf" <<EOF
# Written by slurm-private.sh: a one-node cluster living in $dir.
ClusterName=ltprivate
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/none
CredType=cred/none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
SlurmdParameters=config_overrides
MinJobAge=600
KillWait=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
NodeName=ltnode NodeAddr=127.0.0.1 NodeHostname=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=lt Nodes=ltnode Default=YES MaxTime=INFINITE State=UP
EOF
  # -i: ignore state left by an earlier cluster in this directory.
  slurmctld -f "$conf" -i
  slurmd -f "$conf" -N ltnode
  local i
  for i in $(seq 1 150); do
    if sinfo -h -N -n ltnode -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
      echo "export SLURM_CONF=$conf"
      return 0
    fi
    sleep 0.2
  done
  echo "slurm-private: the node did not come up within 30 s; logs in $dir/log:" >&2
  tail -n 20 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
  stop
  exit 4
}

# Ends the daemon whose pid file is $1 (TERM, then KILL after 5 s).
end_daemon() {
  local pidfile=$1 pid i
  [[ -f "$pidfile" ]] || return 0
  pid=$(cat "$pidfile" 2>/dev/null || true)
  [[ -n "$pid" ]] || return 0
  kill -TERM "$pid" 2>/dev/null || return 0
  for i in $(seq 1 50); do
    kill -0 "$pid" 2>/dev/null || return 0
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null || true
}

stop() {
  if [[ -f "$conf" ]]; then
    scancel --quiet --full --partition=lt 2>/dev/null || true
    # Give the job steps a moment to end before their slurmd goes.
    local i
    for i in $(seq 1 30); do
      [[ -z "$(squeue -h -t RUNNING,COMPLETING -o %i 2>/dev/null)" ]] && break
      sleep 0.1
    done
  fi
  end_daemon "$dir/slurmd.pid"
  end_daemon "$dir/slurmctld.pid"
  return 0
}

case "$cmd" in
  start) start "$@" ;;
  stop) stop ;;
  env) echo "export SLURM_CONF=$conf" ;;
  *) echo "unknown command $cmd" >&2; exit 2 ;;
esac
