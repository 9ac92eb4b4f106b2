#!/usr/bin/env bash
# A throwaway single-node Slurm cluster in a folder, for tests: munged with a generated key,
# slurmctld and slurmd with a generated slurm.conf (no cgroups, no accounting, free ports), all
# state under the folder, all running as the calling user, on 127.0.0.1 (the host name need not
# resolve). Source it, then:
#   slurm_cluster_start DIR   # exports SLURM_CONF; returns non-zero (with the reason on stderr) when
#                             # Slurm is missing or does not come up
#   slurm_cluster_stop        # kills what slurm_cluster_start started (by pid) and nothing else
# The daemons' logs stay in DIR for a failing test to show.

slurm_cluster_pids=()

slurm_cluster_free_port() {
    python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

slurm_cluster_start() {
    local dir=$1
    local tool
    for tool in munged slurmctld slurmd sbatch squeue scontrol sinfo; do
        if ! command -v "$tool" >/dev/null 2>&1 && [[ ! -x /usr/sbin/$tool ]]; then
            echo "slurm_cluster: $tool is not installed (Debian: munge slurmctld slurmd slurm-client)" >&2
            return 1
        fi
    done
    export PATH="$PATH:/usr/sbin"
    mkdir -p "$dir"/{munge,state,spool,log}
    chmod 700 "$dir" "$dir/munge"
    # munge: its own key and socket (the system's daemon, if any, is left alone).
    dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$dir/munge/munge.key"
    local socket=$dir/munge/munge.socket
    munged --force --socket="$socket" --key-file="$dir/munge/munge.key" --pid-file="$dir/munge/munged.pid" \
        --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munge.seed" || {
        echo "slurm_cluster: munged did not start (see $dir/log/munged.log)" >&2
        return 1
    }
    slurm_cluster_pids+=("$(cat "$dir/munge/munged.pid")")

    local host user cpus ctld_port slurmd_port
    host=$(hostname -s)
    user=$(id -un)
    cpus=$(nproc)
    ctld_port=$(slurm_cluster_free_port)
    slurmd_port=$(slurm_cluster_free_port)
    while [[ $slurmd_port == "$ctld_port" ]]; do slurmd_port=$(slurm_cluster_free_port); done
    cat >"$dir/slurm.conf" <<CONF
ClusterName=dynskytest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket,cred_expire=5
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=2
SchedulerParameters=sched_interval=1,defer=0
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:4
CONF
    export SLURM_CONF=$dir/slurm.conf
    slurmctld -D -i -f "$SLURM_CONF" >"$dir/log/slurmctld.out" 2>&1 &
    slurm_cluster_pids+=($!)
    slurmd -D -f "$SLURM_CONF" -N "$host" >"$dir/log/slurmd.out" 2>&1 &
    slurm_cluster_pids+=($!)
    local _
    for _ in $(seq 1 60); do
        if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then return 0; fi
        sleep 0.5
    done
    echo "slurm_cluster: the node did not come up in 30 s; sinfo: $(sinfo -h 2>&1 | head -3)" >&2
    tail -5 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" "$dir/log/slurmctld.out" "$dir/log/slurmd.out" >&2 2>/dev/null
    return 1
}

slurm_cluster_stop() {
    local pid
    for pid in "${slurm_cluster_pids[@]}"; do kill "$pid" 2>/dev/null; done
    for pid in "${slurm_cluster_pids[@]}"; do
        for _ in $(seq 1 20); do kill -0 "$pid" 2>/dev/null || break; sleep 0.25; done
        kill -9 "$pid" 2>/dev/null
    done
    slurm_cluster_pids=()
}
