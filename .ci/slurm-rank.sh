#!/usr/bin/env bash
# A real Slurm test of `dea-fit rank` (docs/rank.md, "Sweeps, shards, Slurm"):
# installs Debian's slurmctld, slurmd, slurm-client and munge, starts a one-node
# cluster on localhost (the recipe of ../shared/docs/slurm.md: munged as the munge
# user, proctrack/linuxproc, task/none, select/cons_tres, no accounting), submits the
# script `rank --slurm 4` prints (a 4-task shard array and a merge job after it with
# --dependency=afterok), checks the merged table and CSV against a single-process
# run byte for byte and that a shard altered by one character is refused, and stops
# exactly the daemons it started, by their PIDs.
#
# Needs root (it installs packages and starts daemons). The cluster's files live in
# a temporary directory (SLURM_CONF points there; /etc/slurm is not touched). A
# munged that is already running is used and left running.
#   .ci/slurm-rank.sh            # builds target/release/dea-fit if it is missing
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
bin=${DEA_FIT:-$repo/target/release/dea-fit}
if [ "$(id -u)" != 0 ]; then
    echo "slurm-rank: needs root (installs packages, starts munged, slurmctld, slurmd)" >&2
    exit 2
fi
[ -x "$bin" ] || cargo build --release
t0=$(date +%s)
work=$(mktemp -d /tmp/dea-fit-slurm.XXXXXX)
pids=()
munge_pid=
cleanup() {
    status=$?
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    for p in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    done
    if [ -n "$munge_pid" ]; then
        kill "$munge_pid" 2>/dev/null || true
        rm -f /run/munge/munged.pid
    fi
    if [ $status != 0 ]; then
        echo "slurm-rank: FAILED; logs in $work" >&2
        tail -n 20 "$work"/*.log "$work"/rank-shards/*.log 2>/dev/null >&2 || true
    else
        rm -rf "$work"
    fi
    exit $status
}
trap cleanup EXIT

echo "slurm-rank: installing slurmctld slurmd slurm-client munge"
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    slurmctld slurmd slurm-client munge >/dev/null

# munge: the postinst wrote /etc/munge/munge.key; start munged unless one answers.
if ! (munge -n | unmunge) >/dev/null 2>&1; then
    mkdir -p /run/munge && chown munge:munge /run/munge
    rm -f /run/munge/munged.pid
    runuser -u munge -- /usr/sbin/munged          # daemonises; its own pidfile
    munge_pid=$(cat /run/munge/munged.pid)
fi
(munge -n | unmunge) | grep -q 'STATUS: *Success'

export SLURM_CONF=$work/slurm.conf
mkdir -p "$work/ctld" "$work/spool"
cat > "$SLURM_CONF" <<CONF
ClusterName=deafit
SlurmctldHost=localhost
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
ReturnToService=2
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmdSpoolDir=$work/spool
StateSaveLocation=$work/ctld
SlurmUser=root
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
MpiDefault=none
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=localhost CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
/usr/sbin/slurmctld -D -f "$SLURM_CONF" > "$work/slurmctld.out" 2>&1 & pids+=($!)
/usr/sbin/slurmd -D -N localhost -f "$SLURM_CONF" > "$work/slurmd.out" 2>&1 & pids+=($!)
deadline=$(( $(date +%s) + 60 ))
until sinfo -h -o %t 2>/dev/null | grep -q idle; do
    [ "$(date +%s)" -lt $deadline ] || { echo "slurm-rank: the node did not come up" >&2; exit 1; }
    sleep 0.2
done
echo "slurm-rank: cluster up after $(( $(date +%s) - t0 )) s"

# The sweep: 4 series × 13 loadings × 4 voltages + VHB × 4 = 212 points.
cd "$work"
cp -r "$repo/datasets" .
design=datasets/design/silicone_fillers.toml
sweep=(--sweep loading=0:0.6:13 --sweep voltage=600V:900V:4)
"$bin" rank "$design" "${sweep[@]}" --no-report --csv single.csv > single.txt
"$bin" rank "$design" "${sweep[@]}" --no-report --csv merged.csv --slurm 4 > sweep.sh
sh sweep.sh
deadline=$(( $(date +%s) + 300 ))
while squeue -h 2>/dev/null | grep -q .; do
    [ "$(date +%s)" -lt $deadline ] || { echo "slurm-rank: jobs still queued after 300 s" >&2; squeue >&2; exit 1; }
    sleep 0.2
done
ls rank-shards/shard-{0,1,2,3}.json >/dev/null
cmp single.txt rank-shards/ranking.txt
cmp single.csv merged.csv
echo "slurm-rank: the merged table and CSV of 4 shards equal the single run ($(grep -c . single.csv) CSV lines)"
# A shard altered by one character (a stroke 0.0… → 1.0…) is refused, named (exit 2).
sed 's/"static_stroke":{"value":0\./"static_stroke":{"value":1./' rank-shards/shard-0.json > altered.json
! cmp -s altered.json rank-shards/shard-0.json
set +e
"$bin" rank merge altered.json rank-shards/shard-{1,2,3}.json --no-report > /dev/null 2> altered.err
rc=$?
set -e
[ $rc = 2 ] && grep -q 'altered.json' altered.err || {
    echo "slurm-rank: an altered shard was not refused (exit $rc)" >&2; cat altered.err >&2; exit 1; }
echo "slurm-rank: an altered shard is refused: $(cut -c1-120 altered.err)"
echo "slurm-rank: ok in $(( $(date +%s) - t0 )) s"
# dea-fit make --slurm --submit of the lab project, on the same cluster
DEA_FIT=$bin "$repo/.ci/slurm-make.sh"
