#!/usr/bin/env bash
# pyvisco (PyPI `pyvisco`, pinned; BSD-3-Clause) as the independent peer of
# `dea-fit dma` on datasets/dma/vhb_like_isotherms.csv: both fitted, both compared
# with the generating series; fails unless dea-fit is at least as close in E' rms
# and E_inf (.ci/pyvisco_reference.py). The venv lives in target/
# (PYVISCO_REFERENCE_VENV to put it elsewhere).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${PYVISCO_REFERENCE_VENV:-$root/target/pyvisco-reference-venv}
. "$root/.ci/venv.sh"
make_venv "$venv"
if ! "$venv/bin/python" -c 'import pyvisco, sys; sys.exit(pyvisco.__version__ != "2.1.3")' 2>/dev/null; then
    # pyvisco's own package imports numpy, pandas, scipy and matplotlib only; its
    # declared Jupyter/voila dependencies serve the notebook GUI (pyvisco.inter),
    # which is not used here.
    "$venv/bin/pip" install --quiet --no-deps "pyvisco==2.1.3"
    "$venv/bin/pip" install --quiet "numpy==2.4.6" "pandas==3.1.1" "scipy==1.17.1" "matplotlib==3.11.2"
fi
(cd "$root" && cargo build --quiet --release --bin dea-fit)
exec "$venv/bin/python" "$root/.ci/pyvisco_reference.py" "$root/target/release/dea-fit"
