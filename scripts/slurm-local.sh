#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine, for the sweep tests (issue 27) and for trying
# `pdamp sweep … --backend slurm` without a cluster. Installs Debian's slurm-wlm and munge when
# missing (root), writes a minimal slurm.conf into a runtime folder and starts munged,
# slurmctld and slurmd there; nothing in /etc/slurm is changed.
#
#   eval "$(bash scripts/slurm-local.sh start)"   # starts it and exports SLURM_CONF
#   sbatch --wrap "hostname"; squeue
#   bash scripts/slurm-local.sh stop
#
# The runtime folder is $PDAMP_SLURM_DIR (default: target/slurm-local of this checkout); its
# logs (slurmctld.log, slurmd.log, munged.log) say why a daemon did not come up.
set -euo pipefail
cd "$(dirname "$0")/.."
run=${PDAMP_SLURM_DIR:-$PWD/target/slurm-local}
conf=$run/slurm.conf

log() { echo "slurm-local: $*" >&2; }

install_slurm() {
  if command -v slurmctld >/dev/null 2>&1 && command -v slurmd >/dev/null 2>&1 \
    && command -v munged >/dev/null 2>&1 && command -v sbatch >/dev/null 2>&1; then
    return 0
  fi
  if ! command -v apt-get >/dev/null 2>&1 || [ "$(id -u)" != 0 ]; then
    log "Slurm is not installed and cannot be installed here (needs root and apt-get: slurm-wlm munge)"
    return 1
  fi
  log "installing Debian's slurm-wlm and munge"
  apt-get update -qq >/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
}

stop() {
  for pidfile in "$run/slurmd.pid" "$run/slurmctld.pid" "$run/munged.pid"; do
    if [ -f "$pidfile" ]; then
      pid=$(cat "$pidfile" 2>/dev/null || true)
      if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
        kill "$pid" 2>/dev/null || true
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
      fi
      rm -f "$pidfile"
    fi
  done
}

start() {
  install_slurm
  stop
  mkdir -p "$run/state" "$run/spool" "$run/munge"
  local host cpus
  host=$(hostname -s)
  cpus=$(nproc)
  # munge: its own key and socket in the runtime folder (root needs --force).
  if [ ! -f "$run/munge/munge.key" ]; then
    dd if=/dev/urandom of="$run/munge/munge.key" bs=1024 count=1 status=none
  fi
  chmod 0400 "$run/munge/munge.key"
  chmod 0700 "$run/munge"
  munged --force --key-file="$run/munge/munge.key" --socket="$run/munge/munge.socket" \
    --pid-file="$run/munged.pid" --log-file="$run/munged.log" --seed-file="$run/munge/munge.seed"
  cat > "$conf" <<EOF
# written by scripts/slurm-local.sh: a one-node cluster for pdamp's sweep tests
ClusterName=pdamp-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=${PDAMP_SLURMCTLD_PORT:-16817}
SlurmdPort=${PDAMP_SLURMD_PORT:-16818}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$run/munge/munge.socket
StateSaveLocation=$run/state
SlurmdSpoolDir=$run/spool
SlurmctldPidFile=$run/slurmctld.pid
SlurmdPidFile=$run/slurmd.pid
SlurmctldLogFile=$run/slurmctld.log
SlurmdLogFile=$run/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MaxArraySize=1001
MinJobAge=300
KillWait=5
SlurmdTimeout=60
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF=$conf
  slurmctld -f "$conf" -i
  slurmd -f "$conf"
  # Up when the node answers idle (the controller needs a moment to register it).
  for _ in $(seq 100); do
    if sinfo -h -o '%t' 2>/dev/null | grep -Eq '^(idle|mix|alloc)'; then
      log "up: 1 node ($host, $cpus CPUs), partition debug; SLURM_CONF=$conf"
      echo "export SLURM_CONF=$conf"
      return 0
    fi
    sleep 0.2
  done
  log "the cluster did not come up; see $run/slurmctld.log and $run/slurmd.log"
  tail -n 20 "$run/slurmctld.log" "$run/slurmd.log" >&2 || true
  stop
  return 1
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  *) echo "usage: $0 start|stop" >&2; exit 2 ;;
esac
