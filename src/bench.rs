//! Speed against accuracy of the estimators (`dea-fit bench …`, criterion benches).
//!
//! Timing is wall clock ([`std::time::Instant`]) of whole library calls on one
//! thread, repeated until a per-case [`Budget`] is spent, summarised by the median
//! (robust to the odd descheduled run on a shared machine). Accuracy is what the
//! fit reached: the objective ½‖r‖² of the estimator's own residuals, the RMSE, and
//! how many multi-start points ended at the best objective.

use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::fit::hyperelastic::{self, HyperelasticFit, Search, Settings};
use crate::fit::problem::HyperProblem;
use crate::fit::Status;
use crate::io::tensile::{self, TensileOptions};
use crate::material::hyperelastic::{ModelSpec, MODEL_NAMES};
use nalgebra::DVector;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// How long to measure one case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Repeat at least this often, whatever the time.
    pub min_repeats: usize,
    /// Never repeat more often than this.
    pub max_repeats: usize,
    /// Stop repeating once this many seconds have passed (after `min_repeats`).
    pub seconds: f64,
}

impl Default for Budget {
    fn default() -> Self {
        Budget {
            min_repeats: 5,
            max_repeats: 20_000,
            seconds: 0.2,
        }
    }
}

impl Budget {
    /// Reject budgets that cannot measure anything.
    pub fn check(&self) -> Result<()> {
        if self.min_repeats == 0 || self.max_repeats < self.min_repeats {
            return Err(Error::settings(format!(
                "repeats must satisfy 1 ≤ min ({}) ≤ max ({})",
                self.min_repeats, self.max_repeats
            )));
        }
        if !(self.seconds >= 0.0 && self.seconds.is_finite()) {
            return Err(Error::settings(format!(
                "the time budget per case must be ≥ 0 s, found {}",
                self.seconds
            )));
        }
        Ok(())
    }
}

/// Wall-clock statistics of repeated runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Median seconds per run.
    pub median_s: f64,
    /// Fastest run (s).
    pub min_s: f64,
    /// Number of runs.
    pub repeats: usize,
}

/// Median of `v` (mean of the two middle values for even length; NaN if empty).
pub fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

/// Run `f` repeatedly within `budget`; returns the timing and the last result.
/// The first error stops the measurement and is returned.
pub fn measure<T>(budget: &Budget, mut f: impl FnMut() -> Result<T>) -> Result<(Timing, T)> {
    budget.check()?;
    let start = Instant::now();
    let mut times = Vec::new();
    loop {
        let t = Instant::now();
        let out = f()?;
        times.push(t.elapsed().as_secs_f64());
        let enough =
            times.len() >= budget.min_repeats && start.elapsed().as_secs_f64() >= budget.seconds;
        if enough || times.len() >= budget.max_repeats {
            let timing = Timing {
                median_s: median(&times),
                min_s: times.iter().copied().fold(f64::INFINITY, f64::min),
                repeats: times.len(),
            };
            return Ok((timing, out));
        }
    }
}

/// Name of the shipped VHB 4910 uniaxial set.
pub const VHB_UNIAXIAL: &str = "vhb4910-uniaxial";
/// Name of the shipped VHB 4910 set with all three modes.
pub const VHB_ALL: &str = "vhb4910-3modes";
/// Name of Treloar's (1944) three modes together: the classic hard case.
pub const TRELOAR_ALL: &str = "treloar-3modes";

/// A named dataset.
#[derive(Debug, Clone)]
pub struct NamedData {
    /// Short name used in tables and file names.
    pub name: String,
    /// The data.
    pub data: Dataset,
}

/// The shipped data under `dir` (normally `datasets/`): [`VHB_UNIAXIAL`],
/// [`VHB_ALL`] and [`TRELOAR_ALL`], in that order. Each file's mode comes from its
/// `# mode:` line.
pub fn shipped_datasets(dir: &Path) -> Result<Vec<NamedData>> {
    let read = |set: &str, mode: &str| {
        tensile::read(
            &dir.join(set).join(format!("{mode}.csv")),
            &TensileOptions::default(),
        )
    };
    let modes = ["uniaxial", "equibiaxial", "planar"];
    let all = |set: &str| -> Result<Dataset> {
        let mut d = Dataset::default();
        for m in modes {
            d.extend(read(set, m)?);
        }
        Ok(d)
    };
    Ok(vec![
        NamedData {
            name: VHB_UNIAXIAL.into(),
            data: read("vhb4910", "uniaxial")?,
        },
        NamedData {
            name: VHB_ALL.into(),
            data: all("vhb4910")?,
        },
        NamedData {
            name: TRELOAR_ALL.into(),
            data: all("treloar")?,
        },
    ])
}

/// Which question a benchmark row answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Study {
    /// Every model on every dataset with default settings: time vs RMSE.
    Models,
    /// Ogden-3 on [`TRELOAR_ALL`]: number of multi-start points vs objective vs time.
    Starts,
    /// Ogden-3 on [`TRELOAR_ALL`]: LM cost tolerance vs objective vs time.
    Tolerance,
    /// Nonlinear models on [`TRELOAR_ALL`]: variable projection vs full LM.
    Method,
}

/// One measured case of the hyperelastic benchmark (one CSV row).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HyperRow {
    /// Which study.
    pub study: Study,
    /// Dataset name.
    pub dataset: String,
    /// Model name.
    pub model: String,
    /// The setting varied (`default`, `max_starts`, `ftol`, `method`).
    pub setting: String,
    /// Its value.
    pub value: String,
    /// Median wall time of a whole [`hyperelastic::fit`] call, diagnostics included (s).
    pub fit_median_s: f64,
    /// Fastest whole call (s).
    pub fit_min_s: f64,
    /// Median time of the search alone ([`crate::fit::SolverReport::seconds`], s).
    pub solver_median_s: f64,
    /// Number of timed runs.
    pub repeats: usize,
    /// Objective reached, ½‖r‖² of the scaled residuals (Pa² for absolute residuals).
    pub objective: f64,
    /// RMSE over all points (Pa).
    pub rmse_pa: f64,
    /// Multi-start points searched.
    pub starts: usize,
    /// Points whose search ended at the best objective of this run.
    pub starts_at_best: usize,
    /// LM iterations, summed over starts and polish.
    pub iterations: usize,
    /// Residual evaluations.
    pub evaluations: usize,
    /// Fit status.
    pub status: Status,
}

/// The objective ½‖r‖² that `settings` minimise, at the fit's parameters.
pub fn objective(fit: &HyperelasticFit, data: &Dataset, settings: &Settings) -> Result<f64> {
    let model = fit.evaluator()?;
    let prob = HyperProblem::new(model.as_ref(), data, settings.residual);
    let mut r = DVector::zeros(prob.len());
    prob.residuals(&fit.values(), &mut r);
    Ok(0.5 * r.norm_squared())
}

/// One case: a model, data and settings, and the name of what was varied.
#[derive(Debug, Clone)]
pub struct HyperCase {
    /// Study.
    pub study: Study,
    /// Index into the plan's datasets.
    pub dataset: usize,
    /// Model.
    pub spec: ModelSpec,
    /// Settings.
    pub settings: Settings,
    /// Setting varied.
    pub setting: String,
    /// Its value.
    pub value: String,
}

/// What `dea-fit bench hyperelastic` measures.
#[derive(Debug, Clone)]
pub struct HyperPlan {
    /// Datasets (the studies other than [`Study::Models`] use the one named [`TRELOAR_ALL`]).
    pub datasets: Vec<NamedData>,
    /// Cases, in run order.
    pub cases: Vec<HyperCase>,
    /// Measurement budget per case.
    pub budget: Budget,
}

/// Tolerances of the [`Study::Tolerance`] sweep.
pub const FTOLS: [f64; 7] = [1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12];

impl HyperPlan {
    /// The standard plan over `datasets` (see [`shipped_datasets`]): every model on
    /// every dataset; then, on [`TRELOAR_ALL`] if present, Ogden-3 with 1, 2, 4, …
    /// and all multi-start points, Ogden-3 at each of [`FTOLS`], and Gent and
    /// Ogden-1…4 by variable projection and by full LM.
    pub fn standard(datasets: Vec<NamedData>, budget: Budget) -> Result<Self> {
        budget.check()?;
        let base = Settings::default();
        let case =
            |study, dataset, name: &str, settings: &Settings, setting: &str, value| HyperCase {
                study,
                dataset,
                spec: ModelSpec::new(name, settings.ogden_form),
                settings: settings.clone(),
                setting: setting.into(),
                value,
            };
        let mut cases = Vec::new();
        for d in 0..datasets.len() {
            for m in MODEL_NAMES {
                cases.push(case(Study::Models, d, m, &base, "default", "".into()));
            }
        }
        if let Some(t) = datasets.iter().position(|d| d.name == TRELOAR_ALL) {
            let ogden3 = ModelSpec::new("ogden3", base.ogden_form).build()?;
            let prob = HyperProblem::new(ogden3.as_ref(), &datasets[t].data, base.residual);
            let total = ogden3.nonlinear_starts(prob.max_i1_minus_3()).len();
            let mut counts: Vec<usize> = (0..)
                .map(|e| 1usize << e)
                .take_while(|&c| c < total)
                .collect();
            counts.push(total);
            for c in counts {
                let s = Settings {
                    max_starts: Some(c),
                    ..base.clone()
                };
                cases.push(case(
                    Study::Starts,
                    t,
                    "ogden3",
                    &s,
                    "max_starts",
                    c.to_string(),
                ));
            }
            for f in FTOLS {
                let s = Settings {
                    ftol: f,
                    ..base.clone()
                };
                cases.push(case(
                    Study::Tolerance,
                    t,
                    "ogden3",
                    &s,
                    "ftol",
                    format!("{f:e}"),
                ));
            }
            for m in ["gent", "ogden1", "ogden2", "ogden3", "ogden4"] {
                for (method, label) in [(Search::VarPro, "varpro"), (Search::Full, "full")] {
                    let s = Settings {
                        method,
                        ..base.clone()
                    };
                    cases.push(case(Study::Method, t, m, &s, "method", label.into()));
                }
            }
        }
        Ok(HyperPlan {
            datasets,
            cases,
            budget,
        })
    }

    /// Measure every case in order, calling `progress` after each.
    pub fn run(&self, progress: &mut dyn FnMut(&HyperRow)) -> Result<Vec<HyperRow>> {
        let mut rows = Vec::with_capacity(self.cases.len());
        for c in &self.cases {
            let d = self.datasets.get(c.dataset).ok_or_else(|| {
                Error::settings(format!("case refers to dataset {} of none", c.dataset))
            })?;
            let mut solver = Vec::new();
            let (timing, fit) = measure(&self.budget, || {
                let f = hyperelastic::fit(&d.data, &c.spec, &c.settings)?;
                solver.push(f.solver.seconds);
                Ok(f)
            })?;
            let row = HyperRow {
                study: c.study,
                dataset: d.name.clone(),
                model: fit.model.clone(),
                setting: c.setting.clone(),
                value: c.value.clone(),
                fit_median_s: timing.median_s,
                fit_min_s: timing.min_s,
                solver_median_s: median(&solver),
                repeats: timing.repeats,
                objective: objective(&fit, &d.data, &c.settings)?,
                rmse_pa: fit.rmse_pa,
                starts: fit.solver.starts,
                starts_at_best: fit.solver.starts_at_best,
                iterations: fit.solver.iterations,
                evaluations: fit.solver.evaluations,
                status: fit.status,
            };
            progress(&row);
            rows.push(row);
        }
        Ok(rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped() -> Vec<NamedData> {
        shipped_datasets(&Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets")).unwrap()
    }

    #[test]
    fn standard_plan_covers_every_study() {
        let plan = HyperPlan::standard(shipped(), Budget::default()).unwrap();
        let count = |s| plan.cases.iter().filter(|c| c.study == s).count();
        assert_eq!(count(Study::Models), 3 * MODEL_NAMES.len());
        assert_eq!(count(Study::Tolerance), FTOLS.len());
        assert_eq!(count(Study::Method), 10);
        // Ogden-3 has C(8, 3) = 56 starts: 1, 2, 4, …, 32 and all 56.
        let starts: Vec<Option<usize>> = plan
            .cases
            .iter()
            .filter(|c| c.study == Study::Starts)
            .map(|c| c.settings.max_starts)
            .collect();
        let want = [1, 2, 4, 8, 16, 32, 56].map(Some);
        assert_eq!(starts, want);
        // Without Treloar's data only the per-model study remains.
        let mut vhb = shipped();
        vhb.truncate(2);
        let plan = HyperPlan::standard(vhb, Budget::default()).unwrap();
        assert!(plan.cases.iter().all(|c| c.study == Study::Models));
    }

    #[test]
    fn objective_is_half_the_residual_sum_of_squares() {
        // Unit weights and absolute residuals: ½‖r‖² = ½·n·RMSE².
        let d = &shipped()[0];
        let s = Settings::default();
        let fit = hyperelastic::fit(&d.data, &ModelSpec::new("yeoh", s.ogden_form), &s).unwrap();
        let n = d.data.samples.len() as f64;
        let want = 0.5 * n * fit.rmse_pa.powi(2);
        let got = objective(&fit, &d.data, &s).unwrap();
        assert!((got - want).abs() <= 1e-12 * want, "{got} vs {want}");
    }

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn measure_respects_repeat_limits_and_errors() {
        let b = Budget {
            min_repeats: 3,
            max_repeats: 7,
            seconds: 10.0,
        };
        let mut n = 0;
        let (t, last) = measure(&b, || {
            n += 1;
            Ok(n)
        })
        .unwrap();
        // The 10 s budget is never spent: max_repeats stops it.
        assert_eq!((t.repeats, last), (7, 7));
        assert!(t.min_s <= t.median_s);
        let b = Budget { seconds: 0.0, ..b };
        let (t, _) = measure(&b, || Ok(())).unwrap();
        assert_eq!(t.repeats, 3);
        let err = measure(&b, || Err::<(), _>(Error::settings("boom")));
        assert!(err.is_err());
        let bad = Budget {
            min_repeats: 0,
            ..b
        };
        assert!(measure(&bad, || Ok(())).is_err());
    }
}

/// The drive of [`identify_case`]'s trace.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Drive {
    /// The scene's input in closed form (its steps, ramps and sines).
    ClosedForm,
    /// The actuator's voltage as a rig logs it: the simulated voltage at the
    /// trace's samples with noise of 0.1 % of its peak (seed 11), fitted as a
    /// measured input (`sim::input::measured`) behind an ideal source: what
    /// `identify` does with a trace file.
    Measured,
}

/// The drive as the JSON names it ("closed-form", "measured"), one spelling for
/// the CSV, the table and the JSON.
impl std::fmt::Display for Drive {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Drive::ClosedForm => "closed-form",
            Drive::Measured => "measured",
        })
    }
}

/// One measured case of `dea-fit bench identify`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IdentifyRow {
    /// The trace's drive.
    pub drive: Drive,
    /// Simulator relative tolerance.
    pub rtol: f64,
    /// Multi-start points.
    pub starts: usize,
    /// Wall time of the whole identification (s), fastest of the repeats.
    pub seconds: f64,
    /// Of which per start (s): `seconds / starts`.
    pub per_start_s: f64,
    /// Of which the interval stage (s): the covariance, the profile checks and
    /// intervals ([`crate::identify::SolverSummary::interval_seconds`]), of the
    /// fastest repeat; 0 when the run gave no result.
    pub interval_s: f64,
    /// Largest |θ − truth|/|truth| over the identifiable constants.
    pub max_rel_error: f64,
    /// Largest |θ − truth|/σ over the identifiable constants.
    pub max_z: f64,
    /// Constants identified / free.
    pub identified: usize,
    /// Free constants.
    pub free: usize,
    /// Starts at the best cost.
    pub starts_at_best: usize,
    /// LM iterations (all starts and polish).
    pub iterations: usize,
    /// Simulator runs (all).
    pub simulator_runs: usize,
    /// Status.
    pub status: Status,
}

/// The identification benchmark's problem: `scene` simulated at its constants with
/// 1 % (of the peak) contraction and 0.1 % capacitance noise (seed 10), driven as
/// `drive` says, and the scene the search starts from, every free constant 20 %
/// above its truth.
pub fn identify_case(
    scene: &crate::sim::scene::Scene,
    drive: Drive,
) -> Result<(crate::identify::problem::Experiment, Vec<f64>)> {
    use crate::identify::params;
    use crate::identify::problem::{simulated, ChannelKind, Experiment};
    use crate::sim::input::{Measured, Term, Waveform};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let o = crate::sim::simulate(scene, &crate::sim::RunOptions::default())?;
    let s0 = o.samples[0];
    let peak = |k: ChannelKind| {
        o.samples
            .iter()
            .map(|s| simulated(k, &s0, s).abs())
            .fold(0.0, f64::max)
    };
    let mut exp = Experiment::synthetic(
        scene,
        &[
            (
                ChannelKind::Contraction,
                0.01 * peak(ChannelKind::Contraction),
            ),
            (
                ChannelKind::Capacitance,
                0.001 * peak(ChannelKind::Capacitance),
            ),
        ],
        10,
    )?;
    if drive == Drive::Measured {
        let peak = o
            .samples
            .iter()
            .map(|s| s.voltage_v.abs())
            .fold(0.0, f64::max);
        let noise = Normal::new(0.0, 1e-3 * peak)
            .map_err(|e| Error::settings(format!("voltage noise of {}: {e}", scene.name)))?;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let t: Vec<f64> = o.samples.iter().map(|s| s.time_s).collect();
        let v: Vec<f64> = o
            .samples
            .iter()
            .map(|s| s.voltage_v + noise.sample(&mut rng))
            .collect();
        let m = Measured::fit(&t, &v)
            .map_err(|e| Error::settings(format!("the measured drive of {}: {e}", scene.name)))?;
        exp.scene.input = Waveform {
            terms: vec![Term::Measured(std::sync::Arc::new(m))],
        };
        exp.scene.source = crate::sim::scene::Source::Ideal;
    }
    let truth = params::theta(scene);
    let start: Vec<f64> = truth.iter().map(|v| 1.2 * v).collect();
    params::set_theta(&mut exp.scene, &start);
    Ok((exp, truth))
}

/// Identify `scene`'s constants (from [`identify_case`]) as the command line does
/// by default (every constant free, the smallest identifiable model:
/// [`crate::identify::reduce::identify`]) for each drive, rtol and start count,
/// fastest of `repeats` runs each.
pub fn identify_rows(
    scene: &crate::sim::scene::Scene,
    drives: &[Drive],
    rtols: &[f64],
    starts: &[usize],
    repeats: usize,
    progress: &mut dyn FnMut(&IdentifyRow),
) -> Result<Vec<IdentifyRow>> {
    use crate::identify::{params, reduce, Run, Settings};
    let all = params::constants(scene);
    let mut rows = Vec::new();
    let cases = drives
        .iter()
        .map(|&d| identify_case(scene, d).map(|c| (d, c)))
        .collect::<Result<Vec<_>>>()?;
    for ((drive, (exp, truth)), &rtol) in
        cases.iter().flat_map(|c| rtols.iter().map(move |r| (c, r)))
    {
        let drive = *drive;
        for &n in starts {
            let settings = Settings {
                starts: n,
                rtol: Some(rtol),
                ..Settings::default()
            };
            let mut best = f64::INFINITY;
            let mut fastest = None;
            for _ in 0..repeats.max(1) {
                let t = Instant::now();
                let id = reduce::identify(std::slice::from_ref(exp), &settings, &|_| {
                    crate::fit::lm::Control::default()
                })?;
                let s = t.elapsed().as_secs_f64();
                if s < best {
                    best = s;
                    fastest = Some(id);
                }
            }
            let row = match fastest.expect("repeats ≥ 1") {
                Run::Identified(id) => {
                    let (mut err, mut z) = (0.0f64, 0.0f64);
                    for p in id.parameters.iter().filter(|p| p.identifiable) {
                        let c = all.iter().find(|c| c.name == p.name).expect("a constant");
                        let t = truth[c.index];
                        err = err.max(((p.value - t) / t).abs());
                        if let Some(s) = p.std_error {
                            z = z.max(((p.value - t) / s).abs());
                        }
                    }
                    IdentifyRow {
                        drive,
                        rtol,
                        starts: n,
                        seconds: best,
                        per_start_s: best / n as f64,
                        interval_s: id.solver.interval_seconds,
                        max_rel_error: err,
                        max_z: z,
                        identified: id.parameters.iter().filter(|p| p.identifiable).count(),
                        free: id.parameters.len(),
                        starts_at_best: id.solver.starts_at_best,
                        iterations: id.solver.iterations,
                        simulator_runs: id.solver.simulator_runs,
                        status: id.status,
                    }
                }
                // no result: no error to measure
                Run::Failed(f) => IdentifyRow {
                    drive,
                    rtol,
                    starts: n,
                    seconds: best,
                    per_start_s: best / n as f64,
                    interval_s: 0.0,
                    max_rel_error: f64::NAN,
                    max_z: f64::NAN,
                    identified: 0,
                    free: f.free.len(),
                    starts_at_best: 0,
                    iterations: f.solver.iterations,
                    simulator_runs: f.solver.simulator_runs,
                    status: f.status,
                },
            };
            progress(&row);
            rows.push(row);
        }
    }
    Ok(rows)
}

// --- bench make: the projects it times -----------------------------------------

/// A scratch folder under the system's temporary folder, removed with what it holds
/// when dropped (`bench make` runs its projects there).
pub struct Scratch(std::path::PathBuf);

impl Scratch {
    /// A new empty folder `dea-fit-<what>-<pid>-<ns>`.
    pub fn new(what: &str) -> Result<Scratch> {
        let ns = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let p = std::env::temp_dir().join(format!("dea-fit-{what}-{}-{ns}", std::process::id()));
        std::fs::create_dir_all(&p).map_err(|e| Error::io(&p, e))?;
        Ok(Scratch(p))
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Write a project of `steps` steps into `dir`: step `m<k>/breakdown` is `dea-fit
/// breakdown` of `raw/c<k>.csv`, each a copy of `series` (a breakdown series).
pub fn make_project(dir: &Path, steps: usize, series: &[u8]) -> Result<()> {
    let raw = dir.join("raw");
    std::fs::create_dir_all(&raw).map_err(|e| Error::io(&raw, e))?;
    let width = steps.saturating_sub(1).to_string().len();
    let mut toml = String::from("# generated by dea-fit bench make\n");
    for k in 0..steps {
        let name = format!("{k:0width$}");
        crate::io::write::atomic_write(&raw.join(format!("c{name}.csv")), series)?;
        toml.push_str(&format!(
            "\n[materials.m{name}.breakdown]\nfiles = \"raw/c{name}.csv\"\n"
        ));
    }
    crate::io::write::atomic_write(&dir.join(crate::project::FILE), toml.as_bytes())
}

/// Copy the project folder `from` into `to`, without what make writes there
/// (`fits/`, `reports/`, `.dea-fit/`).
pub fn copy_project(from: &Path, to: &Path) -> Result<()> {
    fn walk(from: &Path, to: &Path, top: bool) -> Result<()> {
        std::fs::create_dir_all(to).map_err(|e| Error::io(to, e))?;
        for e in std::fs::read_dir(from).map_err(|e| Error::io(from, e))? {
            let e = e.map_err(|e| Error::io(from, e))?;
            let name = e.file_name();
            if top
                && ["fits", "reports", crate::project::STATE_DIR]
                    .contains(&&*name.to_string_lossy())
            {
                continue;
            }
            let (src, dst) = (e.path(), to.join(&name));
            if src.is_dir() {
                walk(&src, &dst, false)?;
            } else {
                std::fs::copy(&src, &dst).map_err(|e| Error::io(&src, e))?;
            }
        }
        Ok(())
    }
    walk(from, to, true)
}
