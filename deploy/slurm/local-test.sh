#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine: installs Slurm and MUNGE
# from the distribution's packages (Debian), starts munged, slurmctld and
# slurmd, submits the rover sweep through deploy/slurm/sweep.sbatch as a
# 4-task array plus the afterok merge job, waits, and checks that the
# merged sweep.json equals a single-machine run of the same sweep (all but
# wall_time_s). Needs root. Not part of .ci/run.
#
#   deploy/slurm/local-test.sh [SCENARIO]   (default scenarios/rover_sweep.toml)
set -euo pipefail
cd "$(dirname "$0")/../.."
scenario=${1:-scenarios/rover_sweep.toml}
bin=$PWD/target/release/anholonomy
[[ -x "$bin" ]] || cargo build --release --locked
command -v slurmctld >/dev/null || apt-get install -y -qq slurm-wlm munge >/dev/null

host=$(hostname -s)
cpus=$(nproc)
mem=$(awk '/MemTotal/ { print int($2 / 1024 * 0.9) }' /proc/meminfo)
work=$(mktemp -d /tmp/anholonomy-slurm.XXXXXX)
mkdir -p /etc/slurm "$work/spool" "$work/state" /run/munge
cat >/etc/slurm/slurm.conf <<EOF
ClusterName=anholonomy-local
SlurmctldHost=$host
SlurmUser=root
SlurmdSpoolDir=$work/spool
StateSaveLocation=$work/state
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobAcctGatherType=jobacct_gather/none
MpiDefault=none
ReturnToService=2
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
[[ -s /etc/munge/munge.key ]] || mungekey --create >/dev/null 2>&1 ||
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 2>/dev/null
chown -R munge:munge /etc/munge /run/munge 2>/dev/null || true
chmod 400 /etc/munge/munge.key
pgrep -x munged >/dev/null || su -s /bin/sh munge -c munged 2>/dev/null || munged --force
pkill -x slurmctld 2>/dev/null || true
pkill -x slurmd 2>/dev/null || true
sleep 1
slurmctld
slurmd
for _ in $(seq 1 30); do
    sinfo -h -o %T 2>/dev/null | grep -qE 'idle|mix' && break
    sleep 1
done
echo "cluster: $(sinfo -h -o '%P %D node(s) %c CPUs %T')"

logs=$work/logs
t0=$(date +%s)
LOGS=$logs ANHOLONOMY=$bin bash deploy/slurm/sweep.sbatch "$scenario" 4
while squeue -h | grep -q .; do sleep 1; done
t1=$(date +%s)
name=$("$bin" list "$scenario" | awk 'NR == 2 { print $1 }')
# The jobs' stdout files (sweep.sbatch's --output) land in the submit directory.
mv anholonomy-*.out "$work/" 2>/dev/null || true
echo "array + merge finished in $((t1 - t0)) s; job states:"
# No accounting database here: the controller's log has each job's exit.
grep -h "_job_complete: .*WEXITSTATUS" "$work/slurmctld.log" | sed 's/.*_job_complete: /  /'
ls "$logs/$name"

"$bin" run "$scenario" --logs "$work/single" --quiet >/dev/null
python3 - "$logs/$name/sweep.json" "$work/single/$name/sweep.json" <<'EOF'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for d in (a, b):
    d.pop("wall_time_s", None)
same = a == b
print(f"merged sweep.json == single-machine sweep.json (without wall_time_s): {same}")
print(f"variants: {len(a.get('results', []))}")
sys.exit(0 if same else 1)
EOF
