//! The summary and report of `dea-fit dma`: the master curve (data coloured by
//! temperature), the shift factors with ±1.96σ bars and the fitted law, and the
//! shift table; the Prony series fitted to the master curve (its E′ and E″ over
//! the master curve, its terms with σ, identifiability and support), its residuals
//! against reduced frequency, and the relaxation modulus E(t) and creep compliance
//! J(t) it gives, drawn a decade beyond the τ range the master curve supports with
//! that range shaded.

use super::fit::DmaFit;
use super::temperature::{celsius, CELSIUS_ZERO_K};
use super::DmaData;
use crate::error::Result;
use crate::fit::prony::interconvert;
use crate::report::format::{sig, table, wrap};
use crate::report::page::{Page, Tone};
use crate::report::plot::{error_bars, Chart, Series, Style};
use crate::report::runs::Run;
use std::path::{Path, PathBuf};

/// The shift table's rows: T, log aT ± σ, and the law's value and misfit.
fn rows(f: &DmaFit) -> Vec<Vec<String>> {
    f.shift_factors
        .iter()
        .map(|s| {
            let mut r = vec![
                celsius(s.temperature_k),
                format!("{:+.3}", s.log10_at),
                format!("{:.3}", s.std_error),
            ];
            if let (Some(l), Some(d)) = (s.law_log10_at, s.law_residual_decades) {
                r.push(format!("{l:+.3}"));
                r.push(format!("{d:+.3}"));
            }
            if let Some(b) = s.log10_bt {
                r.push(format!("{b:+.4}"));
            }
            r
        })
        .collect()
}

fn header(f: &DmaFit) -> Vec<&'static str> {
    let mut h = vec!["T", "log10 aT", "σ"];
    if f.shift_model.is_some() {
        h.extend(["law log10 aT", "free − law"]);
    }
    if f.vertical_shift {
        h.push("log10 bT");
    }
    h
}

/// The law in one line: constants ± σ and how well it fits the free shifts.
fn law_line(f: &DmaFit) -> Option<String> {
    let m = f.shift_model.as_ref()?;
    let consts = match (m.law.c1, m.law.c2, m.law.activation_energy) {
        (Some(c1), Some(c2), _) => format!(
            "C1 = {} ± {}, C2 = {} ± {} K",
            sig(c1, 4),
            sig(m.c1_std_error.unwrap_or(f64::NAN), 2),
            sig(c2, 4),
            sig(m.c2_std_error.unwrap_or(f64::NAN), 2)
        ),
        (_, _, Some(ea)) => format!(
            "Ea = {} ± {} kJ/mol",
            sig(ea / 1e3, 4),
            sig(m.activation_energy_std_error.unwrap_or(f64::NAN) / 1e3, 2)
        ),
        _ => String::new(),
    };
    Some(format!(
        "{}: {consts}; misfit to the free shifts {:.3} decades rms, {:.3} max (χ² {:.1} for {} degrees of freedom)",
        m.law.kind.label(),
        m.rms_decades,
        m.max_decades,
        m.chi2,
        m.dof
    ))
}

/// The terminal summary.
pub fn summary(f: &DmaFit) -> String {
    let mut s = String::new();
    let points = f.master_curve.len();
    match f.reference_temperature_k {
        Some(t) if !f.shift_factors.is_empty() => s.push_str(&format!(
            "dma: {} isotherms ({} … {}), {points} points, reference {}; shifts on {}{}\n",
            f.shift_factors.len(),
            celsius(f.shift_factors[0].temperature_k),
            celsius(f.shift_factors[f.shift_factors.len() - 1].temperature_k),
            celsius(t),
            f.shift_on.name(),
            if f.vertical_shift {
                " (+ vertical)"
            } else {
                ""
            }
        )),
        _ => s.push_str(&format!(
            "dma: a master curve of {points} points (no shifts)\n"
        )),
    }
    s.push_str(&format!("status: {}\n", f.status));
    if !f.shift_factors.is_empty() {
        s.push_str(&format!(
            "shift factors (free, ± standard error; master curve built with: {}):\n",
            f.shift
        ));
        s.push_str(&table(&header(f), &rows(f)));
    }
    if let Some(l) = law_line(f) {
        for l in wrap(&l, 100) {
            s.push_str(&l);
            s.push('\n');
        }
    }
    let [lo, hi] = f.reduced_omega_range_rad_s;
    s.push_str(&format!(
        "master curve: reduced ω {} … {} rad/s ({:.1} decades)\n",
        sig(lo, 3),
        sig(hi, 3),
        (hi / lo).log10()
    ));
    s.push_str(&prony_line(f));
    s.push('\n');
    if !f.warnings.is_empty() {
        s.push_str("warnings:\n");
        for w in &f.warnings {
            for (i, l) in wrap(w, 96).iter().enumerate() {
                s.push_str(if i == 0 { "  - " } else { "    " });
                s.push_str(l);
                s.push('\n');
            }
        }
    }
    s
}

/// The master curve chart: log E′ and log E″ against reduced ω, one colour per isotherm.
/// The Prony series in one line: E∞, the terms, the τ range the master curve
/// supports, the fit's relative RMS of E′ and E″.
fn prony_line(f: &DmaFit) -> String {
    let p = &f.prony;
    let [a, b] = p.fit.supported_tau_s;
    format!(
        "prony: E∞ {} Pa, {} terms (τ supported {} … {} s); rms E′ {:.2} %, E″ {:.2} % of |E*|",
        sig(p.e_inf, 4),
        p.terms.len(),
        sig(a, 3),
        sig(b, 3),
        100.0 * p.fit.rel_rmse_storage,
        100.0 * p.fit.rel_rmse_loss
    )
}

/// The Prony terms with their σ, identifiability and support.
fn prony_rows(f: &DmaFit) -> Vec<Vec<String>> {
    let opt = |v: Option<f64>| v.map_or_else(|| "—".to_string(), |v| sig(v, 3));
    f.prony
        .fit
        .terms
        .iter()
        .enumerate()
        .map(|(i, t)| {
            vec![
                (i + 1).to_string(),
                sig(t.modulus_pa, 4),
                opt(t.modulus_std_pa),
                sig(t.tau_s, 4),
                opt(t.tau_std_s),
                t.identifiable.to_string(),
                t.supported.to_string(),
            ]
        })
        .collect()
}

/// E′ and E″ of the fitted Prony series on 200 reduced frequencies over the
/// master curve's range (log10 Pa); empty when the series cannot be built.
fn prony_curves(f: &DmaFit) -> [Vec<(f64, f64)>; 2] {
    let Ok(prony) = f.prony.fit.prony() else {
        return [Vec::new(), Vec::new()];
    };
    let [lo, hi] = f.reduced_omega_range_rad_s;
    let n = 200;
    let omega: Vec<f64> = (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect();
    let e = interconvert::complex_modulus(&prony, &omega);
    let curve = |k: usize| -> Vec<(f64, f64)> {
        omega
            .iter()
            .zip(&e)
            .map(|(&w, v)| (w, [v.0, v.1][k]))
            .filter(|p| p.1 > 0.0)
            .map(|(w, v)| (w, v.log10()))
            .collect()
    };
    [curve(0), curve(1)]
}

fn master_chart(f: &DmaFit, data: &DmaData) -> Chart {
    let mut series = Vec::new();
    for (j, iso) in data.isotherms.iter().enumerate() {
        let label = iso
            .temperature_k
            .map_or_else(|| "master curve".to_string(), celsius);
        let pts = |loss: bool| -> Vec<(f64, f64)> {
            f.master_curve
                .iter()
                .filter(|p| p.temperature_k == iso.temperature_k)
                .map(|p| {
                    (
                        p.reduced_omega_rad_s,
                        if loss { p.loss_pa } else { p.storage_pa }.log10(),
                    )
                })
                .collect()
        };
        series.push(Series {
            label: format!("E′ {label}"),
            points: pts(false),
            color: j,
            style: Style::Points,
        });
        series.push(Series {
            label: format!("E″ {label}"),
            points: pts(true),
            color: j,
            style: Style::OpenPoints,
        });
    }
    let [storage, loss] = prony_curves(f);
    let colors = data.isotherms.len();
    series.push(Series {
        label: "E′ Prony fit".into(),
        points: storage,
        color: colors,
        style: Style::Line,
    });
    series.push(Series {
        label: "E″ Prony fit".into(),
        points: loss,
        color: colors,
        style: Style::Dashed,
    });
    Chart {
        title: match f.reference_temperature_k {
            Some(t) => format!("master curve at {} (E′ filled, E″ open)", celsius(t)),
            None => "master curve (E′ filled, E″ open)".into(),
        },
        x_label: "reduced angular frequency aT·ω (rad/s)".into(),
        y_label: "log10 modulus (Pa)".into(),
        series,
        log_x: true,
        x_unit: None,
        y_unit: None,
    }
}

/// The Prony fit's relative residuals at every master-curve point: E′ against E′,
/// E″ against |E*| (the fit's own weighting, [`crate::fit::prony::frequency`]), in %.
fn residual_chart(f: &DmaFit) -> Chart {
    let prony = f.prony.fit.prony().ok();
    let residuals = |loss: bool| -> Vec<(f64, f64)> {
        let Some(prony) = &prony else {
            return Vec::new();
        };
        f.master_curve
            .iter()
            .map(|p| {
                let (s, l) = prony.storage_loss(p.reduced_omega_rad_s);
                let r = match loss {
                    false => (s - p.storage_pa) / p.storage_pa,
                    true => (l - p.loss_pa) / p.storage_pa.hypot(p.loss_pa),
                };
                (p.reduced_omega_rad_s, 100.0 * r)
            })
            .collect()
    };
    Chart {
        title: "residuals of the Prony fit".into(),
        x_label: "reduced angular frequency aT·ω (rad/s)".into(),
        y_label: "fit − data (%)".into(),
        series: vec![
            Series {
                label: "E′ (of E′)".into(),
                points: residuals(false),
                color: 0,
                style: Style::Points,
            },
            Series {
                label: "E″ (of |E*|)".into(),
                points: residuals(true),
                color: 1,
                style: Style::OpenPoints,
            },
        ],
        log_x: true,
        x_unit: None,
        y_unit: None,
    }
}

/// E(t) and J(t) of the Prony series (log10, Pa and 1/Pa) on 200 times from a
/// decade below to a decade above the τ range the master curve supports, that range
/// shaded: beyond it the curves are the series' extrapolation, not the data's.
fn time_chart(f: &DmaFit) -> Chart {
    let [a, b] = f.prony.fit.supported_tau_s;
    let (lo, hi) = (a / 10.0, b * 10.0);
    let n = 200;
    let times: Vec<f64> = (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect();
    let (modulus, compliance) = match f.prony.fit.prony() {
        Ok(p) => (
            interconvert::relaxation_modulus(&p, &times),
            interconvert::creep_compliance(&p, &times),
        ),
        Err(_) => (Vec::new(), Vec::new()),
    };
    let curve = |v: &[f64], invert: bool| -> Vec<(f64, f64)> {
        times
            .iter()
            .zip(v)
            .filter(|p| *p.1 > 0.0)
            .map(|(&t, &v)| (t, if invert { -v.log10() } else { v.log10() }))
            .collect()
    };
    Chart {
        title: "relaxation modulus and creep compliance at the reference temperature".into(),
        x_label: "time t (s)".into(),
        y_label: "log10 E(t) (Pa), log10 1/J(t) (Pa)".into(),
        series: vec![
            Series {
                label: "τ range the master curve supports".into(),
                points: vec![(a, 0.0), (b, 0.0)],
                color: 2,
                style: Style::Span,
            },
            Series {
                label: "E(t)".into(),
                points: curve(&modulus, false),
                color: 0,
                style: Style::Line,
            },
            Series {
                label: "1/J(t) (creep compliance, inverted)".into(),
                points: curve(&compliance, true),
                color: 1,
                style: Style::Dashed,
            },
        ],
        log_x: true,
        x_unit: None,
        y_unit: None,
    }
}

/// The shift factors with ±1.96σ bars, and the law over the isotherms' range.
fn shift_chart(f: &DmaFit) -> Chart {
    let c = |k: f64| k - CELSIUS_ZERO_K;
    let mut series = vec![
        Series {
            label: "free shifts".into(),
            points: f
                .shift_factors
                .iter()
                .map(|s| (c(s.temperature_k), s.log10_at))
                .collect(),
            color: 0,
            style: Style::Points,
        },
        Series {
            label: "± 1.96σ".into(),
            points: error_bars(
                f.shift_factors
                    .iter()
                    .map(|s| (c(s.temperature_k), s.log10_at, 1.96 * s.std_error)),
            ),
            color: 0,
            style: Style::ErrorBars,
        },
    ];
    if let Some(m) = &f.shift_model {
        let (t0, t1) = (
            f.shift_factors[0].temperature_k,
            f.shift_factors[f.shift_factors.len() - 1].temperature_k,
        );
        // the law, offset by the mean misfit as its residuals are
        let offset = f
            .shift_factors
            .iter()
            .map(|s| s.log10_at - m.law.log_at(s.temperature_k))
            .sum::<f64>()
            / f.shift_factors.len() as f64;
        series.push(Series {
            label: format!("{} fitted to the free shifts", m.law.kind.label()),
            points: (0..=100)
                .map(|i| t0 + (t1 - t0) * i as f64 / 100.0)
                .map(|t| (c(t), m.law.log_at(t) + offset))
                .filter(|p| p.1.is_finite())
                .collect(),
            color: 1,
            style: Style::Line,
        });
    }
    Chart {
        title: "shift factors".into(),
        x_label: "temperature (°C)".into(),
        y_label: "log10 aT".into(),
        series,
        log_x: false,
        x_unit: None,
        y_unit: None,
    }
}

/// Write the charts and the page (`index.md`, `index.html`, `run.json`) into `dir`;
/// returns the HTML page.
pub fn write(f: &DmaFit, data: &DmaData, dir: &Path) -> Result<PathBuf> {
    let mut page = Page::new("DMA master curve");
    page.status_line(f.status, Tone::of(&f.status.to_string()));
    page.warnings(&f.warnings);
    page.chart(
        dir,
        "master.svg",
        "master curve coloured by temperature",
        &master_chart(f, data),
    )?;
    if !f.shift_factors.is_empty() {
        page.heading("Shift factors");
        page.chart(
            dir,
            "shifts.svg",
            "shift factors with ±1.96σ and the law",
            &shift_chart(f),
        )?;
        if let Some(l) = law_line(f) {
            page.text(l);
        }
        page.table(&header(f), rows(f));
    }
    page.heading("Prony series");
    page.text(prony_line(f));
    page.chart(
        dir,
        "residuals.svg",
        "relative residuals of the Prony fit",
        &residual_chart(f),
    )?;
    page.chart(
        dir,
        "time.svg",
        "E(t) and J(t) over the supported τ range",
        &time_chart(f),
    )?;
    page.table(
        &[
            "term",
            "E (Pa)",
            "σ(E) (Pa)",
            "τ (s)",
            "σ(τ) (s)",
            "identifiable",
            "τ supported",
        ],
        prony_rows(f),
    );
    let files: Vec<String> = f.files.iter().map(|s| s.path.clone()).collect();
    let mut headline = vec![format!("{} isotherms", f.shift_factors.len())];
    if let Some(m) = &f.shift_model {
        headline.push(format!(
            "{} rms {:.3} decades",
            m.law.kind.label(),
            m.rms_decades
        ));
    }
    let run = Run::new(
        "dma",
        files.join(", "),
        format!("shifts {} on {}", f.shift, f.shift_on.name()),
    )
    .headline(headline);
    page.write(dir, "index", run)
}
