#!/usr/bin/env bash
# Proof on a real scheduler (not run by CI: it needs root and a few minutes): installs Debian's
# slurm-wlm and munge, starts a one-node Slurm cluster on this machine, submits the shipped
# trajdrift-array.sbatch over the shared fixtures as a 2-task array (plus its dependent merge job),
# waits, and checks that the merged summary equals a local `trajdrift batch` run of the same missions.
#
#   sudo deploy/slurm/single-node-check.sh        # from the repository root; shared/ at ../shared
#
# It stops only what it started. The cluster's configuration, state, logs and pid files live in a
# fresh /tmp/trajdrift-slurm.* folder (the daemons are started with -f on that configuration, the
# clients find it through SLURM_CONF; /etc/slurm is not touched). At the end it signals the pids in its
# own pid files, each only after checking that the process is the daemon it started (its name, and
# that configuration on its command line). A Slurm daemon it did not start is never signalled: if a
# slurmctld or slurmd is running (a real cluster node), the check refuses to start; the one exception
# is a daemon left by an earlier run of this check that was killed before its cleanup (recognised by
# its /tmp/trajdrift-slurm.*/slurm.conf), which it stops first. munged is started only when none runs,
# and is then stopped at the end the same way.
set -euo pipefail
cd "$(dirname "$0")/../.."
repo=$(pwd)
shared=${TRAJDRIFT_SHARED:-$(cd .. && pwd)/shared}
[ -d "$shared/fixtures" ] || { echo "error: no shared fixtures at $shared" >&2; exit 1; }
[ "$(id -u)" -eq 0 ] || { echo "error: run as root (it installs and starts slurm and munge)" >&2; exit 1; }

echo "== install slurm-wlm and munge"
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

echo "== build trajdrift"
cargo build --release --bin trajdrift --quiet
bin=$repo/target/release/trajdrift

work=$(mktemp -d /tmp/trajdrift-slurm.XXXXXX)
host=$(hostname -s)
cpus=$(nproc)
mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512 ))
conf=$work/slurm.conf
export SLURM_CONF=$conf
munge_pid_file=

# True when process PID is named NAME and one of its arguments is exactly ARG.
is_ours() {
  local pid=$1 name=$2 arg=$3
  [ -r "/proc/$pid/cmdline" ] || return 1
  [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$name" ] || return 1
  tr '\0' '\n' < "/proc/$pid/cmdline" | grep -qxF -- "$arg"
}
# Sends SIGTERM to PID if it is NAME started with ARG, and waits up to 10 s for it to end.
stop_pid() {
  local pid=$1 name=$2 arg=$3
  if ! is_ours "$pid" "$name" "$arg"; then
    echo "note: pid $pid is not the $name started with $arg; left alone" >&2
    return 0
  fi
  kill "$pid" 2>/dev/null || return 0
  for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.2; done
  echo "warning: $name (pid $pid) still running 10 s after SIGTERM" >&2
}
# The same for the pid in PID_FILE (nothing when the daemon never wrote it).
stop_pid_file() {
  local pid_file=$1 name=$2 arg=$3 pid
  [ -s "$pid_file" ] || return 0
  pid=$(tr -dc '0-9' < "$pid_file")
  [ -n "$pid" ] && stop_pid "$pid" "$name" "$arg"
}
cleanup() {
  stop_pid_file "$work/slurmd.pid" slurmd "$conf"
  stop_pid_file "$work/slurmctld.pid" slurmctld "$conf"
  if [ -n "$munge_pid_file" ]; then stop_pid_file "$munge_pid_file" munged "--pid-file=$munge_pid_file"; fi
}
trap cleanup EXIT

# Slurm daemons already running: a leftover of an earlier run of this check is stopped; any other
# (a real cluster's) makes the check refuse, rather than fight it for its ports or stop it.
for name in slurmctld slurmd; do
  for pid in $(pgrep -x "$name" || true); do
    old=$(tr '\0' '\n' < "/proc/$pid/cmdline" 2>/dev/null \
      | grep -xE '/tmp/trajdrift-slurm\.[A-Za-z0-9]+/slurm\.conf' || true)
    if [ -n "$old" ]; then
      echo "== stop $name (pid $pid) left by an earlier run of this check ($old)"
      stop_pid "$pid" "$name" "$old"
    else
      echo "error: a $name this check did not start is running (pid $pid): run the check on a" \
        "machine without Slurm daemons (it starts its own one-node cluster and stops no other)" >&2
      exit 1
    fi
  done
done

echo "== start munge and a one-node cluster ($host, $cpus CPUs) in $work"
mkdir -p /etc/munge /var/log/munge /run/munge /var/lib/munge
[ -s /etc/munge/munge.key ] || dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
chmod 400 /etc/munge/munge.key
if ! pgrep -x munged >/dev/null; then
  munge_pid_file=$work/munged.pid
  munged --force --pid-file="$munge_pid_file"
fi
mkdir -p "$work/state" "$work/spool"
cat > "$conf" <<CONF
ClusterName=trajdrift-check
SlurmctldHost=$host
AuthType=auth/munge
SlurmUser=root
SlurmdUser=root
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=check Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -f "$conf" -c -i
slurmd -f "$conf" -c
for _ in $(seq 30); do sinfo -h -o %T 2>/dev/null | grep -qE 'idle|mix' && break; sleep 1; done
sinfo

echo "== the missions (a manifest over the five shared fixtures, windows 5 and 10 m)"
manifest=$work/missions.toml
printf '[defaults]\nwindow = [5, 10]\n' > "$manifest"
for m in lever_arm gnss_outages legged legged_spins straight; do
  printf '\n[[mission]]\nname = "%s"\nrecording = "%s"\nreference = "/reference/position"\nestimates = ["/estimate/odom"]\n' \
    "$m" "$shared/fixtures/$m/mission.mcap" >> "$manifest"
done

echo "== sbatch --array=0-1 deploy/slurm/trajdrift-array.sbatch"
out=$work/slurm-results
cd "$work"
array=$(TRAJDRIFT=$bin sbatch --parsable --array=0-1 --cpus-per-task=1 "$repo/deploy/slurm/trajdrift-array.sbatch" "$manifest" "$out")
echo "array job $array"
for _ in $(seq 600); do
  [ -s "$out/summary.json" ] && [ -z "$(squeue -h 2>/dev/null)" ] && break
  sleep 1
done
squeue || true
[ -s "$out/summary.json" ] || { echo "FAIL: no merged summary after 10 minutes; logs in $work" >&2; exit 1; }
ls "$out"

echo "== the same missions in one local run"
set +e
"$bin" batch "$manifest" --out "$work/local" --quiet
set -e
strip='del(.timing)'
if command -v jq >/dev/null; then
  diff <(jq -S "$strip" "$out/summary.json") <(jq -S "$strip" "$work/local/summary.json")
else
  python3 - "$out/summary.json" "$work/local/summary.json" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for d in (a, b):
    d.pop("timing", None)
sys.exit(0 if a == b else "merged summary differs from the local run")
PY
fi
cmp "$out/summary.csv" "$work/local/summary.csv"
echo "PASS: Slurm array ($(ls "$out"/summary-shard-*.json | wc -l) shards) + dependent merge = local batch (summary.json without timing, summary.csv byte for byte)"
