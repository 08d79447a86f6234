#!/usr/bin/env bash
# `dea-fit make --slurm --submit` on a real Slurm cluster (docs/project.md): the lab
# project (a copy of datasets/lab) as jobs of batched quick steps and one job per
# identify or rank step, with afterany dependencies (each job's `make --only` blocks
# a step whose need failed), and
# a page job; waits for the queue to empty, then checks that the fit files equal a
# local `make`'s (the timing fields `seconds` and the fit-file hashes `sha256`
# removed, as tests/project.rs compares them), that every report and the project
# page exist, and that `dea-fit status` says every step is up to date.
#
# Runs on the one-node cluster .ci/slurm-rank.sh starts (it calls this script while
# its cluster is up, SLURM_CONF exported); on its own it needs a cluster that
# answers `sinfo`.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
bin=${DEA_FIT:-$repo/target/release/dea-fit}
[ -x "$bin" ] || cargo build --release
sinfo -h >/dev/null || { echo "slurm-make: no Slurm cluster answers sinfo" >&2; exit 2; }
t0=$(date +%s)
work=$(mktemp -d /tmp/dea-fit-slurm-make.XXXXXX)
trap 'status=$?; if [ $status != 0 ]; then echo "slurm-make: FAILED; files in $work" >&2; \
    tail -n 20 "$work"/slurm/.dea-fit/slurm/*.out "$work"/slurm/.dea-fit/logs/*.log 2>/dev/null >&2 || true; \
    else rm -rf "$work"; fi; exit $status' EXIT
for d in local slurm; do
    cp -r "$repo/datasets/lab" "$work/$d"
    rm -rf "$work/$d/fits" "$work/$d/reports" "$work/$d/.dea-fit"
done
"$bin" make -C "$work/local" --jobs 2 > "$work/local.txt"
# the jobs run on the node, which shares this file system (one node: localhost)
"$bin" make -C "$work/slurm" --slurm --submit
deadline=$(( $(date +%s) + 300 ))
while squeue -h 2>/dev/null | grep -q .; do
    [ "$(date +%s)" -lt $deadline ] || { echo "slurm-make: jobs still queued after 300 s" >&2; squeue >&2; exit 1; }
    sleep 0.2
done
python3 - "$work/local" "$work/slurm" <<'PY'
import json, os, sys
def fits(d):
    def strip(v):
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items() if k not in ("seconds", "sha256")}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v
    f = os.path.join(d, "fits")
    return {n: strip(json.load(open(os.path.join(f, n)))) for n in sorted(os.listdir(f))}
a, b = fits(sys.argv[1]), fits(sys.argv[2])
if a != b:
    sys.exit(f"slurm-make: the fits differ from a local make: {sorted(set(a) ^ set(b)) or [n for n in a if a[n] != b.get(n)]}")
reports = lambda d: sorted(os.listdir(os.path.join(d, "reports")))
if reports(sys.argv[1]) != reports(sys.argv[2]):
    sys.exit(f"slurm-make: the reports differ: {reports(sys.argv[1])} vs {reports(sys.argv[2])}")
print(f"slurm-make: {len(a)} fit files equal a local make's (timings aside)")
PY
grep -q 'content="project"' "$work/slurm/reports/index.html" \
    || { echo "slurm-make: the page job wrote no project page" >&2; exit 1; }
"$bin" status -C "$work/slurm" > "$work/status.txt"
tail -n 1 "$work/status.txt" | grep -qx 'status: 12 up to date' \
    || { echo "slurm-make: not every step is up to date after the jobs:" >&2; cat "$work/status.txt" >&2; exit 1; }
echo "slurm-make: ok in $(( $(date +%s) - t0 )) s"
