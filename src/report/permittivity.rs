//! Reports of permittivity runs and composite series: εr and tan δ against
//! frequency (log axis) for all samples on one figure each, εr against filler volume
//! fraction with the fitted mixing rules, and a Markdown page with the tables.

use super::format::{si, si_pm, sig, tolerance};
use super::page::{code, text, Page};
use super::plot::{error_bars, Chart, Series, Style};
use super::runs::Run;
use crate::error::Result;
use crate::fit::composite::{CompositeFit, FrequencyFit};
use crate::fit::permittivity::{PermittivityRun, SamplePermittivity};
use std::path::{Path, PathBuf};

/// At most this many samples are drawn on one figure (the tables list all).
pub const MAX_DRAWN: usize = 24;

/// The εr and tan δ charts of `samples` (the first [`MAX_DRAWN`]), drawn into `dir`
/// and shown on `page`.
fn freq_charts(samples: &[SamplePermittivity], page: &mut Page, dir: &Path) -> Result<()> {
    let drawn = &samples[..samples.len().min(MAX_DRAWN)];
    let series = |f: &dyn Fn(&crate::fit::permittivity::PermittivityPoint) -> f64| {
        drawn
            .iter()
            .enumerate()
            .map(|(i, s)| Series {
                label: s.name.clone(),
                points: s.points.iter().map(|p| (p.freq_hz, f(p))).collect(),
                color: i,
                style: Style::Line,
            })
            .collect()
    };
    // εr′ ± σ where the geometry's tolerances give one
    let mut eps_series: Vec<Series> = series(&|p| p.eps_r);
    for (i, s) in drawn.iter().enumerate() {
        let bars = error_bars(
            s.points
                .iter()
                .map(|p| (p.freq_hz, p.eps_r, p.eps_r_std.unwrap_or(f64::NAN))),
        );
        if !bars.is_empty() {
            eps_series.push(Series {
                label: format!("{} ± σ", s.name),
                points: bars,
                color: i,
                style: Style::ErrorBars,
            });
        }
    }
    let eps = Chart {
        title: "Relative permittivity".into(),
        x_label: "frequency (Hz)".into(),
        y_label: "εr′".into(),
        series: eps_series,
        log_x: true,
        x_unit: None,
        y_unit: None,
    };
    // tan δ from 0: a flat loss with ±0.7 % noise on an axis hugging the data
    // reads as peaks; from 0 the noise shows as what it is
    let mut tan_series: Vec<Series> = series(&|p| p.tan_delta);
    let first_f = drawn
        .iter()
        .flat_map(|s| s.points.first())
        .map(|p| p.freq_hz)
        .next();
    tan_series.extend(first_f.map(|f| Series {
        label: String::new(),
        points: vec![(f, 0.0)],
        color: 0,
        style: Style::Anchor,
    }));
    let tan = Chart {
        title: "Loss tangent".into(),
        x_label: "frequency (Hz)".into(),
        y_label: "tan δ (axis from 0)".into(),
        series: tan_series,
        log_x: true,
        x_unit: None,
        y_unit: None,
    };
    page.chart(dir, "eps_r.svg", "εr", &eps)?;
    page.chart(dir, "tan_delta.svg", "tan δ", &tan)?;
    if samples.len() > MAX_DRAWN {
        page.text(format!(
            "The figures show the first {MAX_DRAWN} of {} samples.",
            samples.len()
        ));
    }
    Ok(())
}

/// Indices of the points nearest each decade (at most 8 rows per sample).
fn decade_rows(s: &SamplePermittivity) -> Vec<usize> {
    let mut idx: Vec<usize> = Vec::new();
    let (Some(lo), Some(hi)) = (s.points.first(), s.points.last()) else {
        return idx;
    };
    let (a, b) = (
        lo.freq_hz.log10().floor() as i32,
        hi.freq_hz.log10().ceil() as i32,
    );
    for e in a..=b {
        let target = 10f64.powi(e);
        if let Some(i) = (0..s.points.len()).min_by(|&x, &y| {
            let d = |k: usize| (s.points[k].freq_hz.log10() - target.log10()).abs();
            d(x).total_cmp(&d(y))
        }) {
            if !idx.contains(&i) {
                idx.push(i);
            }
        }
    }
    idx
}

/// The header of a sample's table.
const SAMPLE_HEADER: [&str; 6] = ["f (Hz)", "εr′", "± σ", "εr″", "tan δ", "σ (S/m)"];

/// The rows of one sample's table (all points, or the points nearest each decade
/// when `decades`).
fn sample_rows(s: &SamplePermittivity, decades: bool) -> Vec<Vec<String>> {
    let idx: Vec<usize> = if decades {
        decade_rows(s)
    } else {
        (0..s.points.len()).collect()
    };
    idx.iter()
        .map(|&i| {
            let p = &s.points[i];
            vec![
                sig(p.freq_hz, 6),
                format!("{:.4}", p.eps_r),
                tolerance(p.eps_r_std, |v| format!("{v:.4}")),
                format!("{:.4e}", p.eps_loss),
                format!("{:.4e}", p.tan_delta),
                format!("{:.3e}", p.conductivity),
            ]
        })
        .collect()
}

/// One section per sample: its source, geometry and status, its table (every point,
/// or the points nearest each decade when `decades`), and its notes (its warnings are
/// the run's, prefixed with its name).
fn samples_section(samples: &[SamplePermittivity], decades: bool, page: &mut Page) {
    for s in samples {
        let g = &s.geometry;
        page.heading(s.name.clone());
        page.para(vec![
            code(&s.provenance.path),
            text(format!(
                " ({} {}), A = {}, d = {}; status {}",
                s.provenance.format,
                s.provenance.pair.name(),
                // an SI prefix on m² would read as (mm)², so the area takes a power of ten
                if g.area_std.is_some() {
                    format!("{} m²", si_pm(g.area, g.area_std, "1"))
                } else {
                    format!("{:.4e} m² (no tolerance)", g.area)
                },
                if g.thickness_std.is_some() {
                    si_pm(g.thickness, g.thickness_std, "m")
                } else {
                    format!("{} (no tolerance)", si(g.thickness, "m"))
                },
                s.status
            )),
        ]);
        page.table(&SAMPLE_HEADER, sample_rows(s, decades));
        page.bullets(s.notes.iter().map(|n| format!("note: {n}")));
    }
}

/// The one rendering of a permittivity batch (the terminal, Markdown and HTML all
/// show this page): status, `charts` (added by the report), the counts, warnings,
/// then one section per sample (every point up to 10 samples, the points nearest
/// each decade beyond).
fn samples_page(
    run: &PermittivityRun,
    charts: impl FnOnce(&mut Page) -> Result<()>,
) -> Result<Page> {
    let mut page = Page::new("Permittivity");
    page.status_line(run.status, run.status);
    charts(&mut page)?;
    page.text(format!(
        "{} sample(s); {} file(s) could not be used.",
        run.samples.len(),
        run.failed.len()
    ));
    page.warnings(&run.warnings);
    samples_section(&run.samples, run.samples.len() > 10, &mut page);
    Ok(page)
}

/// The summary `dea-fit permittivity` prints: the report's page without its charts.
pub fn summary(run: &PermittivityRun) -> Result<String> {
    Ok(samples_page(run, |_| Ok(()))?.terminal())
}

/// Write `eps_r.svg`, `tan_delta.svg` and the page (`index.md`, `index.html`,
/// `run.json`) for a batch; returns the HTML page.
pub fn write_samples(run: &PermittivityRun, dir: &Path) -> Result<PathBuf> {
    let page = samples_page(run, |page| freq_charts(&run.samples, page, dir))?;
    let files: Vec<&str> = run
        .samples
        .iter()
        .map(|s| s.provenance.path.as_str())
        .collect();
    let headline = run
        .samples
        .iter()
        .take(3)
        .filter_map(|s| {
            let i = *decade_rows(s).iter().min_by(|&&a, &&b| {
                let d = |k: usize| (s.points[k].freq_hz.log10() - 3.0).abs();
                d(a).total_cmp(&d(b))
            })?;
            let p = &s.points[i];
            Some(format!(
                "{}: εr′ {:.3} at {} Hz",
                s.name,
                p.eps_r,
                sig(p.freq_hz, 4)
            ))
        })
        .collect();
    let r = Run::new(
        "permittivity",
        files.join(", "),
        format!("{} sample(s)", run.samples.len()),
    )
    .headline(headline);
    page.write(dir, "index", r)
}

/// The frequency fit nearest 1 kHz (the figure's reference), if any.
pub fn reference_fit(fit: &CompositeFit) -> Option<&FrequencyFit> {
    fit.fits.iter().min_by(|a, b| {
        let d = |f: &FrequencyFit| (f.freq_hz.log10() - 3.0).abs();
        d(a).total_cmp(&d(b))
    })
}

/// The header of a frequency's ranking table.
const RANKING_HEADER: [&str; 8] = [
    "rule",
    "εm",
    "εf (effective)",
    "n",
    "RMS %",
    "AICc",
    "Δ",
    "status",
];

/// The rows of the ranking of the mixing rules at one frequency.
fn ranking_rows(f: &FrequencyFit) -> Vec<Vec<String>> {
    f.rules
        .iter()
        .map(|r| {
            let par = |name: &str| {
                r.parameters
                    .iter()
                    .find(|p| p.name == name)
                    .map(|p| {
                        format!(
                            "{}{}",
                            sig(p.value, 4),
                            p.std_error
                                .map(|s| format!(" ± {}", sig(s, 2)))
                                .unwrap_or_default()
                        )
                    })
                    .unwrap_or_else(|| "–".into())
            };
            vec![
                r.rule.name().to_string(),
                par("eps_matrix"),
                par("eps_filler"),
                par("shape_n"),
                format!("{:.3}", r.rms_rel_pct),
                r.aicc.map(|a| format!("{a:.2}")).unwrap_or("n/a".into()),
                format!("{:.2}", r.delta),
                r.status.to_string(),
            ]
        })
        .collect()
}

/// εr against filler volume fraction at the frequency of `rf`: the data and every
/// rule's curve (dashed where its fit is not usable).
fn mixing_chart(rf: &FrequencyFit) -> Chart {
    let phi_max = rf
        .data
        .iter()
        .map(|d| d.volume_fraction)
        .fold(0.0, f64::max)
        .max(0.05)
        * 1.2;
    let mut series = vec![Series {
        label: format!("data at {} Hz", sig(rf.freq_hz, 4)),
        points: rf
            .data
            .iter()
            .map(|d| (d.volume_fraction, d.eps_r))
            .collect(),
        color: 0,
        style: Style::Points,
    }];
    for (i, r) in rf.rules.iter().enumerate() {
        let p = |n: &str| r.parameters.iter().find(|p| p.name == n).map(|p| p.value);
        let (em, ef, n) = (
            p("eps_matrix").unwrap_or(1.0),
            r.eps_filler_eff,
            p("shape_n").unwrap_or(3.0),
        );
        series.push(Series {
            label: format!("{} (Δ {:.1})", r.rule.name(), r.delta),
            points: (0..=100)
                .map(|k| {
                    let phi = phi_max * k as f64 / 100.0;
                    (phi, r.rule.eval(em, ef, phi, n))
                })
                .collect(),
            color: i + 1,
            style: if r.status.is_blocking() {
                Style::Dashed
            } else {
                Style::Line
            },
        });
    }
    // the rules' curves run beyond the measured fractions: shade the range the
    // data support
    let (lo, hi) = rf
        .data
        .iter()
        .map(|d| d.volume_fraction)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if lo < hi {
        series.insert(
            0,
            Series {
                label: "fractions measured (beyond: extrapolated)".into(),
                points: vec![(lo, 0.0), (hi, 0.0)],
                color: 8,
                style: Style::Span,
            },
        );
    }
    Chart {
        title: format!(
            "εr against filler volume fraction at {} Hz",
            sig(rf.freq_hz, 4)
        ),
        x_label: "filler volume fraction φ".into(),
        y_label: "εr′".into(),
        series,
        log_x: false,
        x_unit: None,
        y_unit: None,
    }
}

/// The one rendering of a composite series (the terminal, Markdown and HTML all
/// show this page): matrix, filler and manifest, status, `charts` (added by the
/// report), the mixing rules at the reference frequency and over all frequencies,
/// the fractions, claims, warnings, then one section per sample.
fn composite_page(
    fit: &CompositeFit,
    charts: impl FnOnce(&mut Page) -> Result<()>,
) -> Result<Page> {
    let mut page = Page::new(fit.name.clone());
    page.para(vec![
        text(format!(
            "Matrix: {} · filler: {} · {} sample(s) · manifest ",
            fit.matrix.name,
            fit.filler.name,
            fit.samples.len()
        )),
        code(&fit.provenance.manifest),
    ]);
    page.status_line(fit.status, fit.status);
    charts(&mut page)?;
    if let Some(rf) = reference_fit(fit) {
        page.heading(format!("Mixing rules at {} Hz", sig(rf.freq_hz, 4)));
        page.table(&RANKING_HEADER, ranking_rows(rf));
        page.text(
            "Δ: AICc (BIC where AICc is undefined) minus the best at this frequency; \
             εf (effective): the filler permittivity the rule needs to fit the series.",
        );
    }
    if !fit.summary.is_empty() {
        let rows: Vec<Vec<String>> = fit
            .summary
            .iter()
            .map(|s| {
                vec![
                    s.rule.name().to_string(),
                    s.best_at.to_string(),
                    format!("{:.2}", s.median_delta),
                    format!(
                        "{} – {}",
                        sig(s.eps_filler_eff_range[0], 4),
                        sig(s.eps_filler_eff_range[1], 4)
                    ),
                    s.unusable_at.to_string(),
                ]
            })
            .collect();
        page.heading(format!("Over {} frequencies", fit.fits.len()));
        page.table(
            &["rule", "best at", "median Δ", "εf effective", "unusable at"],
            rows,
        );
        page.text(
            "best at / unusable at: the number of frequencies at which the rule ranked first \
             with a usable fit / had no usable fit.",
        );
    }
    let frows: Vec<Vec<String>> = fit
        .fractions
        .iter()
        .map(|f| {
            vec![
                f.name.clone(),
                format!("{} ({})", f.fraction, f.basis),
                format!("{:.4}", f.volume_fraction),
                f.weight_fraction
                    .map(|w| format!("{w:.4}"))
                    .unwrap_or("n/a".into()),
            ]
        })
        .collect();
    page.heading("Fractions");
    page.table(&["sample", "as given", "volume", "weight"], frows);
    if !fit.claims.is_empty() {
        page.heading("Claims");
        page.bullets(fit.claims.iter().map(|c| c.verdict.clone()));
    }
    page.warnings(&fit.warnings);
    samples_section(&fit.samples, true, &mut page);
    Ok(page)
}

/// The summary `dea-fit composite` prints: the report's page without its charts.
pub fn composite_summary(fit: &CompositeFit) -> Result<String> {
    Ok(composite_page(fit, |_| Ok(()))?.terminal())
}

/// Write the composite report (`eps_r.svg`, `tan_delta.svg`, `mixing.svg` and the page:
/// `index.md`, `index.html`, `run.json`) into `dir`; returns the HTML page.
pub fn write_composite(fit: &CompositeFit, dir: &Path) -> Result<PathBuf> {
    let page = composite_page(fit, |page| {
        freq_charts(&fit.samples, page, dir)?;
        match reference_fit(fit) {
            Some(rf) => page.chart(dir, "mixing.svg", "mixing rules", &mixing_chart(rf)),
            None => Ok(()),
        }
    })?;
    let headline = reference_fit(fit)
        .and_then(|rf| {
            let best = rf.rules.iter().min_by(|a, b| a.delta.total_cmp(&b.delta))?;
            Some(format!(
                "best rule at {} Hz: {} (RMS {:.3} %)",
                sig(rf.freq_hz, 4),
                best.rule.name(),
                best.rms_rel_pct
            ))
        })
        .into_iter()
        .collect();
    let run = Run::new(
        "composite",
        fit.provenance.manifest.clone(),
        format!("{} in {}", fit.filler.name, fit.matrix.name),
    )
    .headline(headline);
    page.write(dir, "index", run)
}
