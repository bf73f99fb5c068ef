#!/bin/bash
# A single-node SLURM with accounting, as root, without systemd, everything under one folder:
#   scripts/slurm-local.sh start  DIR   munged, MariaDB, slurmdbd, slurmctld, slurmd; prints the SLURM_CONF to export
#   scripts/slurm-local.sh stop   DIR   stops the daemons this script started in DIR (their pid files), in parallel
#   scripts/slurm-local.sh status DIR   which of them run, and sinfo
# Debian packages: slurmctld slurmd slurm-client slurmdbd munge mariadb-server (see the Makefile).
# Ports (change with the environment variables): slurmctld 16817, slurmd 16818, slurmdbd 16819, MariaDB 13306.
# Clients need `export SLURM_CONF=DIR/etc/slurm.conf`. The traps avoided here are in the README (SLURM section):
# the hostname (node "localhost" at 127.0.0.1), munge's default paths (own key, socket, seed and pid files),
# the controller-to-slurmdbd authentication (AccountingStoragePass = munge socket), cgroups (linuxproc, task/none).
set -euo pipefail

cmd=${1:-}; dir=${2:-}
if [[ -z "$cmd" || -z "$dir" ]]; then
  echo "usage: $0 start|stop|status DIR" >&2; exit 2
fi
mkdir -p "$dir"; D=$(cd "$dir" && pwd)
CTLD_PORT=${SLURM_LOCAL_CTLD_PORT:-16817}
SLURMD_PORT=${SLURM_LOCAL_SLURMD_PORT:-16818}
DBD_PORT=${SLURM_LOCAL_DBD_PORT:-16819}
DB_PORT=${SLURM_LOCAL_DB_PORT:-13306}
export SLURM_CONF=$D/etc/slurm.conf
DAEMONS=(slurmd slurmctld slurmdbd mariadbd munged)

pidfile() { echo "$D/run/$1.pid"; }
alive() { local f; f=$(pidfile "$1"); [[ -f "$f" ]] && kill -0 "$(cat "$f")" 2>/dev/null; }
wait_for() {   # wait_for SECONDS WHAT COMMAND...
  local t=$1 what=$2; shift 2
  for ((i = 0; i < t * 10; i++)); do "$@" >/dev/null 2>&1 && return 0; sleep 0.1; done
  echo "slurm-local: $what did not come up within $t s (logs in $D/log)" >&2; return 1
}

need() {
  local missing=()
  for b in munged mungekey mariadbd mariadb-install-db mariadb slurmdbd slurmctld slurmd sbatch sacct sacctmgr; do
    command -v "$b" >/dev/null || missing+=("$b")
  done
  if ((${#missing[@]})); then
    echo "slurm-local: missing ${missing[*]} (apt-get install slurmctld slurmd slurm-client slurmdbd munge mariadb-server)" >&2
    exit 3
  fi
  if [[ $(id -u) != 0 ]]; then echo "slurm-local: must run as root (slurmd runs as root)" >&2; exit 3; fi
}

configure() {
  mkdir -p "$D"/{etc,run,log,state,spool,munge,db}
  chmod 0755 "$D" "$D/munge"
  local node mem
  node=$(slurmd -C | head -1 | sed -e 's/^NodeName=[^ ]*/NodeName=localhost NodeAddr=127.0.0.1/')
  cat > "$D/etc/slurm.conf" <<CONF
ClusterName=wendel
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$D/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/run/slurmctld.pid
SlurmdPidFile=$D/run/slurmd.pid
SlurmctldLogFile=$D/log/slurmctld.log
SlurmdLogFile=$D/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=127.0.0.1
AccountingStoragePort=$DBD_PORT
AccountingStoragePass=$D/munge/munge.socket
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MinJobAge=600
$node State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
  cat > "$D/etc/slurmdbd.conf" <<CONF
AuthType=auth/munge
AuthInfo=socket=$D/munge/munge.socket
DbdAddr=127.0.0.1
DbdHost=localhost
DbdPort=$DBD_PORT
SlurmUser=root
PidFile=$D/run/slurmdbd.pid
LogFile=$D/log/slurmdbd.log
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=$DB_PORT
StorageUser=slurm
StoragePass=slurm
StorageLoc=slurm_acct_db
CONF
  chmod 0600 "$D/etc/slurmdbd.conf"
}

start_munge() {
  alive munged && return 0
  [[ -f "$D/munge/munge.key" ]] || mungekey --create --keyfile="$D/munge/munge.key"
  chmod 0600 "$D/munge/munge.key"
  munged --socket="$D/munge/munge.socket" --key-file="$D/munge/munge.key" --seed-file="$D/munge/munged.seed" \
         --pid-file="$D/run/munged.pid" --log-file="$D/log/munged.log" --force
  wait_for 10 munged test -S "$D/munge/munge.socket"
}

start_db() {
  alive mariadbd && return 0
  local fresh=0
  if [[ ! -d "$D/db/data/mysql" ]]; then
    mariadb-install-db --no-defaults --datadir="$D/db/data" --user=root --auth-root-authentication-method=socket \
      --skip-test-db >"$D/log/mariadb-install.log" 2>&1
    fresh=1
  fi
  mariadbd --no-defaults --datadir="$D/db/data" --socket="$D/db/mysql.sock" --port="$DB_PORT" --bind-address=127.0.0.1 \
    --pid-file="$D/run/mariadbd.pid" --user=root --skip-name-resolve --log-error="$D/log/mariadb.log" \
    --innodb-buffer-pool-size=64M --innodb-lock-wait-timeout=900 >/dev/null 2>&1 &
  wait_for 60 MariaDB mariadb --no-defaults --socket="$D/db/mysql.sock" -uroot -e "select 1"
  if ((fresh)); then
    mariadb --no-defaults --socket="$D/db/mysql.sock" -uroot -e "
      CREATE USER IF NOT EXISTS 'slurm'@'127.0.0.1' IDENTIFIED BY 'slurm';
      GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';"
  fi
}

start() {
  need
  if alive slurmctld && alive slurmd && alive slurmdbd; then echo "export SLURM_CONF=$SLURM_CONF"; return 0; fi
  configure
  start_munge
  start_db
  alive slurmdbd || slurmdbd          # reads slurmdbd.conf beside $SLURM_CONF
  wait_for 30 slurmdbd sacctmgr -i -n list cluster
  sacctmgr -i -n list cluster format=cluster | grep -q wendel || sacctmgr -i add cluster wendel >/dev/null
  alive slurmctld || slurmctld
  alive slurmd || slurmd -N localhost
  wait_for 30 "the node" bash -c "sinfo -h -o %T | grep -qE '^(idle|mixed|allocated)'"
  echo "export SLURM_CONF=$SLURM_CONF"
}

stop() {
  local pids=()
  if alive slurmctld; then          # jobs first: their slurmstepd outlive slurmd
    squeue -h -o %A 2>/dev/null | sort -u | xargs -r scancel 2>/dev/null || true
    for ((i = 0; i < 100; i++)); do [[ -z $(squeue -h -t R,CG,PD -o %A 2>/dev/null) ]] && break; sleep 0.1; done
  fi
  for d in "${DAEMONS[@]}"; do
    if alive "$d"; then pids+=("$(cat "$(pidfile "$d")")"); fi
  done
  for p in slurmd slurmctld slurmdbd; do alive $p && kill "$(cat "$(pidfile $p)")" || true; done
  for ((i = 0; i < 100; i++)); do alive slurmd || alive slurmctld || alive slurmdbd || break; sleep 0.1; done
  for p in mariadbd munged; do alive $p && kill "$(cat "$(pidfile $p)")" || true; done
  for ((i = 0; i < 150; i++)); do
    local any=0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && any=1; done
    ((any)) || break; sleep 0.1
  done
  for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && kill -9 "$p" || true; done
  echo "slurm-local: stopped ${#pids[@]} daemon(s) of $D"
}

status() {
  local rc=0
  for d in "${DAEMONS[@]}"; do
    if alive "$d"; then echo "$d: running (pid $(cat "$(pidfile "$d")"))"; else echo "$d: stopped"; rc=1; fi
  done
  ((rc)) || sinfo
  return $rc
}

case "$cmd" in
  start) start ;;
  stop) stop ;;
  status) status ;;
  *) echo "usage: $0 start|stop|status DIR" >&2; exit 2 ;;
esac
