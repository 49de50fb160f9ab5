#!/usr/bin/env bash
# A private single-node Slurm cluster on localhost for the tests of scripts/*.slurm (CTest fixture, issue 37).
#
#   bash slurm_cluster.sh start STATE   # munged + slurmctld + slurmd; returns once the node is idle
#   source STATE/env                    # SLURM_CONF for the clients (sbatch, squeue, scontrol, ...)
#   bash slurm_cluster.sh stop STATE    # stops exactly the daemons `start` started (by pid), removes STATE
#
# Everything is private: a generated munge key and its own munged socket (never /etc/munge or the system socket),
# a slurm.conf with free ports off Slurm's defaults, state, spool, pid and log files under one temporary folder.
# Daemons the Debian packages' install scripts may have started (the system munged, a slurmd on 6818) are left
# alone and do not clash. The node is this machine as `slurmd -C` reports it (CPUs, sockets, cores, memory).
#
# Exit codes of start: 0 the cluster is up; 77 (CTest's skip) when slurm-wlm or munge is not installed, with one
# line saying so, except under CI=true where that is a failure (1); 1 when a daemon does not start or the node
# does not become idle within 60 s (with the daemons' logs). STATE is a folder only this script writes; the
# daemons' files live in a mktemp folder it names (unix sockets must stay under 108 bytes).
set -uo pipefail

cmd=${1:-}
state=${2:-}
[[ ( $cmd == start || $cmd == stop ) && -n $state ]] || { echo "usage: $0 start|stop STATE_DIR" >&2; exit 2; }

cluster_stop() {
  local root pid name
  [[ -f $state/root ]] || { rm -rf "$state"; return 0; }
  root=$(<"$state/root")
  # Reverse start order; each pid file was written by the daemon we started (its own pid file path).
  for name in slurmd slurmctld munged; do
    [[ -f $root/run/$name.pid ]] || continue
    pid=$(<"$root/run/$name.pid")
    [[ $pid =~ ^[0-9]+$ ]] || continue
    kill -TERM "$pid" 2>/dev/null || continue
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2>/dev/null && kill -KILL "$pid" 2>/dev/null
  done
  [[ $root == */hf-slurm.* ]] && rm -rf "$root"
  rm -rf "$state"
}

if [[ $cmd == stop ]]; then
  cluster_stop
  exit 0
fi

cluster_fail() {  # one line, then the logs, then exit 1 (CI) or 77 (skip) as decided by the caller
  echo "slurm cluster: $1" >&2
  local f
  for f in "${root:-/nonexistent}"/log/*.log; do
    [[ -s $f ]] && { echo "--- $f" >&2; tail -n 20 "$f" >&2; }
  done
  cluster_stop
  exit 1
}

cluster_stop  # a stale STATE from an interrupted run: stop what it started (before any skip, so no test uses it)
missing=()
for exe in munged mungekey slurmctld slurmd sbatch sinfo scontrol; do
  command -v "$exe" >/dev/null || [[ -x /usr/sbin/$exe ]] || missing+=("$exe")
done
if ((${#missing[@]})); then
  if [[ ${CI:-} == true ]]; then
    echo "slurm cluster: CI=true but ${missing[*]} not installed (Debian slurm-wlm and munge, scripts/setup.sh)" >&2
    exit 1
  fi
  echo "slurm cluster: skipped: ${missing[*]} not installed (Debian slurm-wlm and munge; bash scripts/setup.sh)"
  exit 77
fi
PATH=$PATH:/usr/sbin

mkdir -p "$state"
root=$(mktemp -d "${TMPDIR:-/tmp}/hf-slurm.XXXXXX") || cluster_fail "cannot create a temporary folder"
echo "$root" > "$state/root"
mkdir -p "$root"/{run,log,munge,state,spool} && chmod 700 "$root/munge"

# munge: a fresh key and a private socket.
mungekey --create --keyfile="$root/munge/munge.key" >/dev/null 2>&1 ||
  { dd if=/dev/urandom of="$root/munge/munge.key" bs=1024 count=1 2>/dev/null && chmod 600 "$root/munge/munge.key"; } ||
  cluster_fail "cannot create a munge key"
socket=$root/munge/munge.socket
munged --force --key-file="$root/munge/munge.key" --socket="$socket" --pid-file="$root/run/munged.pid" \
  --log-file="$root/log/munged.log" --seed-file="$root/munge/munged.seed" 2>>"$root/log/munged.log" ||
  cluster_fail "munged did not start"

# Two free TCP ports off Slurm's defaults (6817/6818): several worktrees may run this suite at once.
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
for _ in $(seq 100); do
  ctl_port=$((20000 + RANDOM % 30000))
  port_free "$ctl_port" && port_free $((ctl_port + 1)) && break
done
host=$(hostname -s)
user=$(id -un)
# The node as slurmd sees it (CPUs, boards, sockets, cores, threads, RealMemory), so it is not drained for a
# configuration that overstates the machine.
node=$(slurmd -C 2>/dev/null | head -n 1 | sed "s/^NodeName=[^ ]*/NodeName=$host NodeAddr=127.0.0.1/")
[[ $node == NodeName=* ]] || cluster_fail "slurmd -C did not describe this node"
conf=$root/slurm.conf
cat > "$conf" <<EOF
# Written by tests/scripts/slurm_cluster.sh: a private single-node cluster, removed by its stop.
ClusterName=hftest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
SlurmctldPort=$ctl_port
SlurmdPort=$((ctl_port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$root/state
SlurmdSpoolDir=$root/spool
SlurmctldPidFile=$root/run/slurmctld.pid
SlurmdPidFile=$root/run/slurmd.pid
SlurmctldLogFile=$root/log/slurmctld.log
SlurmdLogFile=$root/log/slurmd.log
JobCompType=jobcomp/filetxt
JobCompLoc=$root/log/jobcomp.txt
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
# Memory is scheduled: a job without --mem gets this per CPU instead of the whole node.
DefMemPerCPU=512
ReturnToService=2
MpiDefault=none
SchedulerType=sched/backfill
# Schedule at every event instead of batching for Slurm's default 3 s: a dependent merge starts as soon as its
# array ends (each wave of tasks waited 3 s before; a 6-tile run took 12 s of scheduling instead of 4).
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=600
KillWait=5
$node State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$conf
printf 'export SLURM_CONF=%q\n' "$conf" > "$state/env"

slurmctld -f "$conf" 2>>"$root/log/slurmctld.log" || cluster_fail "slurmctld did not start"
slurmd -f "$conf" 2>>"$root/log/slurmd.log" || cluster_fail "slurmd did not start"
for _ in $(seq 120); do
  st=$(sinfo -h -n "$host" -o %t 2>/dev/null)
  [[ $st == idle ]] && { echo "slurm cluster: $host idle ($node) on port $ctl_port, conf $conf"; exit 0; }
  sleep 0.5
done
cluster_fail "node $host not idle after 60 s (sinfo state '${st:-none}')"
