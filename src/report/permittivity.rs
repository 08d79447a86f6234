//! Reports of permittivity runs and composite series: εr and tan δ against
//! frequency (log axis) for all samples on one figure each, εr against filler volume
//! fraction with the fitted mixing rules, and a Markdown page with the tables.

use super::format::{sig, table, tolerance};
use super::plot::{Chart, Series, Style};
use crate::error::Result;
use crate::fit::composite::{CompositeFit, FrequencyFit};
use crate::fit::permittivity::SamplePermittivity;
use crate::io::write::atomic_write;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// At most this many samples are drawn on one figure (the tables list all).
pub const MAX_DRAWN: usize = 24;

fn freq_charts(samples: &[SamplePermittivity], dir: &Path) -> Result<()> {
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
    Chart {
        title: "Relative permittivity".into(),
        x_label: "frequency (Hz)".into(),
        y_label: "εr′".into(),
        series: series(&|p| p.eps_r),
        log_x: true,
    }
    .write_svg(&dir.join("eps_r.svg"))?;
    Chart {
        title: "Loss tangent".into(),
        x_label: "frequency (Hz)".into(),
        y_label: "tan δ".into(),
        series: series(&|p| p.tan_delta),
        log_x: true,
    }
    .write_svg(&dir.join("tan_delta.svg"))
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

/// Text table of one sample (all points, or the points nearest each decade when
/// `decades`).
pub fn sample_table(s: &SamplePermittivity, decades: bool) -> String {
    let idx: Vec<usize> = if decades {
        decade_rows(s)
    } else {
        (0..s.points.len()).collect()
    };
    let rows: Vec<Vec<String>> = idx
        .iter()
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
        .collect();
    table(&["f (Hz)", "εr′", "± σ", "εr″", "tan δ", "σ (S/m)"], &rows)
}

fn samples_md(samples: &[SamplePermittivity], md: &mut String) {
    for s in samples {
        let _ = writeln!(
            md,
            "\n## {}\n\n`{}` ({}, {}), status {}\n",
            s.name,
            s.provenance.path,
            s.provenance.format,
            s.provenance.pair.name(),
            s.status
        );
        let _ = writeln!(md, "```\n{}```", sample_table(s, true));
        for w in &s.warnings {
            let _ = writeln!(md, "- warning: {w}");
        }
        for n in &s.notes {
            let _ = writeln!(md, "- {n}");
        }
    }
}

/// Write `eps_r.svg`, `tan_delta.svg` and `index.md` for a batch; returns the page.
pub fn write_samples(
    samples: &[SamplePermittivity],
    warnings: &[String],
    dir: &Path,
) -> Result<PathBuf> {
    freq_charts(samples, dir)?;
    let mut md = String::from("# Permittivity\n\n![εr](eps_r.svg)\n\n![tan δ](tan_delta.svg)\n");
    if samples.len() > MAX_DRAWN {
        let _ = writeln!(
            md,
            "\nThe figures show the first {MAX_DRAWN} of {} samples.",
            samples.len()
        );
    }
    for w in warnings {
        let _ = writeln!(md, "- warning: {w}");
    }
    samples_md(samples, &mut md);
    let page = dir.join("index.md");
    atomic_write(&page, md.as_bytes())?;
    Ok(page)
}

/// The frequency fit nearest 1 kHz (the figure's reference), if any.
pub fn reference_fit(fit: &CompositeFit) -> Option<&FrequencyFit> {
    fit.fits.iter().min_by(|a, b| {
        let d = |f: &FrequencyFit| (f.freq_hz.log10() - 3.0).abs();
        d(a).total_cmp(&d(b))
    })
}

/// Ranking table of one frequency.
pub fn ranking_table(f: &FrequencyFit) -> String {
    let rows: Vec<Vec<String>> = f
        .rules
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
        .collect();
    table(
        &[
            "rule",
            "εm",
            "εf (effective)",
            "n",
            "RMS %",
            "AICc",
            "Δ",
            "status",
        ],
        &rows,
    )
}

/// Write the composite report (`eps_r.svg`, `tan_delta.svg`, `mixing.svg`,
/// `index.md`) into `dir`; returns the page.
pub fn write_composite(fit: &CompositeFit, dir: &Path) -> Result<PathBuf> {
    freq_charts(&fit.samples, dir)?;
    let mut md = format!(
        "# {}\n\nMatrix: {} · filler: {}\n\n![εr](eps_r.svg)\n\n![tan δ](tan_delta.svg)\n",
        fit.name, fit.matrix.name, fit.filler.name
    );
    if let Some(rf) = reference_fit(fit) {
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
        Chart {
            title: format!(
                "εr against filler volume fraction at {} Hz",
                sig(rf.freq_hz, 4)
            ),
            x_label: "filler volume fraction φ".into(),
            y_label: "εr′".into(),
            series,
            log_x: false,
        }
        .write_svg(&dir.join("mixing.svg"))?;
        let _ = writeln!(
            md,
            "\n![mixing rules](mixing.svg)\n\n## Mixing rules at {} Hz\n\n```\n{}```",
            sig(rf.freq_hz, 4),
            ranking_table(rf)
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
        let _ = writeln!(
            md,
            "\n## Over {} frequencies\n\n```\n{}```",
            fit.fits.len(),
            table(
                &["rule", "best at", "median Δ", "εf effective", "unusable at"],
                &rows
            )
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
    let _ = writeln!(
        md,
        "\n## Fractions\n\n```\n{}```",
        table(&["sample", "as given", "volume", "weight"], &frows)
    );
    if !fit.claims.is_empty() {
        md.push_str("\n## Claims\n\n");
        for c in &fit.claims {
            let _ = writeln!(md, "- {}", c.verdict);
        }
    }
    for w in &fit.warnings {
        let _ = writeln!(md, "- warning: {w}");
    }
    samples_md(&fit.samples, &mut md);
    let page = dir.join("index.md");
    atomic_write(&page, md.as_bytes())?;
    Ok(page)
}
