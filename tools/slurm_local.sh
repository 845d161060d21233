#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for the Slurm tests
# (tests/slurm/) and for trying `--executor slurm` (docs/cluster.md).
#
#   tools/slurm_local.sh start DIR   start munged, slurmctld and slurmd
#   tools/slurm_local.sh stop DIR    stop them (only the ones started in DIR)
#   tools/slurm_local.sh env DIR     print `export SLURM_CONF=...` for a shell
#
# Everything lives in DIR: slurm.conf, its own munge key and socket, the
# state and spool folders, the daemons' logs and pid files. Nothing in /etc
# is touched; commands find the cluster through SLURM_CONF=DIR/slurm.conf.
# Needs root (slurmd starts jobs as their user) and Debian's slurm-wlm and
# munge. The node has this machine's CPUs and memory; jobs are tracked by
# process (proctrack/linuxproc, no cgroups: they work in containers too) and
# a job over its --mem is killed by the accounting poll every second
# (JobAcctGatherParams=OverMemoryKill).
#
# Exit status of start: 0 up, 77 Slurm cannot run here (not root, munged
# refuses, packages missing outside CI; the message says which), 1 it should
# have started but did not (packages missing although CI=true, or slurmctld /
# slurmd failing: a bug in this script or the configuration; the logs are
# printed).
set -uo pipefail

cmd=${1:-}
dir=${2:-}
if [ -z "$cmd" ] || [ -z "$dir" ]; then
  echo "usage: $0 start|stop|env DIR" >&2
  exit 2
fi
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
# Ports apart from a system Slurm's 6817/6818.
ctld_port=${PB_SLURM_CTLD_PORT:-16817}
slurmd_port=${PB_SLURM_SLURMD_PORT:-16818}

stop_pid_file() {
  local f=$1
  [ -s "$f" ] || return 0
  local pid
  pid=$(cat "$f")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  fi
  rm -f "$f"
}

case "$cmd" in
  env)
    echo "export SLURM_CONF=$dir/slurm.conf"
    exit 0
    ;;
  stop)
    stop_pid_file "$dir/slurmd.pid"
    stop_pid_file "$dir/slurmctld.pid"
    stop_pid_file "$dir/munged.pid"
    echo "slurm_local: stopped the cluster in $dir"
    exit 0
    ;;
  start) ;;
  *)
    echo "usage: $0 start|stop|env DIR" >&2
    exit 2
    ;;
esac

skip() { echo "slurm_local: SKIP: $*" >&2; exit 77; }
for tool in munged slurmctld slurmd sbatch scontrol; do
  if ! command -v "$tool" >/dev/null && [ ! -x "/usr/sbin/$tool" ]; then
    # In CI, .ci/setup installs them: missing there is our bug, not the machine's.
    [ "${CI:-}" = true ] && { echo "slurm_local: FAILED: '$tool' is missing although .ci/setup installs slurm-wlm and munge" >&2; exit 1; }
    skip "'$tool' is not installed (apt install slurm-wlm munge; .ci/setup does)"
  fi
done
[ "$(id -u)" = 0 ] || skip "the one-node cluster needs root (slurmd starts jobs as their owner)"
export PATH=$PATH:/usr/sbin

"$0" stop "$dir" >/dev/null
mkdir -p "$dir/state" "$dir/spool" "$dir/munge" "$dir/log"
chmod 700 "$dir/munge"
host=$(hostname -s)
cpus=$(nproc)
mem_mib=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.95 }' /proc/meminfo)

# munge: a key of our own, our own socket.
if [ ! -s "$dir/munge/munge.key" ]; then
  dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge/munge.key"
fi
munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.sock" \
  --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" \
  --seed-file="$dir/munge/munge.seed" ||
  skip "munged does not start here: $(tail -n 3 "$dir/log/munged.log" 2>/dev/null)"

cat > "$dir/slurm.conf" <<EOF
# Written by tools/slurm_local.sh: a one-node cluster for tests.
ClusterName=pointbake-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups: process tracking and task launch that work in containers.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
# Memory is a consumable resource; a job over its --mem is killed by the
# accounting poll (every second) instead of a cgroup limit.
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=task=1
JobAcctGatherParams=OverMemoryKill
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
# Finished jobs stay visible to scontrol for 5 minutes (their state and reason).
MinJobAge=300
SchedulerType=sched/backfill
# Start a job as soon as it is submitted (the default batch_sched_delay
# waits up to 3 s to batch submissions).
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
KillWait=5
InactiveLimit=0
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mib State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$dir/slurm.conf"

fail() {
  echo "slurm_local: FAILED: $*" >&2
  for f in "$dir"/log/*.log; do echo "--- $f" >&2; tail -n 20 "$f" >&2; done
  "$0" stop "$dir" >/dev/null
  exit 1
}
slurmctld -f "$SLURM_CONF" -c -i || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" -c || fail "slurmd did not start"
for _ in $(seq 100); do
  state=$(scontrol show node "$host" 2>/dev/null | sed -n 's/.*State=\([A-Z+_]*\).*/\1/p' | head -n 1)
  case "$state" in
    IDLE*|MIXED*|ALLOCATED*) echo "slurm_local: cluster up in $dir (node $host, $cpus CPUs, $mem_mib MiB; SLURM_CONF=$SLURM_CONF)"; exit 0 ;;
  esac
  sleep 0.2
done
fail "node $host did not become idle (state '${state:-unknown}')"
