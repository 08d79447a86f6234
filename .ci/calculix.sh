#!/usr/bin/env bash
# A real FE solver in the loop (docs/export.md, "CalculiX"): installs Debian's
# calculix-ccx (nothing when `ccx` is already there), then runs the test that the
# default `cargo test` counts as ignored: one `dea-fit export --to calculix` card per
# hyperelastic model CalculiX has, each run in ccx on one element in uniaxial,
# equibiaxial and planar tension, the stress compared with dea-fit's own (1e-3
# relative). The ccx runs take about a second in all. A missing solver fails it.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v ccx >/dev/null; then
    if [ "$(id -u)" != 0 ]; then
        echo "calculix: ccx is not installed and installing it needs root" >&2
        exit 2
    fi
    t0=$(date +%s)
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq calculix-ccx >/dev/null
    echo "calculix: installed calculix-ccx in $(( $(date +%s) - t0 )) s"
fi
cargo test --release --test main calculix_one_element_gives_the_fit_stress -- --ignored --nocapture
