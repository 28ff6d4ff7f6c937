#!/usr/bin/env bash
# local-cluster.sh start DIR | stop DIR: a one-node Slurm cluster on this machine, all of its
# files in DIR (Debian 12's slurm-wlm and munge: scripts/install-deps.sh --with-slurm).
#
#   scripts/slurm/local-cluster.sh start /tmp/ferro-slurm
#   export SLURM_CONF=/tmp/ferro-slurm/slurm.conf     # start prints this line
#   scripts/shot.sh examples/dish.toml shots/dish --slurm
#   scripts/slurm/local-cluster.sh stop /tmp/ferro-slurm
#
# For trying a shot's Slurm submission without a cluster, and for the test suite. It starts
# munged (its own key and socket in DIR), slurmctld and slurmd as the current user, on two free
# TCP ports, with a node of this machine's cores and memory, one partition `local`, no
# accounting and no cgroups (proctrack/linuxproc, task/none: works in containers). `stop`
# stops the three daemons and leaves DIR for reading the logs (DIR/log).
# Exit codes: 2 bad arguments, 4 slurm-wlm or munge not installed, 1 a daemon did not come up.
set -euo pipefail
die() { echo "local-cluster.sh: error: $1" >&2; exit "${2:-2}"; }
[[ $# == 2 && ( $1 == start || $1 == stop ) ]] || die "usage: local-cluster.sh start|stop DIR"
cmd="$1" dir="$2"

stop() {
  local f
  for f in run/slurmd.pid run/slurmctld.pid munge/munged.pid; do
    [[ -f "$dir/$f" ]] && kill "$(cat "$dir/$f")" 2>/dev/null || true
  done
  # slurmd's job steps (slurmstepd) end with their jobs; wait for the daemons to go.
  for _ in $(seq 50); do
    local alive=0
    for f in run/slurmd.pid run/slurmctld.pid munge/munged.pid; do
      [[ -f "$dir/$f" ]] && kill -0 "$(cat "$dir/$f")" 2>/dev/null && alive=1
    done
    [[ $alive == 0 ]] && break
    sleep 0.2
  done
  rm -f "$dir"/run/*.pid "$dir/munge/munged.pid"
}
if [[ $cmd == stop ]]; then stop; exit 0; fi

for exe in munged slurmctld slurmd sbatch; do
  command -v "$exe" >/dev/null || [[ -x /usr/sbin/$exe ]] || die "$exe not found (scripts/install-deps.sh --with-slurm)" 4
done
export PATH="$PATH:/usr/sbin"
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
stop
mkdir -p "$dir"/{munge,key,state,spool,log,run}
# munged wants its socket's directory open to all and its key private.
chmod 755 "$dir" "$dir/munge"
chmod 700 "$dir/key"
if [[ ! -f "$dir/key/munge.key" ]]; then
  head -c 1024 /dev/urandom > "$dir/key/munge.key"
  chmod 400 "$dir/key/munge.key"
fi
munged --key-file="$dir/key/munge.key" --socket="$dir/munge/munge.socket" \
  --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/seed" \
  || die "munged did not start (see $dir/munge/munged.log)" 1

# Two free ports (the kernel picks them), so a real Slurm on this machine is not disturbed.
read -r ctld_port slurmd_port < <(python3 -c 'import socket
s=[socket.socket() for _ in range(2)]
[x.bind(("127.0.0.1", 0)) for x in s]
print(*[x.getsockname()[1] for x in s])')
user="$(id -un)"
cpus="$(nproc)"
mem_mb="$(( $(awk '/MemTotal/ { print $2 }' /proc/meminfo) / 1024 - 512 ))"
cat > "$dir/slurm.conf" <<CONF
# Written by scripts/slurm/local-cluster.sh: a one-node cluster on localhost.
ClusterName=ferro-local
SlurmctldHost=localhost
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CryptoType=crypto/munge
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
# The main and the backfill scheduler every second (defaults 60 s and 30 s), at most every
# 0.1 s on events: a frame task whose frame is published starts within a second. The suite's
# Slurm test, run alone: 60 s with sched_interval=2 only, 50 s with these (2026-12-08).
SchedulerParameters=sched_interval=1,bf_interval=1,sched_min_interval=100000
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MaxArraySize=100001
MinJobAge=600
NodeName=localhost CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -i || die "slurmctld did not start (see $dir/log/slurmctld.log)" 1
slurmd || die "slurmd did not start (see $dir/log/slurmd.log)" 1
for _ in $(seq 100); do
  if sinfo -h -o %T 2>/dev/null | grep -q idle; then
    echo "export SLURM_CONF=$dir/slurm.conf"
    exit 0
  fi
  sleep 0.2
done
die "the node did not come up idle (see $dir/log)" 1
