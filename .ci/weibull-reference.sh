#!/usr/bin/env bash
# Reference Weibull fits from an independent implementation (the Python package
# `reliability`, pinned) of the series in datasets/breakdown/reference/*.csv,
# written to datasets/breakdown/reference/reliability.json and compared by
# tests/weibull.rs. `--check`: recompute and fail when the committed JSON differs.
# The venv lives in target/ (WEIBULL_REFERENCE_VENV to put it elsewhere).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${WEIBULL_REFERENCE_VENV:-$root/target/weibull-reference-venv}
. "$root/.ci/venv.sh"
make_venv "$venv"
if ! "$venv/bin/python" -c 'import reliability, sys; sys.exit(reliability.__version__ != "0.9.0")' 2>/dev/null; then
    "$venv/bin/pip" install --quiet "reliability==0.9.0"
fi
exec "$venv/bin/python" "$root/.ci/weibull_reference.py" "$@"
