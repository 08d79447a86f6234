"""Reference Weibull fits of datasets/breakdown/reference/*.csv by an independent
implementation, the `reliability` package (Reid, reliability.readthedocs.io), for
tests/weibull.rs. Run by .ci/weibull-reference.sh (which makes the venv).

Conventions of reliability 0.9.0 (Fit_Weibull_2P), compared like with like in the
Rust test:
- MLE with right censoring; RRX regresses x = ln t on y = ln(-ln(1-F)), RRY y on x.
- Plotting positions (Probability_plotting.plotting_positions): Johnson's adjusted
  ranks with Bernard's (i - 0.3)/(n + 0.4) (a = 0.3). Its sort of the fields is not
  stable, so the series have no breakdown and survivor at the same field.
- Bounds: Fisher bounds from the inverse Hessian of the log-likelihood evaluated
  at the estimates (for RRX/RRY too), on the log scale: alpha*exp(+-z*SE/alpha),
  beta*exp(+-z*SE/beta), z = 1.959964 (CI = 0.95).
- Log-likelihood of the fields in the file's unit (V/um).

Usage: weibull_reference.py [--check]  (--check: recompute and fail when the
committed JSON differs).
"""
import csv
import json
import pathlib
import sys

import reliability
from reliability.Fitters import Fit_Weibull_2P

ROOT = pathlib.Path(__file__).resolve().parent.parent
DIR = ROOT / "datasets" / "breakdown" / "reference"
OUT = DIR / "reliability.json"


def sig(v):
    """Ten significant digits: the text is compared by --check."""
    return float(f"{v:.10g}")


def series(path):
    failures, survived = [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            e = float(row["field_V_per_um"])
            (survived if row["survived"].strip() == "1" else failures).append(e)
    return failures, survived


def fit(failures, survived, method):
    f = Fit_Weibull_2P(
        failures=failures,
        right_censored=survived or None,
        method=method,
        CI=0.95,
        show_probability_plot=False,
        print_results=False,
    )
    return {
        "alpha": sig(f.alpha),
        "beta": sig(f.beta),
        "alpha_se": sig(f.alpha_SE),
        "beta_se": sig(f.beta_SE),
        "alpha_ci95": [sig(f.alpha_lower), sig(f.alpha_upper)],
        "beta_ci95": [sig(f.beta_lower), sig(f.beta_upper)],
        "log_likelihood": sig(f.loglik),
    }


def compute():
    out = {
        "generator": f"reliability {reliability.__version__} Fit_Weibull_2P (.ci/weibull_reference.py)",
        "unit": "V/um",
        "series": {},
    }
    for path in sorted(DIR.glob("*.csv")):
        failures, survived = series(path)
        out["series"][path.name] = {
            "n": len(failures) + len(survived),
            "failures": len(failures),
            "mle": fit(failures, survived, "MLE"),
            "rrx": fit(failures, survived, "RRX"),
            "rry": fit(failures, survived, "RRY"),
        }
    return json.dumps(out, indent=2, sort_keys=True) + "\n"


def main():
    text = compute()
    if "--check" in sys.argv[1:]:
        if not OUT.exists() or OUT.read_text() != text:
            sys.stderr.write(
                f"{OUT.relative_to(ROOT)} differs from a fresh computation; "
                "run .ci/weibull-reference.sh and commit the result\n"
            )
            return 1
        print(f"{OUT.relative_to(ROOT)}: up to date")
        return 0
    OUT.write_text(text)
    print(f"wrote {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
