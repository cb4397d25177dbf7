#!/bin/sh
# A sharded light-map bake through a real scheduler (issue 27): a single-node Slurm from the
# distribution's packages (slurmctld, slurmd, munge) runs deploy/slurm/submit.sh — an array
# of N shards, then the merge — and the result is compared with a one-machine bake, file by
# file (the manifests apart from the bake id and timings).
#
#   sh bench/slurm_shards.sh [SCENE] [SHARDS]        (as root; default: room 4)
#
# LIGHTLAB names the binary (default target/release/lightlab, else target/debug/lightlab);
# BAKE_ARGS the bake's options. Installs slurm-wlm and munge with apt when they are missing.
# It starts its own munged, slurmctld and slurmd with a configuration in a temporary folder
# and stops them at the end.
set -eu
SCENE=${1:-room}
SHARDS=${2:-4}
root=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "${LIGHTLAB:-}" ]; then
    LIGHTLAB=$root/target/release/lightlab
    [ -x "$LIGHTLAB" ] || LIGHTLAB=$root/target/debug/lightlab
fi
BAKE_ARGS=${BAKE_ARGS:---method path --texels-per-metre 16 --gather-samples 64}
export LIGHTLAB BAKE_ARGS SCENE SHARDS

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi
work=$(mktemp -d /tmp/lightlab-slurm.XXXXXX)
host=$(hostname -s)
cpus=$(nproc)
cleanup() {
    [ -f "$work/slurmd.pid" ] && kill "$(cat "$work/slurmd.pid")" 2>/dev/null || true
    [ -f "$work/slurmctld.pid" ] && kill "$(cat "$work/slurmctld.pid")" 2>/dev/null || true
    [ -f "$work/munged.pid" ] && kill "$(cat "$work/munged.pid")" 2>/dev/null || true
}
trap cleanup EXIT

# munge: a key and a daemon of our own.
mkdir -p "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 2>/dev/null
chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
    --pid-file="$work/munged.pid" --log-file="$work/munge/log" --seed-file="$work/munge/seed"

cat > "$work/slurm.conf" <<CONF
ClusterName=lightlab
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=main Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
mkdir -p "$work/state" "$work/spool"
export SLURM_CONF="$work/slurm.conf"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
i=0
until sinfo -h -o %T 2>/dev/null | grep -q idle; do
    i=$((i + 1))
    if [ $i -gt 60 ]; then
        echo "Slurm did not come up; logs in $work" >&2
        exit 1
    fi
    sleep 1
done
echo "slurm $(sinfo -V | cut -d' ' -f2) up: node $host, $cpus CPUs"

job=$work/job
t0=$(date +%s.%N)
WORK=$job SBATCH_ARGS="--cpus-per-task=1" sh "$root/deploy/slurm/submit.sh"
until [ -z "$(squeue -h -o %i)" ]; do sleep 1; done
t1=$(date +%s.%N)
[ -f "$job/baked/manifest.json" ] || { echo "no merged bake; see $job/*.log" >&2; exit 1; }
# shellcheck disable=SC2086
"$LIGHTLAB" bake --scene "$SCENE" $BAKE_ARGS --out "$work/whole" 2>/dev/null
t2=$(date +%s.%N)
python3 - "$work/whole" "$job/baked" "$t0" "$t1" "$t2" "$SHARDS" <<'PY'
import json, os, sys
a, b, t0, t1, t2, n = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:6]), int(sys.argv[6])
def strip(d):
    m = json.load(open(os.path.join(d, "manifest.json")))
    del m["integrity"]["bake_id"]
    for k in ("seconds_layout", "seconds_solve", "seconds_total"):
        m["stats"].pop(k, None)
    return m
files = sorted(f for f in os.listdir(a) if f != "manifest.json")
same = files == sorted(f for f in os.listdir(b) if f != "manifest.json") and all(
    open(os.path.join(a, f), "rb").read() == open(os.path.join(b, f), "rb").read() for f in files)
same = same and strip(a) == strip(b)
print(f"{n} shards + merge under Slurm: {t1 - t0:.1f} s wall; one machine: {t2 - t1:.1f} s")
print(f"files: {', '.join(files)}")
print("merged bake equals the one-machine bake:", "yes" if same else "NO")
sys.exit(0 if same else 1)
PY
for f in "$job"/lightlab-bake-*.log; do
    printf '%s: %s\n' "$(basename "$f")" "$(tail -n 1 "$f")"
done
