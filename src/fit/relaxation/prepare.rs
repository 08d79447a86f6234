//! The time domain's data made ready for the Prony core: the loading history, the
//! hereditary input (strain, or the hyperelastic stress of QLV), the residual
//! weights and the window of τ the curve supports.

use super::{Loading, QlvInfo, QlvInput, Settings};
use crate::error::{Error, Result};
use crate::fit::problem::{Residual, REL_FLOOR};
use crate::fit::prony::problem::Problem;
use crate::fit::prony::{fmt_s, Kernels, Setup};
use crate::io::relaxation::RelaxationData;
use crate::material::hyperelastic::Mode;
use crate::material::viscoelastic::{Formulation, History, KernelCarry, Schedule};

/// Most decades of time the τ search spans, counted back from the last sample: a
/// relaxation record covers 3–8 decades (a 1 ms rig to a day); a first time of
/// 1e-300 s would put 300 decades of columns in the NNLS grid and stall the fit.
const MAX_DECADES: i32 = 12;

/// The rows of a relaxation curve: the loading x(tₖ) and the hereditary states
/// hₖ(τ) = ∫ e^(−(tₖ−s)/τ) dx(s) ([`Schedule::kernels`]), with the loading kept to
/// build subsamples (the schedule holds the times).
#[derive(Debug, Clone)]
pub struct TimeKernels {
    /// The loading merged with the times.
    pub sched: Schedule,
    history: History,
}

impl Kernels for TimeKernels {
    const WINDOW: &'static str = "the sampled time window";

    fn len(&self) -> usize {
        self.sched.len()
    }
    fn input(&self) -> &[f64] {
        self.sched.input()
    }
    type Carry = KernelCarry;

    fn kernel_rows(
        &self,
        taus: &[f64],
        rows: std::ops::Range<usize>,
        carry: &mut KernelCarry,
        h: &mut [f64],
        dh: Option<&mut [f64]>,
    ) {
        self.sched.kernel_rows(taus, rows, carry, h, dh);
    }
    fn subsample(&self, idx: &[usize]) -> Option<TimeKernels> {
        let times: Vec<f64> = idx.iter().map(|&i| self.sched.times()[i]).collect();
        let sched = Schedule::new(&self.history, &times).ok()?;
        Some(TimeKernels {
            sched,
            history: self.history.clone(),
        })
    }
    fn outside_window(name: &str, short: bool, window: (f64, f64)) -> String {
        match short {
            true => format!(
                "{name} is shorter than the first sample ({}): this relaxation is over before the data see it, so its τ and modulus are not determined separately",
                fmt_s(window.0)
            ),
            false => format!(
                "{name} is longer than the test ({}): the data show only the start of this relaxation, so its τ, its modulus and E∞ are not determined separately",
                fmt_s(window.1)
            ),
        }
    }
}

/// Everything the estimator derives from data and loading before fitting.
pub(super) struct Prepared {
    /// The Prony core's problem, window and bounds.
    pub setup: Setup<TimeKernels>,
    pub formulation: Formulation,
    pub held_strain: f64,
    pub loading: String,
    /// The residuals used (the settings' or the loading's choice).
    pub residual: Residual,
    pub qlv: Option<QlvInfo>,
    pub notes: Vec<String>,
}

/// Whether a recorded strain history unloads: after its peak |strain| it falls below
/// 90 % of it. A relaxation test holds its strain (within the machine's control
/// error of a few %); a load-unload cycle, a recovery or a second cycle returns
/// towards zero, and its stress with it.
pub fn unloads(strain: &[f64]) -> bool {
    let peak = strain.iter().map(|e| e.abs()).fold(0.0, f64::max);
    // From the first time the peak is reached.
    let first = strain.iter().position(|e| e.abs() == peak).unwrap_or(0);
    strain[first..].iter().any(|e| e.abs() < 0.9 * peak)
}

/// The residual weights wₖ: 1/max(|yₖ|, floor) (relative) or 1/max|y| (absolute).
fn weights(y: &[f64], residual: Residual) -> Vec<f64> {
    let ymax = y.iter().map(|v| v.abs()).fold(0.0, f64::max);
    y.iter()
        .map(|v| match residual {
            Residual::Rel => 1.0 / v.abs().max(REL_FLOOR * ymax),
            Residual::Abs => 1.0 / ymax,
        })
        .collect()
}

pub(super) fn prepare(
    data: &RelaxationData,
    loading: &Loading,
    qlv: Option<&QlvInput>,
    settings: &Settings,
) -> Result<Prepared> {
    data.check()?;
    let n = data.time.len();
    if n < 3 {
        return Err(Error::settings(format!(
            "{n} points cannot determine even a long-term modulus with an uncertainty"
        ))
        .with_hint("a relaxation curve needs at least 3 points, and 2N + 3 for N terms"));
    }
    let mut notes = Vec::new();
    let (strain_hist, held, peak, desc, unloading) = strain_history(data, loading, &mut notes)?;
    if !(peak.is_finite() && peak != 0.0 && peak > -1.0) {
        return Err(Error::settings(format!(
            "the held (or peak) strain must be non-zero and > −1, found {peak}"
        )));
    }
    let residual = residual_choice(settings, unloading, &mut notes);
    let (history, formulation, unit, qlv_info) =
        hereditary_input(data, loading, qlv, strain_hist, (held, peak), &mut notes)?;
    let sched = Schedule::new(&history, &data.time)?;
    let y = data.stress.clone();
    let ymax = y.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let xmax = sched.input().iter().map(|v| v.abs()).fold(0.0, f64::max);
    if xmax.is_nan() || xmax <= 0.0 {
        return Err(Error::settings(
            "the loading is zero at every data point: nothing relaxes",
        ));
    }
    let w = weights(&y, residual);
    let t_pos = data
        .time
        .iter()
        .copied()
        .find(|&t| t > 0.0)
        .expect("times increase from ≥ 0 and n ≥ 3");
    let t_end = data.time[n - 1];
    let window = (t_pos.max(t_end * 10f64.powi(-MAX_DECADES)), t_end);
    if window.0 > t_pos {
        notes.push(format!(
            "the data span more than {MAX_DECADES} decades of time (first positive time {} after a last of {}): relaxation times are searched over the last {MAX_DECADES} decades only",
            fmt_s(t_pos),
            fmt_s(t_end)
        ));
    }
    let kern = TimeKernels { sched, history };
    Ok(Prepared {
        setup: Setup::new(Problem::new(kern, y, w, ymax / xmax), window, unit),
        formulation,
        held_strain: held,
        loading: desc,
        residual,
        qlv: qlv_info,
        notes,
    })
}

/// The loading history of the data, recorded, ramp or step: (history, held strain,
/// peak strain (largest |strain|), description, whether it unloads).
fn strain_history(
    data: &RelaxationData,
    loading: &Loading,
    notes: &mut Vec<String>,
) -> Result<(History, f64, f64, String, bool)> {
    let n = data.time.len();
    Ok(match (&data.strain, loading.ramp_time) {
        (Some(_), Some(_)) => {
            return Err(Error::settings(
                "the file records the strain history; --ramp-time would contradict it",
            )
            .with_hint(
                "drop --ramp-time (the recorded strain is used), or drop the strain column",
            ))
        }
        (Some(eps), None) => {
            let held = *eps.last().expect("non-empty");
            let ip = (0..n)
                .max_by(|&i, &j| eps[i].abs().total_cmp(&eps[j].abs()))
                .expect("non-empty");
            let peak = eps[ip];
            let unloading = unloads(eps);
            if let Some(s) = loading.strain {
                let (what, v) = if unloading {
                    ("peaks", peak)
                } else {
                    ("ends", held)
                };
                if (s - v).abs() > 0.01 * v.abs().max(1e-12) {
                    return Err(Error::settings(format!(
                        "the held strain is given as {s} but the file's strain column {what} at {v:.6}"
                    ))
                    .with_hint("drop --strain/--stretch (the recorded strain is used) or correct it"));
                }
            }
            if eps[0] != 0.0 && data.time[0] > 0.0 {
                notes.push(format!(
                    "the recorded strain is already {} at the first sample (t = {}): the loading before it is taken as a step at that time; start the file at t = 0 to fit the true history",
                    eps[0],
                    fmt_s(data.time[0])
                ));
            }
            let knots: Vec<(f64, f64)> =
                data.time.iter().copied().zip(eps.iter().copied()).collect();
            let desc = if unloading {
                format!(
                    "recorded history (piecewise linear between samples), peak stretch {:.4} at t = {}, unloaded to stretch {:.4}",
                    1.0 + peak,
                    fmt_s(data.time[ip]),
                    1.0 + held
                )
            } else {
                format!(
                    "recorded history (piecewise linear between samples), held at strain {held:.6} (stretch {:.4})",
                    1.0 + held
                )
            };
            (History::from_knots(knots)?, held, peak, desc, unloading)
        }
        (None, ramp) => {
            let Some(s) = loading.strain else {
                return Err(Error::settings("the held strain is needed").with_hint(
                    "pass --strain 0.5 or --stretch 1.5, or add a strain column to the file",
                ));
            };
            match ramp {
                Some(tr) => {
                    if !(tr > 0.0 && tr.is_finite()) {
                        return Err(Error::settings(format!(
                            "--ramp-time must be > 0, found {tr}"
                        )));
                    }
                    if tr >= data.time[n - 1] {
                        return Err(Error::settings(format!(
                            "the ramp ({tr} s) does not end before the last point ({} s): there is no hold to fit",
                            data.time[n - 1]
                        )));
                    }
                    (
                        History::ramp(s, tr),
                        s,
                        s,
                        format!("linear ramp to strain {s} over {tr} s from t = 0, then held"),
                        false,
                    )
                }
                None => (
                    History::step(s),
                    s,
                    s,
                    format!("ideal step to strain {s} at t = 0"),
                    false,
                ),
            }
        }
    })
}

/// The residuals: the settings' (said when relative on a history that unloads) or
/// the loading's choice.
fn residual_choice(settings: &Settings, unloading: bool, notes: &mut Vec<String>) -> Residual {
    match settings.residual {
        Some(r) => {
            if r == Residual::Rel && unloading {
                notes.push(
                    "relative residuals on a history that unloads: its stress passes through zero, where 1/|σ| (floored at 1 % of the peak) weights the slack end of the cycle 100 × its peak; drop --residual (absolute residuals are the automatic choice here)".into(),
                );
            }
            r
        }
        None if unloading => Residual::Abs,
        None => Residual::Rel,
    }
}

/// The input of the hereditary integral: the strain (small-strain reading) or the
/// hyperelastic stress σₑ(λ(s)) (QLV), with the formulation, the moduli unit and the
/// QLV details.
fn hereditary_input(
    data: &RelaxationData,
    loading: &Loading,
    qlv: Option<&QlvInput>,
    strain_hist: History,
    (held, peak): (f64, f64),
    notes: &mut Vec<String>,
) -> Result<(History, Formulation, f64, Option<QlvInfo>)> {
    Ok(match qlv {
        None => (strain_hist, Formulation::Parallel, 1.0, None),
        Some(q) => {
            let model = q.fit.evaluator()?;
            let p = &q.fit.params;
            let se = |e: f64| model.nominal_stress(p, Mode::Uniaxial, 1.0 + e);
            if let Some(w) = q.fit.range_warning(Mode::Uniaxial, 1.0 + peak) {
                notes.push(format!("hyperelastic fit: {w}"));
            }
            // A ramp in strain is not a ramp in σₑ: resolve it in 64 linear pieces.
            let history = match loading.ramp_time.filter(|_| data.strain.is_none()) {
                Some(tr) => History::from_knots(
                    (0..=64)
                        .map(|i| (tr * i as f64 / 64.0, se(held * i as f64 / 64.0)))
                        .collect(),
                )?,
                None => strain_hist.map(se),
            };
            let e_ref = 3.0 * model.initial_shear_modulus(p);
            let held_stress = se(peak);
            if !(held_stress.is_finite() && held_stress != 0.0 && e_ref > 0.0) {
                return Err(Error::settings(format!(
                    "the hyperelastic fit gives stress {held_stress} Pa at stretch {}: no QLV reference",
                    1.0 + peak
                )));
            }
            (
                history,
                Formulation::Qlv,
                e_ref,
                Some(QlvInfo {
                    hyperelastic_model: q.fit.spec.name.clone(),
                    reference_modulus_pa: e_ref,
                    instantaneous_scale: f64::NAN,
                    held_stress_pa: held_stress,
                }),
            )
        }
    })
}
