//! What a relaxation fit reports: the notes on a fit with no term, the status and
//! warnings of the chosen count, and the fit record.

use super::prepare::{Prepared, TimeKernels};
use super::{
    ArmEntry, Loading, Method, PronyEntry, Provenance, QlvInfo, QlvInput, RelaxationFit, Selection,
    Settings, SpectrumPoint, EXPLAINS_NOTHING, SCHEMA, SYSTEMATIC,
};
use crate::fit::diagnostics;
use crate::fit::prony::assess::Assessed;
use crate::fit::prony::grid::Grid;
use crate::fit::prony::refine::START_POINTS;
use crate::fit::prony::select::{self, Choice};
use crate::fit::prony::{fmt_s, Search};
use crate::fit::{SolverReport, Status};
use crate::io::relaxation::RelaxationData;

/// What the record of a fit is made from, besides the chosen count.
pub(super) struct Inputs<'a> {
    pub data: &'a RelaxationData,
    pub loading: &'a Loading,
    pub qlv: Option<&'a QlvInput>,
    pub settings: &'a Settings,
    pub prep: &'a Prepared,
    pub grid: &'a Grid,
}

/// For `--terms auto` that chose no term although the data vary: why no Prony series
/// could be reported (returned: the fit is ill-posed), or (into `notes`) that the
/// stress does not relax as exponentials, or that it does not relax at all.
pub(super) fn no_terms(
    prep: &Prepared,
    assessed: &[Assessed<TimeKernels>],
    choice: &Choice,
    search: &Search,
    notes: &mut Vec<String>,
) -> Option<String> {
    let best = choice.best?;
    let c = &assessed[choice.index];
    let score = |a: &Assessed<TimeKernels>| select::score(search, a);
    if c.tf.n_terms == 0 && c.explained > EXPLAINS_NOTHING {
        if score(c) > score(&assessed[best]) + 2.0 {
            return Some(format!(
                "no identifiable Prony series: the data relax (a constant modulus leaves a relative RMSE of {:.3} %), but every fit with terms puts them where these data cannot determine them; check the loading (--ramp-time, a strain column) and the time window",
                100.0 * c.rel_rmse
            ));
        } else if c.lag1 >= SYSTEMATIC {
            notes.push(format!(
                "no Prony series explains how the stress varies: a constant modulus leaves a relative RMSE of {:.3} % whose residuals are systematic (lag-1 autocorrelation {:.2}), not noise; the stress does not relax as decaying exponentials of this loading: check the loading (--ramp-time, a strain column) and the stress column",
                100.0 * c.rel_rmse,
                c.lag1
            ));
        } else {
            notes.push(format!(
                "no relaxation resolved: a constant modulus fits as well as any Prony series (relative RMSE {:.3} %) — purely elastic within the noise over {}–{}",
                100.0 * c.rel_rmse,
                fmt_s(prep.setup.window.0),
                fmt_s(prep.setup.window.1)
            ));
        }
    }
    None
}

/// Status and warnings of the chosen count, and the QLV reading's instantaneous scale.
pub(super) struct Verdict {
    status: Status,
    warnings: Vec<String>,
    qlv: Option<QlvInfo>,
}

/// The status and warnings of the chosen count `a`: the notes so far, its problems,
/// a fit that explains nothing, a step assumed on a ramp, a hyperelastic fit that is
/// not the instantaneous response.
pub(super) fn verdict(
    data: &RelaxationData,
    loading: &Loading,
    prep: &Prepared,
    a: &Assessed<TimeKernels>,
    notes: Vec<String>,
    unresolved: Option<String>,
) -> Verdict {
    let (n, m) = (a.tf.n_terms, data.time.len());
    let mut status = Status::Ok;
    let mut warnings = Vec::new();
    for w in notes {
        status.escalate(Status::Warning);
        warnings.push(w);
    }
    // what the reader did beyond reading (a preamble skipped, a units row read,
    // columns not used): said, as for tensile files, not a warning of the fit
    let name = std::path::Path::new(&data.source.path)
        .file_name()
        .map_or_else(
            || data.source.path.clone(),
            |n| n.to_string_lossy().into_owned(),
        );
    warnings.extend(data.source.notes.iter().map(|n| format!("{name}: {n}")));
    if let Some(w) = unresolved {
        status.escalate(Status::IllPosed);
        warnings.push(w);
    }
    for (s, w) in a.problems.iter().chain(&a.warnings) {
        status.escalate(*s);
        warnings.push(w.clone());
    }
    if let Some(w) = diagnostics::worse_than_mean(a.r2) {
        status.escalate(Status::IllPosed);
        warnings.push(w);
    }
    if a.explained <= EXPLAINS_NOTHING {
        status.escalate(Status::IllPosed);
        warnings.push(format!(
            "the fit explains nothing: it leaves {:.0} % of the data's weighted sum of squares (relative RMSE {:.3} %, R² {:.3}), where zero stress leaves 100 %; check the stress column (its sign and unit), the loading and --residual",
            100.0 * (1.0 - a.explained),
            100.0 * a.rel_rmse,
            a.r2
        ));
    }
    // A step assumed while the stress builds up: the loading was not a step.
    if data.strain.is_none() && loading.ramp_time.is_none() {
        let y = &data.stress;
        let peak = (0..m)
            .max_by(|&i, &j| y[i].abs().total_cmp(&y[j].abs()))
            .expect("non-empty");
        if peak > 0 && y[peak].abs() > 1.05 * y[0].abs() && data.time[peak] < 0.2 * data.time[m - 1]
        {
            status.escalate(Status::Warning);
            warnings.push(format!(
                "the stress rises until t = {} although the loading is taken as an ideal step: give the ramp (--ramp-time) or a strain column, or the fit puts spurious stiff short-τ terms on the ramp",
                fmt_s(data.time[peak])
            ));
        }
    }
    let si = &a.si;
    let e0: f64 = si[..=n].iter().sum();
    let mut qlv_info = prep.qlv.clone();
    if let Some(q) = &mut qlv_info {
        q.instantaneous_scale = e0 / prep.setup.unit;
        if let Some(w) = qlv_consistency(q.instantaneous_scale) {
            status.escalate(Status::Warning);
            warnings.push(w);
        }
    }
    Verdict {
        status,
        warnings,
        qlv: qlv_info,
    }
}

/// What QLV's G(0) (`g0`, the relaxation's start over the hyperelastic stress)
/// says about the two data sets, beyond 10 % of agreement. A tensile test at a
/// finite rate lies between the relaxed and the instantaneous response: its stress
/// is s × the instantaneous one with s ≤ 1, so consistent data have G(0) = 1/s ≥ 1
/// (the finite-rate case, said as such when G(0) > 1.1). G(0) < 1 no rate
/// explains: the tensile and the relaxation data disagree (another specimen or
/// material, strain measure, units, a preload), and the warning says so. (The
/// relaxed end G(∞) is not judged: E∞ is an extrapolation of the data's window.)
pub(super) fn qlv_consistency(g0: f64) -> Option<String> {
    const TOL: f64 = 0.1;
    if g0 < 1.0 - TOL {
        Some(format!(
            "the tensile and the relaxation data disagree: the relaxation starts at G(0) = {g0:.3} × the hyperelastic stress, below it, while a tensile test at any rate lies at or below the instantaneous response (G(0) ≥ 1); check that both are of one material and specimen, the strain measure, the units and a preload; the instantaneous response is taken as G(0) times the hyperelastic stress"
        ))
    } else if g0 > 1.0 + TOL {
        Some(format!(
            "the hyperelastic fit is not the instantaneous response of these data: the relaxation starts at G(0) = {g0:.3} × its stress (a tensile test at a finite rate lies between the instantaneous and the long-term response); the instantaneous response is G(0) times the hyperelastic stress"
        ))
    } else {
        None
    }
}

/// The fit record of the chosen count `a`.
pub(super) fn report(
    inputs: Inputs,
    a: Assessed<TimeKernels>,
    verdict: Verdict,
    selection: Option<Selection>,
    seconds: f64,
) -> RelaxationFit {
    let Inputs {
        data,
        loading,
        qlv,
        settings,
        prep,
        grid,
    } = inputs;
    let (n, m) = (a.tf.n_terms, data.time.len());
    let solver_iterations = a.tf.iterations + grid.2;
    let si = &a.si;
    let e0: f64 = si[..=n].iter().sum();
    let parameters = a.parameters();
    let prony: Vec<PronyEntry> = (0..n)
        .map(|i| PronyEntry {
            tau_s: si[1 + n + i],
            modulus_pa: si[1 + i],
            g: if e0 > 0.0 { si[1 + i] / e0 } else { 0.0 },
            tau_std_s: a.unc.std_error[1 + n + i],
            modulus_std_pa: a.unc.std_error[1 + i],
        })
        .collect();
    let kelvin_maxwell = prony
        .iter()
        .map(|p| ArmEntry {
            k_pa: p.modulus_pa,
            n_pa_s: p.modulus_pa * p.tau_s,
        })
        .collect();
    let spectrum = grid
        .0
        .iter()
        .zip(&grid.1[1..])
        .map(|(&t, &e)| SpectrumPoint {
            tau_s: t,
            modulus_pa: e * prep.setup.prob.scale * prep.setup.unit,
        })
        .collect();
    let termination = a.tf.termination.to_string();
    // The grid stage's points (grid_stage).
    let on = match m > START_POINTS {
        true => format!(" on {START_POINTS} of the {m} points"),
        false => String::new(),
    };
    let method = match settings.method {
        Method::Refined => format!(
            "grid NNLS ({} τ, {}/decade, Lawson–Hanson{on}) + merge/prune + variable projection (bounded Levenberg-Marquardt over ln τᵢ, E∞ and Eᵢ by NNLS), multi-start, then LM over (E∞, Eᵢ, ln τᵢ)",
            grid.0.len(),
            settings.grid_per_decade
        ),
        Method::Grid => format!(
            "grid NNLS ({} τ, {}/decade, Lawson–Hanson{on}) + merge/prune, moduli by NNLS at the merged τ (no refinement)",
            grid.0.len(),
            settings.grid_per_decade
        ),
    };
    RelaxationFit {
        schema: SCHEMA.into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        formulation: prep.formulation,
        held_strain: prep.held_strain,
        loading: prep.loading.clone(),
        prony,
        long_term_modulus_pa: si[0],
        instantaneous_modulus_pa: e0,
        g_inf: if e0 > 0.0 { si[0] / e0 } else { 0.0 },
        kelvin_maxwell,
        qlv: verdict.qlv,
        parameters,
        rmse_pa: a.rmse,
        rel_rmse: a.rel_rmse,
        r2: a.r2,
        aicc: a.aicc,
        bic: a.bic,
        residual: prep.residual,
        points: m,
        time_window_s: [prep.setup.window.0, prep.setup.window.1],
        spectrum,
        correlation: a.unc.correlation.clone(),
        condition_number: a.unc.condition.is_finite().then_some(a.unc.condition),
        status: verdict.status,
        warnings: verdict.warnings,
        solver: SolverReport {
            method,
            starts: a.tf.starts,
            starts_at_best: a.tf.at_best,
            iterations: solver_iterations,
            evaluations: a.tf.evaluations,
            seconds,
            termination,
        },
        selection,
        provenance: Provenance {
            files: vec![data.source.clone()],
            hyperelastic_fit: qlv.map(|q| q.file.clone()),
            loading: *loading,
            settings: serde_json::to_value(settings).unwrap_or_default(),
        },
    }
}
