#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The cohort example run by a real SLURM: a one-node cluster (slurmctld and slurmd
# from Debian's slurm-wlm, started here on private ports with a configuration of
# their own, auth/none, nothing of the machine's), examples/cohort/voxhap-array.slurm
# submitted as a 4-task array, then `voxhap batch merge`: every job done.
#
#   slurm_array_job.sh VOXHAP_BINARY PROJECT_ROOT
#
# Exit 77 (ctest: skipped) with the reason when SLURM is missing, the user is not
# root or its daemons cannot start on this machine; under VOXHAP_REQUIRE_ALL (CI,
# root on a fresh Debian 12) each of these fails instead (tests/common/prerequisite.sh).
set -euo pipefail
voxhap=$1
root=$2
source "$root/tests/common/prerequisite.sh"
for tool in slurmctld slurmd sbatch sinfo; do
  command -v "$tool" >/dev/null || missing "$tool is not installed (Debian: slurmctld slurmd slurm-client)"
done
[ "$(id -u)" -eq 0 ] || missing "root: slurmd must run as root to start jobs as their user"

work=$(mktemp -d /tmp/voxhap-slurm.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
mkdir -p "$work/state" "$work/spool"
host=$(hostname -s)
# Two free ports on loopback for this cluster alone.
read -r ctld_port d_port < <(python3 -c 'import socket
s=[socket.socket() for _ in range(2)]
[x.bind(("127.0.0.1",0)) for x in s]
print(*[x.getsockname()[1] for x in s])')
cat >"$work/slurm.conf" <<CONF
ClusterName=voxhaptest
SlurmctldHost=$host
AuthType=auth/none
CredType=cred/none
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
ProctrackType=proctrack/pgid
TaskPlugin=task/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=10 State=UP
CONF
export SLURM_CONF=$work/slurm.conf
slurmctld -D -c >"$work/ctld.out" 2>&1 & pids+=($!)
slurmd -D >"$work/d.out" 2>&1 & pids+=($!)
for _ in $(seq 50); do
  sinfo -h -o %t 2>/dev/null | grep -q idle && break
  sleep 0.2
done
sinfo -h -o %t 2>/dev/null | grep -q idle ||
  missing "SLURM daemons that come up here: $(tail -n 1 "$work/slurmctld.log" 2>/dev/null)"

cd "$work"
"$voxhap" phantom torso --spacing 1.5 -o torso.vdb >/dev/null
"$voxhap" phantom slab --spacing 1 -o slab.vdb >/dev/null
cat >cohort.json <<'JSON'
{"schema": "voxhap-batch/1", "output": "cohort",
 "defaults": {"plan": ["--top", "2", "--step", "5", "--max-angle", "60", "--no-views"], "simulate": ["--no-plot"]},
 "jobs": [
  {"id": "torso-plan", "command": "plan", "volume": "torso.vdb", "args": ["--target", "5,-78,0"]},
  {"id": "lumbar-sim", "command": "simulate", "phantom": "lumbar:average", "args": ["--scene", "senac-average"]},
  {"id": "slab-seg", "command": "segment", "volume": "slab.vdb"},
  {"id": "conci-sim", "command": "simulate", "args": ["--scene", "conci"]}
 ]}
JSON
VOXHAP=$voxhap timeout 300 sbatch --array=0-3 --cpus-per-task=1 --wait --chdir="$work" \
  --output="$work/task-%a.out" "$root/examples/cohort/voxhap-array.slurm" cohort.json
status=0
"$voxhap" batch merge cohort.json --json >merge.json || status=$?
cat merge.json
for i in 0 1 2 3; do echo "--- task $i"; cat "task-$i.out"; done
[ "$status" -eq 0 ] || { echo "FAILED: merge exit $status"; exit 1; }
python3 - <<'PY'
import csv, json, sys
rows = list(csv.DictReader(open("cohort/cohort.csv")))
assert [r["id"] for r in rows] == ["torso-plan", "lumbar-sim", "slab-seg", "conci-sim"], rows
assert all(r["status"] == "done" for r in rows), [(r["id"], r["status"], r["error"]) for r in rows]
print("4 jobs done by a 4-task SLURM array, merged")
PY
