#!/usr/bin/env bash
# Starts a single-node Slurm cluster on this machine (Debian's slurm-wlm and munge): munged,
# slurmctld and slurmd on localhost, one node with this machine's CPUs and one GPU "gres", for
# trying the job-array recipe (render-array.sh) and for the test that runs it. Needs root.
#
#   source scripts/slurm/local-cluster.sh DIR    # starts it; exports SLURM_CONF
#   scripts/slurm/local-cluster.sh --stop DIR    # stops it
#
# State, logs and configuration live in DIR. Without slurm-wlm and munge: apt-get install
# slurm-wlm munge.
set -euo pipefail

stop=0
if [[ "${1:-}" == "--stop" ]]; then
    stop=1
    shift
fi
dir=$(realpath -m "${1:?usage: local-cluster.sh [--stop] DIR}")

if ((stop)); then
    for daemon in slurmd slurmctld; do
        [[ -f "$dir/$daemon.pid" ]] && kill "$(cat "$dir/$daemon.pid")" 2>/dev/null || true
    done
    [[ -f "$dir/munged.pid" ]] && kill "$(cat "$dir/munged.pid")" 2>/dev/null || true
    return 0 2>/dev/null || exit 0
fi

mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
chown munge:munge "$dir/munge"
host=$(hostname -s)
cpus=$(nproc)
# Ports of our own, so that a cluster already on the machine is left alone.
ctld_port=${RT_GPU_SLURMCTLD_PORT:-16817}
slurmd_port=${RT_GPU_SLURMD_PORT:-16818}

# munge authenticates Slurm's messages; the package made a key in /etc/munge.
if [[ ! -S "$dir/munge/munge.socket" ]]; then
    runuser -u munge -- /usr/sbin/munged --socket="$dir/munge/munge.socket" \
        --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
        --seed-file="$dir/munge/munged.seed"
    cp "$dir/munge/munged.pid" "$dir/munged.pid"
fi

cat >"$dir/slurm.conf" <<CONF
ClusterName=rtgpu
SlurmctldHost=$host
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
SchedulerType=sched/builtin
GresTypes=gpu
NodeName=$host CPUs=$cpus RealMemory=1024 Gres=gpu:1 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
# One GPU "gres" the jobs can ask for with --gres=gpu:1 (here lavapipe, or the real one).
echo "NodeName=$host Name=gpu File=/dev/null" >"$dir/gres.conf"
export SLURM_CONF=$dir/slurm.conf

/usr/sbin/slurmctld -f "$SLURM_CONF"
/usr/sbin/slurmd -f "$SLURM_CONF"
for _ in $(seq 100); do
    if sinfo -h -o %t 2>/dev/null | grep -qx idle; then
        break
    fi
    sleep 0.2
done
sinfo -h -o %t | grep -qx idle || {
    echo "local-cluster.sh: the node did not come up; see $dir/slurmctld.log and $dir/slurmd.log" >&2
    exit 1
}
