//! The summary and report of `dea-fit dma`: the master curve (data coloured by
//! temperature), the shift factors with ±1.96σ bars and the fitted law, and the
//! shift table; the Prony fit's curves (fit, residuals, E(t) over the supported
//! window) join them once the Prony step is wired (`fit::prony_step`).

use super::fit::DmaFit;
use super::temperature::{celsius, CELSIUS_ZERO_K};
use super::DmaData;
use crate::error::Result;
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
    match &f.prony {
        Some(p) => s.push_str(&format!(
            "prony: E∞ {} Pa, {} terms\n",
            sig(p.e_inf, 4),
            p.terms.len()
        )),
        None => s.push_str("prony: not fitted\n"),
    }
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
    page.text(match &f.prony {
        Some(p) => format!("E∞ {} Pa, {} terms", sig(p.e_inf, 4), p.terms.len()),
        None => {
            "not fitted: this version of `dma` ends at the master curve (see the warnings)".into()
        }
    });
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
