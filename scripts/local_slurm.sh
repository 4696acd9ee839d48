#!/usr/bin/env bash
# A one-machine Slurm cluster in a folder, for the tests and for trying `--run.scheduler slurm`:
#   scripts/local_slurm.sh start DIR   starts munged, slurmctld and slurmd on loopback, configured in DIR (one node
#                                      with every CPU of this machine, partition p2n); then
#                                      `export SLURM_CONF=DIR/slurm.conf` points sbatch, squeue and scancel at it
#   scripts/local_slurm.sh stop DIR    stops them
# Needs Debian's munge, slurmctld, slurmd and slurm-client (scripts/install_deps.sh installs them).
set -euo pipefail
command="${1:-}"
dir="${2:-}"
if [ -z "$dir" ] || { [ "$command" != start ] && [ "$command" != stop ]; }; then
  echo "usage: scripts/local_slurm.sh start|stop DIR" >&2
  exit 2
fi
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"

stop() {
  for daemon in slurmd slurmctld munged; do
    if [ -f "$dir/$daemon.pid" ]; then
      pid="$(cat "$dir/$daemon.pid")"
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
      rm -f "$dir/$daemon.pid"
    fi
  done
}

# A TCP port of loopback that nothing listens on.
free_port() {
  local port
  for port in $(shuf -i 20000-40000 -n 50); do
    if ! (echo >"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
      echo "$port"
      return
    fi
  done
  echo "local_slurm.sh: no free port found" >&2
  exit 1
}

if [ "$command" = stop ]; then
  stop
  exit 0
fi

for program in munged slurmctld slurmd sbatch; do
  if ! command -v "$program" >/dev/null && [ ! -x "/usr/sbin/$program" ]; then
    echo "local_slurm.sh: $program is missing; install munge, slurmctld, slurmd and slurm-client" >&2
    exit 1
  fi
done
export PATH="$PATH:/usr/sbin"
stop
rm -rf "$dir/state" "$dir/spool" "$dir/log"
mkdir -p "$dir/state" "$dir/spool" "$dir/log"
if [ ! -f "$dir/munge.key" ]; then
  dd if=/dev/urandom of="$dir/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge.key"
fi
# A Unix socket's path holds at most 107 bytes: a deep folder's socket goes to /tmp.
socket="$dir/munge.sock"
[ ${#socket} -gt 100 ] && socket="/tmp/p2n-munge-$(echo "$dir" | sha1sum | cut -c1-12).sock"
munged --force --key-file="$dir/munge.key" --socket="$socket" --pid-file="$dir/munged.pid" \
  --log-file="$dir/log/munged.log" --seed-file="$dir/munge.seed"

host="$(hostname -s)"
user="$(id -un)"
memory_mb=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 * 9 / 10))
cat >"$dir/slurm.conf" <<EOF
# A one-machine cluster for photo2nerf's tests (scripts/local_slurm.sh).
ClusterName=p2n
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
# cred_expire: how long a job Slurm requeues (its node failed) waits to start again; 120 s by default.
AuthInfo=socket=$socket,cred_expire=10
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
# Memory counted as CPUs are (a job without --mem has half of a CPU's share), so that --mem is a limit.
SelectTypeParameters=CR_CPU_Memory
DefMemPerCPU=$((memory_mb / $(nproc) / 2))
SchedulerType=sched/backfill
ReturnToService=2
# A job above the memory it asked for (--mem) is killed ("Exceeded job memory limit"), as by a cluster's cgroups.
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherParams=OverMemoryKill
JobAcctGatherFrequency=task=1
AccountingStorageType=accounting_storage/none
MpiDefault=none
InactiveLimit=0
KillWait=5
MinJobAge=600
NodeName=p2n-node NodeHostname=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory_mb State=UNKNOWN
PartitionName=p2n Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF" -N p2n-node
for _ in $(seq 100); do
  if [ "$(sinfo --noheader --format=%T 2>/dev/null)" = idle ]; then
    echo "local Slurm up: export SLURM_CONF=$SLURM_CONF"
    exit 0
  fi
  sleep 0.3
done
echo "local_slurm.sh: the node did not come up; see $dir/log" >&2
tail -5 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
stop
exit 1
