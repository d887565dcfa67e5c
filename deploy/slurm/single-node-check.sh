#!/usr/bin/env bash
# Proof on a real scheduler (not run by CI: it needs root and a few minutes): installs Debian's
# slurm-wlm and munge, starts a one-node Slurm cluster on this machine, submits the shipped
# trajdrift-array.sbatch over the shared fixtures as a 2-task array (plus its dependent merge job),
# waits, and checks that the merged summary equals a local `trajdrift batch` run of the same missions.
#
#   sudo deploy/slurm/single-node-check.sh        # from the repository root; shared/ at ../shared
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

echo "== start munge and a one-node cluster ($host, $cpus CPUs) in $work"
mkdir -p /etc/munge /var/log/munge /run/munge /var/lib/munge
[ -s /etc/munge/munge.key ] || dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
chmod 400 /etc/munge/munge.key
pgrep -x munged >/dev/null || munged --force
conf=/etc/slurm/slurm.conf
mkdir -p /etc/slurm "$work/state" "$work/spool"
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
pkill -x slurmctld || true
pkill -x slurmd || true
sleep 1
slurmctld -c -i
slurmd -c
cleanup() { pkill -x slurmd || true; pkill -x slurmctld || true; }
trap cleanup EXIT
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
