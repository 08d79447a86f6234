#!/usr/bin/env bash
# One report page of every kind the tool writes, opened in headless Chromium and
# checked (.ci/report_pages_check.py): hyperelastic, relaxation (QLV), permittivity,
# composite, breakdown, simulate, static, identify, rank, the run index of a report
# folder, the project page of the lab project (dea-fit make), and the bench pages
# (hyperelastic, relaxation, identify). Each page loads without errors, every file
# it or its Markdown twin links exists and loads (an SVG as an image), every chart
# has marks, and no chart text lies outside its chart or over another text. Needs chromium and a built target/release/dea-fit
# (.ci/chromium-page.sh installs the one and .ci/run builds the other). About 25 s
# on the 2-core machine (the pages' runs take 8 s of it, the 15 browser runs the rest).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
B=$root/target/release/dea-fit
[ -x "$B" ] || cargo build --release
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
R=$out/reports
(
    set -x
    $B hyperelastic datasets/vhb4910/uniaxial.csv datasets/vhb4910/equibiaxial.csv --model yeoh --report "$R/hyperelastic" --out "$out/h.json"
    $B relaxation datasets/vhb4910/relaxation.csv --strain 0.5 --hyperelastic tests/data/export/vhb4910-yeoh.json --report "$R/relaxation" --out "$out/r.json"
    $B permittivity datasets/composites/sylgard_batio3/*.csv --diameter 42.80mm --thickness 2.2mm --stray 0.3pF --report "$R/permittivity"
    $B composite datasets/composites/sylgard_batio3.toml --report "$R/composite" --out "$out/c.json"
    $B breakdown datasets/breakdown/vhb4910-coupons.csv --report "$R/breakdown" --out "$out/b.json"
    $B simulate datasets/scenes/stack_step_5kV.toml --report "$R/simulate" --out "$out/sim.csv"
    $B static datasets/scenes/stack_step_5kV.toml --report "$R/static" --out "$out/static.csv"
    $B identify datasets/identify/step.csv --scene datasets/identify/stack.toml --free C10,eps_r --starts 2 --report "$R/identify" --out "$out/id.json"
    $B rank datasets/design/silicone_fillers.toml --report "$R/rank"
    $B bench hyperelastic --out-dir "$out/bench" --budget 0 --min-repeats 1
    # the project page of the lab project (make writes it over the run list)
    cp -r datasets/lab "$out/lab" && rm -rf "$out/lab/fits" "$out/lab/reports" "$out/lab/.dea-fit"
    $B make -C "$out/lab" --jobs 2
    # bench relaxation and identify write into ./reports/bench
    cd "$out" && $B bench relaxation && $B bench identify --scene "$root/datasets/scenes/stack_rig_7s.toml"
) >"$out/log" 2>&1 || { cat "$out/log"; echo "report-pages: making the pages failed" >&2; exit 1; }
python3 .ci/report_pages_check.py "$R"/*/index.html "$R/index.html" "$out/lab/reports/index.html" \
    "$out/bench/hyperelastic.html" "$out/reports/bench/relaxation.html" "$out/reports/bench/identify.html"
