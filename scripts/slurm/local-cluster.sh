#!/usr/bin/env bash
# Starts a single-node Slurm on this machine for the CI check (and for trying
# the job-array scripts on a workstation): munged, slurmctld and slurmd on
# localhost, with a minimal slurm.conf written to $DIR (default
# /tmp/riglab-slurm). Needs root and Debian's slurm-wlm and munge packages.
# Prints `export SLURM_CONF=...`; `local-cluster.sh stop DIR` stops the
# daemons it started (by their pid files).
set -euo pipefail
cmd=${1:-start}
dir=${2:-/tmp/riglab-slurm}
if [ "$cmd" = stop ]; then
    for pid in "$dir"/slurmd.pid "$dir"/slurmctld.pid "$dir"/munged.pid; do
        [ -f "$pid" ] && kill "$(cat "$pid")" 2>/dev/null || true
    done
    exit 0
fi
mkdir -p "$dir"/state "$dir"/spool "$dir"/munge
host=$(hostname -s)
cpus=$(nproc)
mem_mb=$(awk '/MemTotal/ {print int($2 / 1024) - 512}' /proc/meminfo)
cat > "$dir/slurm.conf" <<CONF
# Minimal single-node Slurm (rig-lab scripts/slurm/local-cluster.sh).
ClusterName=riglab
SlurmctldHost=$host(127.0.0.1)
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf
# munge: the packaged key, a private socket, run as root with --force.
munged --force --socket="$dir/munge/munge.socket" --pid-file="$dir/munged.pid" \
    --log-file="$dir/munged.log" --seed-file="$dir/munge/seed"
export MUNGE_SOCKET=$dir/munge/munge.socket
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
# Wait until the node takes jobs.
for _ in $(seq 1 30); do
    if sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then
        echo "export SLURM_CONF=$SLURM_CONF"
        exit 0
    fi
    sleep 1
done
echo "local-cluster: the node did not come up; see $dir/*.log" >&2
exit 1
