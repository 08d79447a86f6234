//! Report of a simulation: trajectory charts (stroke and voltage, current and power)
//! and a Markdown summary; and the trajectory CSV.

use super::format::si;
use super::page::{code, strong, text, Page, Tone};
use super::plot::{band, Chart, Series, Style};
use super::runs::Run;
use crate::error::Result;
use crate::sim::derivatives::OutputSensitivity;
use crate::sim::sampling::Band;
use crate::sim::{Outcome, Row, Sensitivities};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn opt(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        v.to_string()
    }
}

/// One output's value in a row of [`OutputSensitivity`].
type Of = fn(&OutputSensitivity) -> f64;

/// The sensitivity outputs of a trajectory: the column of the quantity, its SI unit
/// (empty: dimensionless) and its value.
const SENSITIVITY_COLUMNS: [(&str, &str, Of); 4] = [
    ("stretch", "", |d| d.stretch),
    ("length", "m", |d| d.length),
    ("capacitance", "F", |d| d.capacitance),
    ("current", "A", |d| d.current),
];

/// The CSV header of ∂`quantity`/∂`param`: `d<quantity>_d_<name>` with the unit
/// `<quantity unit>_per_<parameter unit>`, from a parameter named as
/// [`Sensitivities::params`] does (`C10 (Pa)`, `nv (Pa s)`, `eps_r`):
/// `dlength_d_C10_m_per_Pa`, `dstretch_d_eps_r`.
fn sensitivity_header(quantity: &str, unit: &str, param: &str) -> String {
    let (name, p_unit) = match param.split_once(" (") {
        Some((n, u)) => (n, u.trim_end_matches(')').replace(' ', "_")),
        None => (param, String::new()),
    };
    let mut h = format!("d{quantity}_d_{name}");
    if !unit.is_empty() {
        h.push('_');
        h.push_str(unit);
    }
    if !p_unit.is_empty() {
        h.push_str("_per_");
        h.push_str(&p_unit);
    }
    h
}

/// Scaled sensitivity of a parameter: over the run, the largest |θj·∂λ/∂θj| (the
/// first-order change of the stretch for a 100 % change of θj) and of |θj·∂C/∂θj| (F).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ScaledSensitivity {
    /// Parameter name with unit.
    pub param: String,
    /// Its value (SI).
    pub value: f64,
    /// max over samples of |θj·∂λ/∂θj|.
    pub stretch: f64,
    /// max over samples of |θj·∂C/∂θj| (F).
    #[serde(rename = "capacitance_F")]
    pub capacitance_f: f64,
}

/// Scaled sensitivities of every parameter (over every sample, kept or not),
/// largest stretch effect first.
pub fn scaled_sensitivities(se: &Sensitivities) -> Vec<ScaledSensitivity> {
    let mut v: Vec<ScaledSensitivity> = (0..se.params.len())
        .map(|j| ScaledSensitivity {
            param: se.params[j].clone(),
            value: se.theta[j],
            stretch: se.peak_stretch[j],
            capacitance_f: se.peak_capacitance[j],
        })
        .collect();
    v.sort_by(|a, b| b.stretch.total_cmp(&a.stretch));
    v
}

/// The trajectory CSV, written row by row as a run reaches its samples (SI units
/// in the header, written with the first row); with sensitivities, for each of
/// stretch, length, capacitance and current the derivative of that output to every
/// parameter (per SI unit of the parameter; headers by [`sensitivity_header`], e.g.
/// `dcurrent_d_eps_r_A`, `dlength_d_C10_m_per_Pa`), empty at a pull-in sample.
pub struct TrajectoryCsv<W: std::io::Write> {
    out: W,
    line: String,
    started: bool,
}

impl<W: std::io::Write> TrajectoryCsv<W> {
    /// A CSV into `out`.
    pub fn new(out: W) -> Self {
        TrajectoryCsv {
            out,
            line: String::new(),
            started: false,
        }
    }

    /// Write one sample (the header first).
    pub fn row(&mut self, r: &Row) -> std::io::Result<()> {
        let s = &mut self.line;
        s.clear();
        if !self.started {
            self.started = true;
            s.push_str("time_s,input_V,voltage_V,stretch,length_m,stroke_m,capacitance_F,current_A,power_W,leakage_power_W,alpha_rad,reference,sensed_contraction");
            if let Some((params, _)) = r.sensitivities {
                for (quantity, unit, _) in SENSITIVITY_COLUMNS {
                    for p in params {
                        let _ = write!(s, ",{}", sensitivity_header(quantity, unit, p));
                    }
                }
            }
            s.push('\n');
        }
        let x = r.sample;
        let _ = write!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            x.time_s,
            x.input_v,
            x.voltage_v,
            x.stretch,
            x.length_m,
            r.rest_length_m - x.length_m,
            x.capacitance_f,
            x.current_a,
            x.power_w,
            x.leakage_w,
            opt(x.alpha_rad),
            opt(x.reference),
            x.sensed_contraction
        );
        if let Some((_, row)) = r.sensitivities {
            for (_, _, of) in SENSITIVITY_COLUMNS {
                for d in row {
                    let _ = write!(s, ",{}", opt(of(d)));
                }
            }
        }
        s.push('\n');
        self.out.write_all(s.as_bytes())
    }

    /// The writer, after the last row.
    pub fn into_inner(self) -> W {
        self.out
    }
}

/// A sampled quantity as a chart series: the line through the samples, or, when the
/// samples do not resolve the motion ([`Outcome::envelope`]), the band of its min/max
/// per output interval. `f` maps a value to the chart's unit; `band_of` picks the
/// quantity's band.
fn trace(
    o: &Outcome,
    label: &str,
    color: usize,
    value: &dyn Fn(&crate::sim::Sample) -> f64,
    band_of: &dyn Fn(&crate::sim::sampling::Interval) -> Band,
    f: &dyn Fn(f64) -> f64,
) -> Series {
    match &o.envelope {
        Some(env) => {
            let x: Vec<f64> = o.samples.iter().map(|s| s.time_s).collect();
            let (lo, hi): (Vec<f64>, Vec<f64>) = env
                .iter()
                .map(|i| {
                    let b = band_of(i);
                    let (a, b) = (f(b.lo), f(b.hi));
                    (a.min(b), a.max(b))
                })
                .unzip();
            Series {
                label: match o.decimation {
                    1 => {
                        format!("{label}: min/max per output interval (samples alias the ringing)")
                    }
                    k => format!("{label}: min/max per {k} output intervals"),
                },
                points: band(&x, &lo, &hi),
                color,
                style: Style::Band,
            }
        }
        None => Series {
            label: label.into(),
            points: o.samples.iter().map(|s| (s.time_s, f(value(s)))).collect(),
            color,
            style: Style::Line,
        },
    }
}

/// Write `stroke.svg`, `voltage.svg`, `power.svg` (and `sensitivities.svg`) and the
/// page (`index.md`, `index.html`, `run.json`) into `dir`; `input` names the scene
/// file. Returns the HTML page.
/// `status` is the command's (the run's, or `breakdown`); `check` the largest
/// field against breakdown.
pub fn write(
    o: &Outcome,
    input: &str,
    dir: &Path,
    status: &str,
    check: &crate::sim::breakdown::Check,
) -> Result<PathBuf> {
    let pts = |f: &dyn Fn(&crate::sim::Sample) -> f64| -> Vec<(f64, f64)> {
        o.samples.iter().map(|s| (s.time_s, f(s))).collect()
    };
    let mut stroke_series = vec![trace(
        o,
        "stroke",
        0,
        &|s| s.length_m,
        &|i| i.length_m,
        &|l| o.rest_length_m - l,
    )];
    // A closed loop's reference contraction, on the same axis as the stroke.
    if o.samples.iter().any(|s| s.reference.is_finite()) {
        stroke_series.push(Series {
            label: "reference (controller)".into(),
            points: pts(&|s| s.reference * o.rest_length_m),
            color: 1,
            style: Style::Dashed,
        });
    }
    let stroke = Chart {
        title: format!("{}: stroke", o.scene),
        x_label: "time (s)".into(),
        y_label: "contraction".into(),
        series: stroke_series,
        log_x: false,
        x_unit: None,
        y_unit: Some("m".into()),
    };
    let voltage = Chart {
        title: format!("{}: voltage", o.scene),
        x_label: "time (s)".into(),
        y_label: "voltage".into(),
        series: vec![
            Series {
                label: "terminal".into(),
                points: pts(&|s| s.voltage_v),
                color: 1,
                style: Style::Line,
            },
            Series {
                label: "input".into(),
                points: pts(&|s| s.input_v),
                color: 2,
                style: Style::Dashed,
            },
        ],
        log_x: false,
        x_unit: None,
        y_unit: Some("V".into()),
    };
    let power = Chart {
        title: format!("{}: power", o.scene),
        x_label: "time (s)".into(),
        y_label: "power".into(),
        series: vec![
            trace(o, "total V·I", 3, &|s| s.power_w, &|i| i.power_w, &|p| p),
            Series {
                label: "leakage".into(),
                points: pts(&|s| s.leakage_w),
                color: 4,
                style: Style::Dashed,
            },
        ],
        log_x: false,
        x_unit: None,
        y_unit: Some("W".into()),
    };
    let x = o.extremes();
    let mut page = Page::new(format!("Simulation: {}", o.scene));
    page.para(vec![text("Scene: "), code(input)]);
    page.status_line(status, Tone::of(status));
    let mut facts = vec![vec![
        text("fidelity: "),
        strong(o.fidelity.model.to_string()),
        text(format!(" — {}", o.fidelity.reason)),
    ]];
    for a in &o.fidelity.arms {
        facts.push(vec![text(a.to_string())]);
    }
    facts.push(vec![text(format!(
        "axial mode: {}, ζ = {:.3e}, Q = {:.3e}",
        si(o.mode.frequency_hz, "Hz"),
        o.mode.damping_ratio,
        o.mode.q_factor
    ))]);
    let i = &o.integrator;
    facts.push(vec![text(format!(
        "integrator: {} (rtol {:.0e}; {}): {} steps, {} rejected, {} restarts, {} f-evals — {}",
        i.method,
        i.rtol,
        i.reason,
        i.stats.steps,
        i.stats.rejected,
        i.stats.restarts,
        i.stats.rhs_evals,
        i.message
    ))]);
    facts.push(vec![text(format!(
        "over every accepted step of the integration: stretch {:.6} … {:.6} (rest {:.6}); max stroke {}, max current {}, max power {} (leakage up to {})",
        x.stretch_min,
        x.stretch_max,
        o.rest_stretch,
        si(x.stroke_max_m, "m"),
        si(x.current_max_a, "A"),
        si(x.power_max_w, "W"),
        si(x.leakage_max_w, "W")
    ))]);
    facts.push(vec![text(check.message.clone())]);
    for n in &check.notes {
        facts.push(vec![text(format!("breakdown strength: {n}"))]);
    }
    for e in &o.events {
        facts.push(vec![
            strong(e.kind.to_string()),
            text(format!(
                " at t = {:.6} s, V = {}, λ = {:.5}",
                e.time_s,
                si(e.voltage_v, "V"),
                e.stretch
            )),
        ]);
    }
    let en = &o.energy;
    facts.push(vec![text(format!(
        "energy: in {} = field {} + elastic {} + arms {} + kinetic {} + load {} + viscous {} + leakage {} + source {} (residual {})",
        si(en.input_j, "J"), si(en.field_j, "J"), si(en.elastic_j, "J"), si(en.arms_j, "J"),
        si(en.kinetic_j, "J"), si(en.load_j, "J"), si(en.viscous_j, "J"), si(en.leakage_j, "J"),
        si(en.source_j, "J"), si(en.residual_j, "J")
    ))]);
    if o.decimation > 1 {
        facts.push(vec![text(format!(
            "charts: one sample in {} of the {} (the trajectory CSV holds them all), stroke and power as their min/max over the samples in between",
            o.decimation, o.sample_count
        ))]);
    }
    if let Some(r) = o.tracking_rmse_pct {
        facts.push(vec![text(format!("tracking %RMSE (Eq. 3.28): {r:.2} %"))]);
    }
    page.list(facts);
    page.warnings(&o.warnings);
    page.chart(dir, "stroke.svg", "stroke", &stroke)?;
    page.chart(dir, "voltage.svg", "voltage", &voltage)?;
    page.chart(dir, "power.svg", "power", &power)?;
    if let Some(se) = &o.sensitivities {
        page.heading("Sensitivities");
        page.text("Largest first-order change over the run for a 100 % change of each parameter (θ·∂/∂θ):");
        page.table(
            &["parameter", "value", "stretch", "capacitance"],
            scaled_sensitivities(se)
                .into_iter()
                .map(|r| {
                    vec![
                        r.param,
                        format!("{:.4e}", r.value),
                        format!("{:.3e}", r.stretch),
                        si(r.capacitance_f, "F"),
                    ]
                })
                .collect(),
        );
        let chart = Chart {
            title: format!("{}: stretch sensitivities θ·∂λ/∂θ", o.scene),
            x_label: "time (s)".into(),
            y_label: "θ·∂λ/∂θ".into(),
            series: (0..se.params.len())
                .map(|j| Series {
                    label: se.params[j].clone(),
                    points: o
                        .samples
                        .iter()
                        .zip(se.stretch.iter())
                        .filter(|(_, r)| r[j].is_finite())
                        .map(|(s, r)| (s.time_s, se.theta[j] * r[j]))
                        .collect(),
                    color: j,
                    style: Style::Line,
                })
                .collect(),
            log_x: false,
            x_unit: None,
            y_unit: None,
        };
        page.chart(dir, "sensitivities.svg", "sensitivities", &chart)?;
    }
    let run = Run::new("simulate", input, o.fidelity.model.to_string()).headline(vec![
        format!("max stroke {}", si(x.stroke_max_m, "m")),
        format!("max power {}", si(x.power_max_w, "W")),
        format!("{} event(s)", o.events.len()),
        match check.margin {
            Some(m) => format!("breakdown margin {:.0} %", 100.0 * m),
            None => "breakdown not checked".into(),
        },
    ]);
    page.write(dir, "index", run)
}
