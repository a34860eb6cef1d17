#!/usr/bin/env bash
# A single-node SLURM cluster on this machine, for the tests and for trying the
# sbatch scripts by hand. Needs root and Debian's apt-get (it installs slurm-wlm
# and munge if they are missing).
#
#   slurm/local-cluster.sh [start]   install, configure, start munged/slurmctld/slurmd,
#                                    wait until the node is idle (idempotent)
#   slurm/local-cluster.sh stop      cancel every job, stop the three daemons
#   slurm/local-cluster.sh status    print sinfo/squeue, exit 1 if the cluster is down
#
# Environment: LOCAL_SLURM_TIMEOUT (seconds to wait for an idle node, default 90),
# LOCAL_SLURM_PARTITION (default "local").
#
# Everything is on loopback: the controller and the node both use 127.0.0.1.
# Files: /etc/slurm/{slurm,cgroup}.conf (rewritten only when their content changes),
# logs in /var/log/slurm/, state in /var/spool/slurmctld and /var/spool/slurmd.
set -euo pipefail

ACTION=${1:-start}
TIMEOUT=${LOCAL_SLURM_TIMEOUT:-90}
PARTITION=${LOCAL_SLURM_PARTITION:-local}

CONF_DIR=/etc/slurm
LOG_DIR=/var/log/slurm
CTLD_STATE=/var/spool/slurmctld
SLURMD_SPOOL=/var/spool/slurmd
CTLD_PID=/run/slurmctld.pid
SLURMD_PID=/run/slurmd.pid
MUNGE_KEY=/etc/munge/munge.key
MUNGE_RUN=/run/munge
MUNGE_PID=$MUNGE_RUN/munged.pid

log() { echo "local-cluster: $*" >&2; }
die() { log "ERROR: $*"; exit 1; }

# pid_alive PIDFILE NAME: true if PIDFILE names a live process whose command is NAME.
pid_alive() {
    local pid
    [[ -s $1 ]] || return 1
    pid=$(<"$1")
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    [[ "$(cat /proc/"$pid"/comm 2>/dev/null)" == "$2" ]]
}

# stop_pidfile PIDFILE NAME: SIGTERM the daemon named in PIDFILE, wait up to 20 s, then SIGKILL.
stop_pidfile() {
    local pid i
    pid_alive "$1" "$2" || { rm -f "$1"; return 0; }
    pid=$(<"$1")
    log "stopping $2 (pid $pid)"
    kill -TERM "$pid" 2>/dev/null || true
    for ((i = 0; i < 200; i++)); do
        pid_alive "$1" "$2" || break
        sleep 0.1
    done
    if pid_alive "$1" "$2"; then
        log "$2 did not stop in 20 s: SIGKILL"
        kill -KILL "$pid" 2>/dev/null || true
        sleep 0.5
    fi
    rm -f "$1"
}

show_logs() {
    local f
    for f in "$LOG_DIR/slurmctld.log" "$LOG_DIR/slurmd.log" /var/log/munge/munged.log; do
        [[ -f $f ]] || continue
        echo "----- last lines of $f -----" >&2
        tail -n 40 "$f" >&2
    done
}

need_root() {
    [[ $(id -u) == 0 ]] || die "must run as root (it installs packages and starts daemons)"
}

install_packages() {
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null &&
        command -v sinfo >/dev/null && command -v munged >/dev/null &&
        compgen -G '/usr/lib/*/slurm-wlm/mpi_pmi2.so' >/dev/null; then
        return 0
    fi
    command -v apt-get >/dev/null || die "slurm-wlm/munge are missing and there is no apt-get to install them"
    log "installing slurm-wlm and munge with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    # The package lists may be missing or old on a fresh machine.
    apt-get update -qq
    # Debian's maintainer scripts try to start the daemons through systemd; with no
    # systemd here that fails harmlessly (policy-rc.d), and this script starts them.
    apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
}

write_if_changed() { # write_if_changed PATH (content on stdin); true if the file changed
    local tmp
    tmp=$(mktemp)
    cat >"$tmp"
    if [[ -f $1 ]] && cmp -s "$tmp" "$1"; then
        rm -f "$tmp"
        return 1
    fi
    install -m 0644 "$tmp" "$1"
    rm -f "$tmp"
    return 0
}

write_config() { # true if slurm.conf or cgroup.conf changed
    local node cpus mem changed=1
    node=$(hostname -s)
    cpus=$(nproc)
    mem=$(free -m | awk '/^Mem:/ {print $2}')
    mkdir -p "$CONF_DIR" "$LOG_DIR" "$CTLD_STATE" "$SLURMD_SPOOL"
    write_if_changed "$CONF_DIR/slurm.conf" <<EOF && changed=0
# Written by campar's slurm/local-cluster.sh: a single-node cluster on loopback.
ClusterName=campar-local
SlurmctldHost=$node(127.0.0.1)
# Everything runs as root; the daemons authenticate each other with munge.
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
# A requeued job may start again cred_expire seconds after the requeue
# (default 120 s); the local node needs far less than that to launch a step.
# 5 is the least Slurm takes: below it, it logs "cred_expire invalid" and uses 120.
AuthInfo=cred_expire=5
SlurmctldPort=6817
SlurmdPort=6818
StateSaveLocation=$CTLD_STATE
SlurmdSpoolDir=$SLURMD_SPOOL
SlurmctldPidFile=$CTLD_PID
SlurmdPidFile=$SLURMD_PID
SlurmctldLogFile=$LOG_DIR/slurmctld.log
SlurmdLogFile=$LOG_DIR/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups, no accounting: this has to work inside a container.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
# Cores are the consumable resource; memory is not tracked.
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# Schedule every second, so that a requeued job starts again as soon as it may.
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1,bf_interval=1
# A node that went down (e.g. slurmd restarted) comes back by itself.
ReturnToService=2
# Trust this file's node description rather than draining on small differences.
SlurmdParameters=config_overrides
# Let a job catch SIGTERM (time limit, scancel, requeue) and flush before SIGKILL.
KillWait=30
# Completed jobs stay visible to scontrol/squeue for 5 minutes (there is no sacct).
MinJobAge=300
JobRequeue=1
# No mail from this cluster (the default MailProg is not installed).
MailProg=/bin/true
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=$PARTITION Nodes=$node Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF
    write_if_changed "$CONF_DIR/cgroup.conf" <<EOF && changed=0
# Written by campar's slurm/local-cluster.sh. No cgroup plugin is used
# (proctrack/linuxproc, task/none); slurmd still reads this file.
CgroupPlugin=autodetect
IgnoreSystemd=yes
EOF
    return $changed
}

start_munge() {
    if [[ ! -s $MUNGE_KEY ]]; then
        log "creating the munge key"
        mkdir -p "$(dirname "$MUNGE_KEY")"
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile="$MUNGE_KEY"
        else
            dd if=/dev/urandom of="$MUNGE_KEY" bs=1 count=1024 status=none
        fi
    fi
    chown munge:munge "$(dirname "$MUNGE_KEY")" "$MUNGE_KEY"
    chmod 0700 "$(dirname "$MUNGE_KEY")"
    chmod 0400 "$MUNGE_KEY"
    mkdir -p "$MUNGE_RUN" /var/log/munge /var/lib/munge
    chown munge:munge "$MUNGE_RUN" /var/log/munge /var/lib/munge
    chmod 0755 "$MUNGE_RUN"
    if pid_alive "$MUNGE_PID" munged && munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        return 0
    fi
    log "starting munged"
    rm -f "$MUNGE_PID"
    runuser -u munge -- /usr/sbin/munged
    local i
    for ((i = 0; i < 50; i++)); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && return 0
        sleep 0.2
    done
    show_logs
    die "munged does not answer (munge -n | unmunge fails)"
}

node_state() { sinfo -h -n "$(hostname -s)" -o %T 2>/dev/null | head -n 1; }

start() {
    need_root
    install_packages
    local restart=0
    write_config && restart=1
    start_munge
    if ((restart)) && { pid_alive "$CTLD_PID" slurmctld || pid_alive "$SLURMD_PID" slurmd; }; then
        log "configuration changed: restarting slurmctld and slurmd"
        stop_pidfile "$SLURMD_PID" slurmd
        stop_pidfile "$CTLD_PID" slurmctld
    fi
    if ! pid_alive "$CTLD_PID" slurmctld; then
        log "starting slurmctld"
        /usr/sbin/slurmctld || { show_logs; die "slurmctld failed to start"; }
    fi
    if ! pid_alive "$SLURMD_PID" slurmd; then
        log "starting slurmd"
        /usr/sbin/slurmd || { show_logs; die "slurmd failed to start"; }
    fi
    local deadline=$((SECONDS + TIMEOUT)) state resumed=0
    while :; do
        state=$(node_state || true)
        case $state in
        idle | mixed | allocated | completing)
            # "idle" on a fresh start; a node already running jobs is up as well.
            log "node $(hostname -s) is $state"
            return 0
            ;;
        down* | drain* | fail*)
            # e.g. state restored from before a crash; bring it back once.
            if ((!resumed)); then
                log "node is $state: resuming it"
                scontrol update NodeName="$(hostname -s)" State=RESUME >/dev/null 2>&1 || true
                resumed=1
            fi
            ;;
        esac
        if ((SECONDS >= deadline)); then
            sinfo -N -l >&2 || true
            show_logs
            die "node not idle after ${TIMEOUT} s (state: '${state}')"
        fi
        sleep 0.2 # the node registers within a second of slurmd's start: look often
    done
}

stop() {
    need_root
    if pid_alive "$CTLD_PID" slurmctld; then
        # Cancel every job first, so that no job step outlives slurmd.
        local jobs i
        jobs=$(squeue -h -o %A 2>/dev/null || true)
        if [[ -n $jobs ]]; then
            log "cancelling jobs: ${jobs//$'\n'/ }"
            # shellcheck disable=SC2086
            scancel $jobs 2>/dev/null || true
            for ((i = 0; i < 45; i++)); do
                [[ -z "$(squeue -h -o %A 2>/dev/null)" ]] && break
                sleep 1
            done
        fi
    fi
    stop_pidfile "$SLURMD_PID" slurmd
    stop_pidfile "$CTLD_PID" slurmctld
    if pid_alive "$MUNGE_PID" munged; then
        log "stopping munged"
        munged --stop >/dev/null 2>&1 || stop_pidfile "$MUNGE_PID" munged
    fi
    log "stopped"
}

status() {
    local ok=0
    local pidfile name
    for pidfile in "$MUNGE_PID:munged" "$CTLD_PID:slurmctld" "$SLURMD_PID:slurmd"; do
        name=${pidfile##*:}
        if pid_alive "${pidfile%:*}" "$name"; then
            echo "$name: running"
        else
            echo "$name: stopped"
            ok=1
        fi
    done
    if ((ok == 0)); then
        sinfo
        squeue
    fi
    return $ok
}

case $ACTION in
start) start ;;
stop) stop ;;
restart) stop && start ;;
status) status ;;
*)
    echo "usage: $0 [start|stop|restart|status]" >&2
    exit 2
    ;;
esac
