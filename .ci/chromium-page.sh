#!/usr/bin/env bash
# One report page rendered by a real browser (docs/reports.md): installs Debian's
# headless chromium (about 1 min 40 s for apt-get update + install on the 2-core CI
# machine, measured; nothing when it is already installed), then runs the test that
# the default `cargo test` counts as ignored, and opens one page of every kind the
# tool writes (.ci/report-pages.sh, about 30 s). A missing browser fails it.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v chromium >/dev/null; then
    if [ "$(id -u)" != 0 ]; then
        echo "chromium-page: chromium is not installed and installing it needs root" >&2
        exit 2
    fi
    t0=$(date +%s)
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
    echo "chromium-page: installed chromium in $(( $(date +%s) - t0 )) s"
fi
cargo test --release page_renders_in_chromium -- --ignored
.ci/report-pages.sh
