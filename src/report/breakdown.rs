//! The outputs of `dea-fit breakdown`: the fit file's object ([`BreakdownResult`]:
//! the core's [`BreakdownFit`], schema `dea-fit/breakdown/1`, and what the command
//! adds beside it), the summary, and the report: a Weibull probability plot on
//! probability-paper axes (x: log field; y: ln(−ln(1 − F)) labelled in % of
//! specimens failed) with the breakdowns at their plotting positions, the survivors
//! marked at the field they reached, the fitted line and its 95 % confidence band,
//! and a page with the table.

use super::format::sig;
use super::page::{code, text, Page, Tone};
use super::plot::{band, Chart, Series, Style, PROBABILITY_PAPER};
use super::runs::Run;
use crate::error::Result;
use crate::fit::weibull::{BoundKind, Estimate, Method, Percentile, WeibullFit};
use crate::io::breakdown::BreakdownSeries;
use crate::material::breakdown::area_factor;
use crate::material::file::{
    BreakdownFit, BreakdownParameter, BreakdownPercentile, BREAKDOWN_SCHEMA,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The percentiles every breakdown output gives: E_1 %, E_10 % (a safe working
/// field) and α (F = 1 − 1/e ≈ 63.2 %).
pub fn percentile_levels() -> [f64; 3] {
    [0.01, 0.10, -(-1f64).exp_m1()]
}

/// The goodness-of-fit test of a straight Weibull plot, as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GoodnessOut {
    /// The test and its source.
    pub test: String,
    /// Its statistic.
    pub statistic: f64,
    /// Its 5 % critical value.
    pub critical5: f64,
    /// p-value, where the test gives one.
    pub p_value: Option<f64>,
    /// Consistent with one Weibull population at the 5 % level.
    pub straight: bool,
}

/// α and the percentiles carried to the actuator's electrode area (`--area`) by the
/// weakest-link law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AtArea {
    /// The actuator's electrode area (m²).
    pub area_m2: f64,
    /// The factor on α, (A₀/A)^(1/β).
    pub alpha_factor: f64,
    /// E_1 %, E_10 % and α at that area, with bounds.
    pub percentiles: Vec<BreakdownPercentile>,
}

/// One specimen as the probability plot shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlotRow {
    /// Its label, or its row number in the series.
    pub specimen: String,
    /// Field (V/m).
    pub field: f64,
    /// Plotting position F (None for a survivor).
    pub probability: Option<f64>,
    /// It survived to `field`.
    pub survived: bool,
}

/// What `dea-fit breakdown` writes as its fit file and prints with `--json`: the
/// core's [`BreakdownFit`] (which scenes and the ranking read) and, beside it, what
/// a reader of the fit does not need.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BreakdownResult {
    /// The fit file's contract.
    #[serde(flatten)]
    pub fit: BreakdownFit,
    /// The plotting position of the probability plot (and of a rank regression).
    pub plot_positions: String,
    /// How `beta_unbiased` was computed (or why there is none).
    pub beta_unbiased_method: String,
    /// Goodness of fit of a straight Weibull plot, where a test applies.
    pub goodness: Option<GoodnessOut>,
    /// At the actuator's electrode area (`--area`).
    pub actuator: Option<AtArea>,
    /// The specimens at their plotting positions, in field order.
    pub plot: Vec<PlotRow>,
}

/// A parameter of the file from an estimate, with the bounds of `kind`.
fn parameter(name: &str, unit: &str, e: &Estimate, kind: BoundKind) -> BreakdownParameter {
    BreakdownParameter {
        name: name.into(),
        unit: unit.into(),
        value: e.value,
        std_error: e.std_error,
        ci95: e.bounds(kind).map(|(a, b)| [a, b]),
    }
}

fn percentile_out(p: &Percentile, kind: BoundKind) -> BreakdownPercentile {
    BreakdownPercentile {
        p: p.p,
        value: p.estimate.value,
        std_error: p.estimate.std_error,
        ci95: p.estimate.bounds(kind).map(|(a, b)| [a, b]),
    }
}

/// The smallest and largest of the specimens' values of a covariate.
fn range(values: impl Iterator<Item = Option<f64>>) -> Option<[f64; 2]> {
    values.flatten().fold(None, |r, v| match r {
        None => Some([v, v]),
        Some([lo, hi]) => Some([lo.min(v), hi.max(v)]),
    })
}

/// The fit file's object of a fit of `series` (the settings and input files in
/// `provenance`), with percentiles at the actuator's electrode area `area` (m²)
/// when given.
pub fn result(
    fit: &WeibullFit,
    series: &[BreakdownSeries],
    area: Option<f64>,
    provenance: serde_json::Value,
) -> Result<BreakdownResult> {
    let kind = fit.bounds;
    let mut parameters = vec![
        parameter("alpha", "V/m", &fit.alpha, kind),
        parameter("beta", "1", &fit.beta, kind),
    ];
    let (mut reference_thickness, mut reference_prestretch) = (None, None);
    let (mut thickness_range, mut prestretch_range) = (None, None);
    let specimens = || series.iter().flat_map(|s| &s.specimens);
    for x in &fit.exponents {
        let name = format!("{}_exponent", x.covariate.name());
        parameters.push(parameter(&name, "1", &x.estimate, kind));
        match x.covariate {
            crate::fit::weibull::Covariate::Thickness => {
                reference_thickness = Some(x.reference);
                thickness_range = range(specimens().map(|s| s.thickness));
            }
            crate::fit::weibull::Covariate::Prestretch => {
                reference_prestretch = Some(x.reference);
                prestretch_range = range(specimens().map(|s| s.prestretch));
            }
        }
    }
    if let Some(t) = &fit.threshold {
        parameters.push(parameter("threshold", "V/m", t, kind));
    }
    let levels = percentile_levels();
    let at = |a: Option<f64>| -> Result<Vec<BreakdownPercentile>> {
        levels
            .iter()
            .map(|&p| Ok(percentile_out(&fit.percentile(p, a)?, kind)))
            .collect()
    };
    let percentiles = at(None)?;
    let actuator = match area {
        Some(a) => Some(AtArea {
            area_m2: a,
            alpha_factor: fit
                .reference_area
                .map_or(1.0, |a0| area_factor(a0, a, fit.beta.value)),
            percentiles: at(Some(a))?,
        }),
        None => None,
    };
    let labels: Vec<String> = specimens()
        .enumerate()
        .map(|(i, s)| s.label.clone().unwrap_or_else(|| format!("#{}", i + 1)))
        .collect();
    let plot = fit
        .plot
        .iter()
        .map(|p| PlotRow {
            specimen: labels.get(p.specimen).cloned().unwrap_or_default(),
            field: p.field,
            probability: p.probability,
            survived: p.survived,
        })
        .collect();
    Ok(BreakdownResult {
        fit: BreakdownFit {
            schema: BREAKDOWN_SCHEMA.into(),
            tool_version: env!("CARGO_PKG_VERSION").into(),
            status: fit.status.to_string(),
            method: fit.method.name().into(),
            positions: fit.positions.map(|p| p.name().into()),
            n: fit.n,
            failures: fit.failures,
            survived: fit.survived,
            parameters,
            correlation: fit
                .correlation
                .as_ref()
                .map(|c| {
                    c.iter()
                        .map(|r| r.iter().map(|v| v.is_finite().then_some(*v)).collect())
                        .collect()
                })
                .unwrap_or_default(),
            beta_unbiased: fit.beta_unbiased,
            log_likelihood: fit.log_likelihood,
            percentiles,
            reference_area: fit.reference_area,
            reference_thickness,
            reference_prestretch,
            thickness_range,
            prestretch_range,
            bounds: kind.name().into(),
            warnings: fit.warnings.clone(),
            provenance,
        },
        plot_positions: fit.plot_positions.name().into(),
        beta_unbiased_method: fit.beta_unbiased_method.clone(),
        goodness: fit.goodness.as_ref().map(|g| GoodnessOut {
            test: g.test.clone(),
            statistic: g.statistic,
            critical5: g.critical5,
            p_value: g.p_value,
            straight: g.straight,
        }),
        actuator,
        plot,
    })
}

/// A field in V/µm, four significant digits.
fn field(v: f64) -> String {
    format!("{} V/µm", sig(v * 1e-6, 4))
}

/// `lo – hi` in V/µm, or "—".
fn bounds(ci: Option<[f64; 2]>, unit: fn(f64) -> String) -> String {
    ci.map_or("—".into(), |[a, b]| format!("{} – {}", unit(a), unit(b)))
}

/// A plain number, four significant digits.
fn plain(v: f64) -> String {
    sig(v, 4)
}

/// The method in words.
fn method_words(r: &BreakdownResult) -> String {
    match r.fit.method.as_str() {
        "mle" => format!(
            "maximum likelihood{} (plotting positions of the plot only: {})",
            if r.fit.survived > 0 {
                " with right censoring"
            } else {
                ""
            },
            r.plot_positions
        ),
        m => format!(
            "rank regression {} ({}), plotting positions {}",
            m,
            if m == "rry" {
                "y = ln(−ln(1 − F)) on ln E"
            } else {
                "ln E on y = ln(−ln(1 − F))"
            },
            r.fit.positions.as_deref().unwrap_or(&r.plot_positions)
        ),
    }
}

/// The share `p` as a label: "1 %", "10 %", "63.2 %".
fn percent(p: f64) -> String {
    let s = format!("{:.1}", 100.0 * p);
    format!("{} %", s.trim_end_matches(".0"))
}

/// Table rows of percentiles: E_p with bounds.
fn percentile_rows(ps: &[BreakdownPercentile]) -> Vec<Vec<String>> {
    ps.iter()
        .map(|p| {
            let name = match p.p {
                x if (x - percentile_levels()[2]).abs() < 1e-12 => "α (63.2 %)".to_string(),
                x => format!("E_{}", percent(x).replace(' ', "")),
            };
            vec![
                name,
                field(p.value),
                p.std_error.map_or("—".into(), field),
                bounds(p.ci95, field),
            ]
        })
        .collect()
}

/// The summary `dea-fit breakdown` prints: the report's page without its chart.
pub fn summary(r: &BreakdownResult, series: &[BreakdownSeries]) -> Result<String> {
    Ok(page(r, series, |_| Ok(()))?.terminal())
}

/// The one rendering of a breakdown fit (terminal, Markdown and HTML).
fn page(
    r: &BreakdownResult,
    series: &[BreakdownSeries],
    charts: impl FnOnce(&mut Page) -> Result<()>,
) -> Result<Page> {
    let f = &r.fit;
    let mut page = Page::new(format!(
        "Breakdown: {}-parameter Weibull, {}",
        if f.parameter("threshold").is_some() {
            "three"
        } else {
            "two"
        },
        match f.method.as_str() {
            "mle" => "maximum likelihood",
            _ => "rank regression",
        }
    ));
    for s in series {
        page.para(vec![
            text("Data: "),
            code(s.path.display().to_string()),
            text(format!(
                " ({} specimens, sha256 {}…){}.",
                s.specimens.len(),
                s.sha256.get(..12).unwrap_or(&s.sha256),
                match s.conversions.as_slice() {
                    [] => String::new(),
                    c => format!("; {}", c.join("; ")),
                }
            )),
        ]);
    }
    page.text(format!(
        "{} specimens: {} breakdowns, {} survived (right-censored); electrode area {}.",
        f.n,
        f.failures,
        f.survived,
        f.reference_area
            .map_or("not given".into(), |a| format!("{} mm²", sig(a * 1e6, 4)))
    ));
    page.text(format!("Method: {}.", method_words(r)));
    page.status_line(&f.status, Tone::of(&f.status));
    charts(&mut page)?;
    let kind = match f.bounds.as_str() {
        "likelihood-ratio" => "likelihood-ratio (profile)",
        _ => "Fisher (normal on the log scale)",
    };
    page.heading("Weibull parameters");
    let mut rows: Vec<Vec<String>> = Vec::new();
    for p in &f.parameters {
        let unit: fn(f64) -> String = if p.unit == "V/m" { field } else { plain };
        let name = match p.name.as_str() {
            "alpha" => "α".to_string(),
            "beta" => "β".to_string(),
            "threshold" => "threshold γ".to_string(),
            n => n.replace('_', " "),
        };
        rows.push(vec![
            name,
            unit(p.value),
            p.std_error.map_or("—".into(), unit),
            bounds(p.ci95, unit),
        ]);
        if p.name == "beta" {
            rows.push(vec![
                "β unbiased".into(),
                f.beta_unbiased.map_or("—".into(), plain),
                "".into(),
                "".into(),
            ]);
        }
    }
    rows.extend(
        percentile_rows(&f.percentiles)
            .into_iter()
            .filter(|r| !r[0].starts_with('α')),
    );
    page.table(
        &["quantity", "value", "σ", &format!("95 % bounds ({kind})")],
        rows,
    );
    page.text(format!(
        "β unbiased: {}. Percentiles E_p = α·(−ln(1 − p))^(1/β){}; σ: standard error from the observed information; log-likelihood {:.4} (fields in V/m).",
        r.beta_unbiased_method,
        if f.parameter("threshold").is_some() { " + γ" } else { "" },
        f.log_likelihood
    ));
    if let Some(a) = &r.actuator {
        page.heading(format!(
            "At the actuator's electrode area, {} mm²",
            sig(a.area_m2 * 1e6, 4)
        ));
        page.text(format!(
            "Weakest link (IEEE Std 930 §6.5): α × (A₀/A)^(1/β) = α × {:.4} from the specimens' {}.",
            a.alpha_factor,
            f.reference_area
                .map_or("area".into(), |a0| format!("{} mm²", sig(a0 * 1e6, 4)))
        ));
        page.table(
            &["quantity", "value", "σ", &format!("95 % bounds ({kind})")],
            percentile_rows(&a.percentiles)
                .into_iter()
                .map(|mut r| {
                    r[0] = r[0].replace("α (63.2 %)", "α at this area");
                    r
                })
                .collect(),
        );
    }
    if r.goodness.is_none() && f.survived > 0 {
        page.text(format!(
            "Goodness of fit: not tested. The Anderson–Darling test here is for complete series, and {} of {} specimens survived (docs/breakdown.md); judge the straightness of the Weibull plot by eye.",
            f.survived, f.n
        ));
    }
    if let Some(g) = &r.goodness {
        page.text(format!(
            "Goodness of fit: {} = {:.4} (5 % critical value {:.4}{}): {}.",
            g.test,
            g.statistic,
            g.critical5,
            g.p_value.map_or(String::new(), |p| format!(", p = {p:.3}")),
            if g.straight {
                "consistent with one Weibull population"
            } else {
                "the Weibull plot is not straight"
            }
        ));
    }
    page.warnings(&f.warnings);
    Ok(page)
}

/// The Weibull probability plot: y = ln(−ln(1 − F)) against log field, breakdowns at
/// their plotting positions, survivors as open marks at the field they reached (on
/// the fitted line: they have no rank of their own), the fitted line and its 95 %
/// Fisher band over the data's range.
pub fn chart(r: &BreakdownResult, fit: &WeibullFit) -> Chart {
    let y = |f: f64| (-(-f).ln_1p()).ln();
    let (lo, hi) = r.plot.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.field), b.max(p.field))
    });
    let (lo, hi) = (lo / 1.15, hi * 1.1);
    let xs: Vec<f64> = (0..=80)
        .map(|i| lo * (hi / lo).powf(i as f64 / 80.0))
        .filter(|&e| (1e-4..1.0 - 1e-6).contains(&fit.cdf(e)))
        .collect();
    let (down, up): (Vec<f64>, Vec<f64>) = fit
        .band(&xs)
        .into_iter()
        .map(|(a, b)| (y(a.max(1e-6)), y(b.min(1.0 - 1e-9))))
        .unzip();
    let line: Vec<(f64, f64)> = xs.iter().map(|&e| (e, y(fit.cdf(e)))).collect();
    let positions = format!("{} plotting positions", r.plot_positions);
    Chart {
        title: format!("Weibull probability plot ({}, {})", r.fit.method, positions),
        x_label: "breakdown field".into(),
        y_label: "failed (%)".into(),
        series: vec![
            Series {
                label: "95 % confidence band of the fit (Fisher)".into(),
                points: band(&xs, &down, &up),
                color: 1,
                style: Style::Band,
            },
            Series {
                label: format!(
                    "fit: α {}, β {}",
                    field(r.fit.law().alpha),
                    plain(r.fit.law().beta)
                ),
                points: line,
                color: 1,
                style: Style::Line,
            },
            Series {
                label: format!("breakdowns ({positions})"),
                points: r
                    .plot
                    .iter()
                    .filter_map(|p| p.probability.map(|f| (p.field, y(f))))
                    .collect(),
                color: 0,
                style: Style::Points,
            },
            Series {
                label: "survived (open: at the field reached, on the fit)".into(),
                points: r
                    .plot
                    .iter()
                    .filter(|p| p.survived)
                    .map(|p| (p.field, y(fit.cdf(p.field).clamp(1e-6, 1.0 - 1e-9))))
                    .collect(),
                color: 0,
                style: Style::OpenPoints,
            },
        ],
        log_x: true,
        x_unit: Some("V/m".into()),
        y_unit: Some(PROBABILITY_PAPER.into()),
    }
}

/// Write `weibull.svg` and the page (`index.md`, `index.html`, `run.json`) into
/// `dir`; returns the HTML page.
pub fn write(
    r: &BreakdownResult,
    fit: &WeibullFit,
    series: &[BreakdownSeries],
    dir: &Path,
) -> Result<PathBuf> {
    let chart = chart(r, fit);
    let page = page(r, series, |page| {
        page.chart(dir, "weibull.svg", "Weibull probability plot", &chart)
    })?;
    let files: Vec<String> = series
        .iter()
        .map(|s| s.path.display().to_string())
        .collect();
    let law = r.fit.law();
    let mut headline = vec![
        format!("α {}", field(law.alpha)),
        format!("β {}", plain(law.beta)),
    ];
    if let Some(p) = r.fit.percentiles.first() {
        headline.push(format!("E_1% {}", field(p.value)));
    }
    let run = Run::new(
        "breakdown",
        files.join(", "),
        format!(
            "Weibull, {}",
            match fit.method {
                Method::Mle => "maximum likelihood".to_string(),
                m => format!("rank regression {m}"),
            }
        ),
    )
    .headline(headline);
    page.write(dir, "index", run)
}
