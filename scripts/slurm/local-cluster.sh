#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for testing genpath's Slurm pipeline (CI runs
# it through scripts/slurm/ci.sh). As root, on Debian:
#
#   bash scripts/slurm/local-cluster.sh start   # installs slurm-wlm and munge if missing,
#                                               # starts munged, slurmctld and slurmd
#   bash scripts/slurm/local-cluster.sh stop    # stops the daemons this script started
#
# The configuration lives in $GENPATH_SLURM_DIR (default /tmp/genpath-slurm): slurm.conf
# with this machine's CPUs and memory, proctrack/linuxproc and task/none (the cgroup plugins
# need a delegated cgroup tree, which containers and CI runners seldom give), and the
# daemons' state, logs and pid files. Slurm's tools find it through SLURM_CONF, which
# `start` prints for the caller to export.
set -euo pipefail
dir=${GENPATH_SLURM_DIR:-/tmp/genpath-slurm}
conf=$dir/slurm.conf

install_packages() {
    local missing=() p
    for p in slurm-wlm munge; do
        [[ $(dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null) == "ii " ]] || missing+=("$p")
    done
    ((${#missing[@]} == 0)) && return
    echo "installing ${missing[*]}"
    DEBIAN_FRONTEND=noninteractive apt-get -q -o Acquire::Retries=3 update >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get -q -y -o Acquire::Retries=3 install \
        --no-install-recommends "${missing[@]}" >/dev/null
}

write_conf() {
    local host cpus mem
    host=$(hostname -s)
    cpus=$(nproc)
    # slurmd refuses a node that claims more memory than it has: leave some for the OS.
    mem=$(awk '/MemTotal/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
    mkdir -p "$dir/state" "$dir/spool" "$dir/log"
    cat >"$conf" <<CONF
ClusterName=genpath
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
KillWait=10
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
}

start() {
    install_packages
    write_conf
    export SLURM_CONF=$conf
    if ! pgrep -x munged >/dev/null; then
        mkdir -p /run/munge /var/log/munge /var/lib/munge
        [[ -s /etc/munge/munge.key ]] || mungekey --create --keyfile=/etc/munge/munge.key
        chown munge:munge /etc/munge/munge.key /run/munge /var/log/munge /var/lib/munge
        chmod 0400 /etc/munge/munge.key
        runuser -u munge -- /usr/sbin/munged
        echo started >"$dir/munged.ours"
    fi
    slurmctld -c -f "$conf"
    slurmd -f "$conf"
    local i
    for ((i = 0; i < 60; i++)); do
        if sinfo -h -o '%T' 2>/dev/null | grep -qx idle; then
            echo "Slurm is up: export SLURM_CONF=$conf"
            return
        fi
        sleep 1
    done
    echo "the local Slurm cluster did not come up within 60 s:" >&2
    sinfo >&2 || true
    tail -n 20 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
    return 1
}

stop() {
    local f pids=() i
    for f in "$dir/slurmd.pid" "$dir/slurmctld.pid"; do
        [[ -f $f ]] && pids+=("$(cat "$f")")
    done
    ((${#pids[@]})) && kill "${pids[@]}" 2>/dev/null
    # Wait for them to save their state and exit, so that their directory can be removed.
    for ((i = 0; i < 100; i++)); do
        kill -0 "${pids[@]}" 2>/dev/null || break
        sleep 0.1
    done
    if [[ -f $dir/munged.ours ]]; then
        pkill -x munged 2>/dev/null || true
        rm -f "$dir/munged.ours"
    fi
    echo "stopped the local Slurm cluster"
}

case ${1:-} in
start) start ;;
stop) stop ;;
*)
    echo "usage: bash scripts/slurm/local-cluster.sh start|stop" >&2
    exit 2
    ;;
esac
