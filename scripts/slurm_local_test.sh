#!/usr/bin/env bash
# End-to-end test of scripts/slurm_render.sh on a single-node Slurm cluster started here
# (munged, slurmctld, slurmd from Debian's slurm-wlm, configuration in a temporary folder, all
# stopped on exit): 4 array tasks + the merge job render the shard test scene; the merged image
# must equal a single local run. Needs root (installs slurm-wlm if missing) and the mfrender
# build: scripts/slurm_local_test.sh [BUILD_DIR, default build/test]. An integration command,
# not part of scripts/test.sh (daemons, ~1 min).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(realpath "${1:-$root/build/test}")
mfrender=$build/cpp_host/mfrender mfcompare=$build/cpp_host/mfcompare
[ -x "$mfrender" ] || { echo "slurm_local_test: build mfrender first ($mfrender)" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "slurm_local_test: needs root (starts slurmctld/slurmd)" >&2; exit 2; }
if ! command -v slurmctld >/dev/null; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi
work=$(mktemp -d /tmp/mfslurm.XXXXXX)
chmod 755 "$work"
host=$(hostname -s)
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    sleep 1
    for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
}
trap cleanup EXIT
mkdir -p "$work/spool" "$work/state" "$work/out" "$work/munge"
cat >"$work/slurm.conf" <<CONF
ClusterName=mflocal
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
SlurmctldPort=16817
SlurmdPort=16818
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$work/slurm.conf
# munge with its own socket so that a system munged (if any) is left alone
munged --socket="$work/munge/munge.socket" --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" \
    --seed-file="$work/munge/seed" --force
sleep 0.5
pids+=("$(cat "$work/munge/munged.pid")")
cat >>"$work/slurm.conf" <<CONF
AuthInfo=socket=$work/munge/munge.socket
CONF
slurmctld -D -f "$work/slurm.conf" >"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$work/slurm.conf" >"$work/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 60); do
    if sinfo -h -o %T 2>/dev/null | grep -qE "idle|mixed"; then break; fi
    sleep 1
done
sinfo || { echo "FAIL: the local Slurm cluster did not come up"; tail -20 "$work"/*.log; exit 1; }
scene=$root/cpp_host/tests/scenes/shard_scene.xml
args=(-D spp=16 -D res=64)
MFRENDER=$mfrender "$root/scripts/slurm_render.sh" "$scene" 4 "$work/out" "${args[@]}" | tee "$work/submit.txt"
merge_job=$(sed -n 's/.*merge job \([0-9]*\).*/\1/p' "$work/submit.txt")
for _ in $(seq 300); do
    state=$(scontrol show job "$merge_job" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
    case "$state" in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) break ;; esac
    sleep 1
done
echo "merge job state: ${state:-unknown}"
echo "--- job logs"
tail -n +1 "$work/out"/*.log
[ "$state" = COMPLETED ] || { echo "FAIL: merge job ended in state ${state:-unknown}"; tail -20 "$work"/slurm*.log; exit 1; }
"$mfrender" "$scene" "${args[@]}" --quiet -o "$work/single.exr"
diff=$("$mfcompare" maxreldiff "$work/single.exr" "$work/out/shard_scene.exr")
echo "max relative difference, Slurm merge vs single run: $diff"
awk -v d="$diff" 'BEGIN { exit !(d <= 1e-6) }' || { echo "FAIL: the Slurm render differs from the single run"; exit 1; }
echo "1 passed, 0 failed"
