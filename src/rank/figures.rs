//! The figures of one candidate at one drive: catalogue figures and what the
//! simulator predicts on the design's actuator.
//!
//! Catalogue (SI): εr; Y = 3μ0; β = εr/Y; the Sommer-Larsen & Larsen figure of merit
//! Fm = 3ε0εrEb²/Y (El Atrache Ceballos (2021) §2.6); tan δ at the drive frequency.
//!
//! On the actuator (the design's scene with the candidate's constants; stroke is
//! the contraction 1 − λ/λ0 of the loaded rest length, λ the thickness stretch):
//! * **static stroke at the drive voltage V**: the fully relaxed equilibrium
//!   (`Plant::static_stretch`). Past the pull-in voltage (the peak of the static
//!   curve, `sim::static_curve`) there is none: the candidate is `pull_in` and not
//!   ranked on stroke. Where the true field V/g(λ) at that equilibrium reaches the
//!   breakdown field Eb (g the electrode gap: z0·λ for a stack layer, z0·λ·sin α
//!   for a helix element), the candidate is `breakdown`; so is a drive past the
//!   pull-in whose rise meets Eb first on the stable branch (the limit it meets
//!   first names the state).
//! * **largest stroke** before pull-in or breakdown, whichever comes first along the
//!   stable branch of the static curve (the field rises monotonically along it), and
//!   which one it was (`range` when neither happens down to λ = [`STRETCH_MIN`]: the
//!   stroke there is a lower bound).
//! * **blocked force** F = −½V²·C′(λ0)/L0 (N): the electrostatic force with the
//!   actuator held at its rest length (for a stack εr·ε0·(V/z)²·A, the Maxwell
//!   pressure on the electrode area).
//! * **response time**: 10–90 % of the contraction a step to V reaches at the end
//!   of the step window, from a damped run of the simulator (`sim::simulate`,
//!   the scene's source, the candidate's viscous arms and dashpot), read between
//!   samples by linear interpolation.
//! * **electrical energy in** per cycle, W = ½C(λd)V² + ∫ from λ0 to λd of
//!   (Vol·P(λ) − F_load·L0) dλ, the work of a quasi-static charge to V (field energy
//!   plus the work on the material and the load; from the Lagrange equation
//!   Vol·P − F_load·L0 = ½V²·C′), and the **dielectric loss** per cycle of a 0–V
//!   sine at the drive frequency, π·C(λd)·(V/2)²·tan δ (the loss of its AC part of
//!   amplitude V/2, with the capacitance at the drive: an upper bound, C grows with
//!   the stroke).
//! * **margins** at the operating point: to breakdown 1 − E/Eb, E = V/g(λd) the
//!   true field at the static stroke; to pull-in 1 − V/V_pull-in. Below
//!   [`SMALL_MARGIN`] the ranking warns.

use super::candidate::Candidate;
use super::manifest::{Design, Level};
use super::short;
use super::{Figure, Provenance};
use crate::fit::composite::Basis;
use crate::report::format::si;
use crate::sim::input::{Term, Waveform};
use crate::sim::plant::EPS0;
use crate::sim::scene::{Actuator, Material, Scene};
use crate::sim::static_curve::{breakdown_point, static_curve, voltage_at, Search};
use crate::sim::{self, RunOptions, RunStatus};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::sync::Arc;

/// Smallest stretch the static curve examines.
pub const STRETCH_MIN: f64 = 0.3;
/// Points of the static curve (the peak is refined by golden section between them).
pub const CURVE_POINTS: usize = 60;
/// Points of the stroke–voltage curve kept for the report.
pub const KEPT_POINTS: usize = 16;
/// A margin to breakdown or to pull-in at the operating point below this (10 %)
/// is a warning of the ranking: breakdown fields scatter by more (a Weibull β of
/// 10 puts 10 % of specimens below 0.8α), and a drive within 10 % of pull-in
/// sits on the flat top of the static curve, where a few % of modulus or
/// thickness decide between a stroke and a collapse.
pub const SMALL_MARGIN: f64 = 0.1;

/// The state of a candidate at the drive voltage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum State {
    /// A stable static equilibrium below the breakdown field.
    Ok,
    /// The drive is at or above the pull-in voltage, and the field stays below the
    /// breakdown field on the way up to it.
    PullIn,
    /// The field at the static equilibrium reaches the breakdown field, or, with
    /// the drive past the pull-in, the field reaches it first on the way up.
    Breakdown,
    /// The candidate could not be evaluated (no rest state, a refused or failed run).
    Failed,
}

impl std::fmt::Display for State {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            State::Ok => "ok",
            State::PullIn => "pull_in",
            State::Breakdown => "breakdown",
            State::Failed => "failed",
        })
    }
}

/// What ends the stable stroke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Limit {
    /// The pull-in (peak of the static curve).
    PullIn,
    /// The breakdown field.
    Breakdown,
    /// Neither down to the smallest stretch examined.
    Range,
}

impl std::fmt::Display for Limit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Limit::PullIn => "pull_in",
            Limit::Breakdown => "breakdown",
            Limit::Range => "range",
        })
    }
}

/// A point of the static stroke–voltage curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurvePoint {
    /// Voltage (V).
    #[serde(rename = "voltage_V")]
    pub voltage_v: f64,
    /// Stroke 1 − λ/λ0.
    pub stroke: f64,
}

/// Everything computed for one candidate at one drive.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Evaluation {
    /// Index of the point in the sweep.
    pub index: usize,
    /// Candidate name.
    pub name: String,
    /// Series.
    pub series: String,
    /// Matrix.
    pub matrix: String,
    /// Filler (null: the matrix alone).
    pub filler: Option<String>,
    /// Loading on the basis.
    pub loading: f64,
    /// Basis of the loading.
    pub basis: Basis,
    /// Filler volume fraction.
    pub volume_fraction: f64,
    /// The εr model and the stiffening rule of the series.
    pub rules: String,
    /// Drive voltage.
    pub voltage: Figure,
    /// Relative permittivity.
    pub eps_r: Figure,
    /// Young's modulus 3μ0.
    pub youngs_modulus: Figure,
    /// β = εr/Y.
    pub beta: Figure,
    /// Fm = 3ε0εrEb²/Y.
    pub fm: Figure,
    /// Loss tangent at the drive frequency.
    pub tan_delta: Figure,
    /// Breakdown field.
    pub breakdown_field: Figure,
    /// State at the drive.
    pub state: State,
    /// The state in words.
    pub state_note: String,
    /// Static stroke at the drive.
    pub static_stroke: Figure,
    /// The pull-in (null: none down to the smallest stretch examined).
    pub pull_in: Option<CurvePoint>,
    /// Where the field reaches Eb on the stable branch (null: it does not).
    pub breakdown: Option<CurvePoint>,
    /// Largest stroke before pull-in or breakdown.
    pub max_stroke: Figure,
    /// What ends it.
    pub max_stroke_limit: Limit,
    /// Blocked force at the drive.
    pub blocked_force: Figure,
    /// 10–90 % response time of a step to the drive.
    pub response_time: Figure,
    /// Electrical energy in per cycle.
    pub energy_in: Figure,
    /// Dielectric loss per cycle.
    pub loss_per_cycle: Figure,
    /// Margin to breakdown at the operating point, 1 − E/Eb (E the true field at
    /// the static stroke; below [`SMALL_MARGIN`] a warning of the ranking).
    pub breakdown_margin: Figure,
    /// Margin to pull-in, 1 − V/V_pull-in (none without a pull-in).
    pub pull_in_margin: Figure,
    /// Warnings of the candidate's properties.
    pub warnings: Vec<String>,
}

impl Evaluation {
    /// Every figure of the evaluation with its field name, in the order above.
    pub fn figures_mut(&mut self) -> [(&'static str, &mut Figure); 15] {
        [
            ("voltage", &mut self.voltage),
            ("eps_r", &mut self.eps_r),
            ("youngs_modulus", &mut self.youngs_modulus),
            ("beta", &mut self.beta),
            ("fm", &mut self.fm),
            ("tan_delta", &mut self.tan_delta),
            ("breakdown_field", &mut self.breakdown_field),
            ("static_stroke", &mut self.static_stroke),
            ("max_stroke", &mut self.max_stroke),
            ("blocked_force", &mut self.blocked_force),
            ("response_time", &mut self.response_time),
            ("energy_in", &mut self.energy_in),
            ("loss_per_cycle", &mut self.loss_per_cycle),
            ("breakdown_margin", &mut self.breakdown_margin),
            ("pull_in_margin", &mut self.pull_in_margin),
        ]
    }

    /// The first-order standard errors of the simulated figures (drive, strokes,
    /// force, response time, energy, loss) by central differences: `shifts` holds,
    /// per property with a σ, the evaluations of the same candidate with that
    /// property 1σ higher and 1σ lower ([`super::candidate::Candidate::shifts`]),
    /// and u(f)² = Σᵢ ((f₊ᵢ − f₋ᵢ)/2)² + (∂f/∂tan δ · u(tan δ))², the properties
    /// being independent (they come from different experiments; GUM, JCGM
    /// 100:2008, eq. 10). The central difference at ±1σ has no second-order term:
    /// it differs from the derivative by f‴σ²/6 (exact for a quadratic; 0.25 % for
    /// a figure going as 1/Y at a 5 % σ), against the one-sided step's f″σ/2, and
    /// it looks at the states on both sides. The loss per cycle is linear in tan δ
    /// (exact derivative, no evaluation); the catalogue figures' σ are their closed
    /// forms ([`catalogue`]); εr, Y, tan δ and Eb keep their own. A shift that moves
    /// the candidate into another state (pulled in, broken down), or a σ not
    /// smaller than its value (no 1σ lower), leaves the simulated figures without
    /// a standard error, and a warning says so.
    pub fn spread(&mut self, shifts: Vec<(&str, Evaluation, Option<Evaluation>)>) {
        for (what, up, down) in &shifts {
            let why = match down {
                None => {
                    Some("1σ lower is not positive (σ is not smaller than the value)".to_string())
                }
                Some(_) if up.state != self.state => Some(format!(
                    "1σ higher the state is {} ({})",
                    up.state, up.state_note
                )),
                Some(d) if d.state != self.state => Some(format!(
                    "1σ lower the state is {} ({})",
                    d.state, d.state_note
                )),
                Some(_) => None,
            };
            if let Some(why) = why {
                self.warnings.push(format!(
                    "{}: with {what} {why}, so its figures have no standard error",
                    self.name
                ));
                return;
            }
        }
        let values = |e: &Evaluation| e.clone().figures_mut().map(|(_, f)| f.value);
        let pairs: Vec<_> = shifts
            .iter()
            .filter_map(|(_, up, down)| down.as_ref().map(|d| (values(up), values(d))))
            .collect();
        // ∂loss/∂tan δ · u(tan δ) = loss · u(tan δ)/tan δ (loss ∝ tan δ)
        let tan = match (self.tan_delta.value, self.tan_delta.std_error) {
            (Some(t), Some(u)) if t > 0.0 => u / t,
            _ => 0.0,
        };
        for (i, (name, f)) in self.figures_mut().into_iter().enumerate() {
            if !SIMULATED.contains(&name) {
                continue;
            }
            let Some(v) = f.value else { continue };
            let var = pairs
                .iter()
                .map(|(u, d)| u[i].zip(d[i]).map(|(a, b)| (0.5 * (a - b)).powi(2)))
                .sum::<Option<f64>>()
                .map(|x| match name {
                    "loss_per_cycle" => x + (v * tan).powi(2),
                    _ => x,
                });
            f.std_error = var.filter(|x| x.is_finite() && *x > 0.0).map(f64::sqrt);
        }
    }
}

/// The figures whose standard errors come from evaluations of the shifted
/// candidate ([`Evaluation::spread`]): the others are the candidate's properties
/// (their own σ) and the closed forms β and Fm ([`catalogue`]).
const SIMULATED: [&str; 9] = [
    "voltage",
    "static_stroke",
    "max_stroke",
    "blocked_force",
    "response_time",
    "energy_in",
    "loss_per_cycle",
    "breakdown_margin",
    "pull_in_margin",
];

/// An evaluation with its static stroke–voltage curve (for the report).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Evaluated {
    /// The figures.
    pub evaluation: Evaluation,
    /// Static stroke against voltage from rest to the limit ([`KEPT_POINTS`]).
    pub curve: Vec<CurvePoint>,
}

/// The step-response scene of a design: its actuator scene with the step window's
/// span and samples (the input and the material are set per candidate).
pub fn step_scene(d: &Design) -> Scene {
    let mut s = d.scene.clone();
    let (span, n) = (d.drive.step_span_s, d.drive.step_samples);
    s.time.span = span;
    s.time.samples = (1..=n).map(|i| span * i as f64 / n as f64).collect();
    s
}

/// The active electrode area of the actuator as built (m²; every layer's), the
/// same in words, and the electrode gap as built h(1) (m): the film a breakdown
/// fit is scaled to (weakest link: a breakdown anywhere under field fails the
/// actuator, so the whole active area counts), the same film the scene's own
/// check uses (`Actuator::film_area`, `Actuator::gap`). A stack: nd·π·r0²; a
/// helix: Np·Ne electrode areas of one element at λ = 1 (El Atrache Ceballos (2021) Eq. 4.12).
pub fn electrode_area(a: &Actuator) -> (f64, String, f64) {
    let how = match a {
        Actuator::Stack(s) => format!("{} layers × π·r0²", s.layers),
        Actuator::Helix(h) => format!(
            "{} elements × A_e (El Atrache Ceballos (2021) Eq. 4.12)",
            h.periods * h.per_period
        ),
    };
    (a.film_area(), how, a.gap(1.0))
}

/// The weakest provenance of several inputs (measured < fitted < stated <
/// predicted: a typed value is an assertion, a prediction rests on typed ones).
fn weakest(p: &[Provenance]) -> Provenance {
    let order = |x: &Provenance| match x {
        Provenance::Measured => 0,
        Provenance::Fitted => 1,
        Provenance::Stated => 2,
        Provenance::Predicted => 3,
    };
    *p.iter()
        .max_by_key(|x| order(x))
        .unwrap_or(&Provenance::Measured)
}

/// The catalogue figures of candidate `c` computed from its properties: β = εr/Y
/// and Fm = 3ε0·εr·Eb²/Y (Sommer-Larsen & Larsen 2004, El Atrache Ceballos (2021) §2.6), with their
/// first-order standard errors in closed form from the properties' (independent):
/// (u_β/β)² = (u_ε/εr)² + (u_Y/Y)², (u_Fm/Fm)² = (u_ε/εr)² + (2u_Eb/Eb)² + (u_Y/Y)².
pub fn catalogue(c: &Candidate) -> (Figure, Figure) {
    let v = |f: &Figure| f.value.unwrap_or(f64::NAN);
    let (eps, y, eb) = (v(&c.eps_r), v(&c.youngs_modulus), v(&c.breakdown));
    let rel = |f: &Figure, power: f64| match (f.value, f.std_error) {
        (Some(x), Some(s)) if x != 0.0 => Some(power * s / x),
        _ => None,
    };
    let (re, ry, rb) = (
        rel(&c.eps_r, 1.0),
        rel(&c.youngs_modulus, 1.0),
        rel(&c.breakdown, 2.0),
    );
    // √Σ of the relative parts that exist (none: no σ)
    let combine = |parts: &[Option<f64>]| {
        parts.iter().any(Option::is_some).then(|| {
            parts
                .iter()
                .map(|p| p.unwrap_or(0.0).powi(2))
                .sum::<f64>()
                .sqrt()
        })
    };
    let cat = weakest(&[c.eps_r.provenance, c.youngs_modulus.provenance]);
    let b = eps / y;
    let beta =
        Figure::new(b, "1/Pa", cat, "εr/Y").with_std_error(combine(&[re, ry]).map(|r| r * b));
    let f = 3.0 * EPS0 * eps * eb * eb / y;
    let fm = Figure::new(
        f,
        "1",
        weakest(&[cat, c.breakdown.provenance]),
        "3ε0·εr·Eb²/Y (Sommer-Larsen & Larsen 2004, El Atrache Ceballos (2021) §2.6)",
    )
    .with_std_error(combine(&[re, rb, ry]).map(|r| r * f));
    (beta, fm)
}

/// Evaluate candidate `c` at drive `level` on `template` (from [`step_scene`]);
/// `index` is the point's place in the sweep. Never fails: what could not be
/// computed is a figure without value and the state `failed`, with the reason.
pub fn evaluate(
    template: &Scene,
    scene_name: &str,
    c: &Candidate,
    level: Level,
    index: usize,
) -> Evaluated {
    let v = |f: &Figure| f.value.unwrap_or(f64::NAN);
    let (eps, eb) = (v(&c.eps_r), v(&c.breakdown));
    let (beta, fm) = catalogue(c);
    let sim_src = format!("simulator: {scene_name} with the candidate's constants");
    let mut e = Evaluation {
        index,
        name: c.name.clone(),
        series: c.series.clone(),
        matrix: c.matrix.clone(),
        filler: c.filler.clone(),
        loading: c.loading,
        basis: c.basis,
        volume_fraction: c.volume_fraction,
        rules: c.rules.clone(),
        voltage: Figure::none("V", Provenance::Predicted, "drive", "not evaluated"),
        eps_r: c.eps_r.clone(),
        youngs_modulus: c.youngs_modulus.clone(),
        beta,
        fm,
        tan_delta: c.tan_delta.clone(),
        breakdown_field: c.breakdown.clone(),
        state: State::Failed,
        state_note: String::new(),
        static_stroke: Figure::none("1", Provenance::Predicted, &sim_src, "not evaluated"),
        pull_in: None,
        breakdown: None,
        max_stroke: Figure::none("1", Provenance::Predicted, &sim_src, "not evaluated"),
        max_stroke_limit: Limit::Range,
        blocked_force: Figure::none("N", Provenance::Predicted, &sim_src, "not evaluated"),
        response_time: Figure::none("s", Provenance::Predicted, &sim_src, "not evaluated"),
        energy_in: Figure::none("J", Provenance::Predicted, &sim_src, "not evaluated"),
        loss_per_cycle: Figure::none("J", Provenance::Predicted, &sim_src, "not evaluated"),
        breakdown_margin: Figure::none("1", Provenance::Predicted, &sim_src, "not evaluated"),
        pull_in_margin: Figure::none("1", Provenance::Predicted, &sim_src, "not evaluated"),
        warnings: c.warnings.clone(),
    };
    let mut scene = template.clone();
    let material = match c.hyperelastic.spec.build() {
        Ok(model) => Material {
            spec: c.hyperelastic.spec.clone(),
            model: Arc::from(model),
            params: c.hyperelastic.params.clone(),
            fit: c.hyperelastic.ranges.clone().map(Arc::new),
            viscous: c.viscous.clone(),
            eps_r: eps,
            composite: None,
            density: c.density,
            resistivity: None,
        },
        Err(err) => {
            e.state_note = err.to_string();
            return Evaluated {
                evaluation: e,
                curve: Vec::new(),
            };
        }
    };
    scene.material = material;
    let p = match sim::full_plant(&scene) {
        Ok(p) => p,
        Err(err) => {
            e.state_note = format!("no stable rest state: {err}");
            return Evaluated {
                evaluation: e,
                curve: Vec::new(),
            };
        }
    };
    let a = scene.actuator;
    let lam0 = p.lam0;
    let stroke = |lam: f64| 1.0 - lam / lam0;
    let vd = match level {
        Level::Voltage(x) => x,
        Level::BreakdownFraction(f) => f * eb * a.gap(lam0),
    };
    e.voltage = match level {
        Level::Voltage(_) => Figure::new(vd, "V", Provenance::Stated, "drive voltage"),
        Level::BreakdownFraction(f) => Figure::new(
            vd,
            "V",
            c.breakdown.provenance,
            format!("{} × Eb × gap at rest", short(f)),
        ),
    };

    // The static curve, its peak and where the field reaches Eb on the stable branch.
    let sc = static_curve(&p, CURVE_POINTS, STRETCH_MIN);
    let pull = match sc.search {
        Search::PullIn => sc.pull_in,
        _ => None,
    };
    e.pull_in = pull.map(|q| CurvePoint {
        voltage_v: q.voltage_v,
        stroke: stroke(q.stretch),
    });
    let lam_b = breakdown_point(&p, &sc, eb).map(|q| q.stretch);
    e.breakdown = lam_b.map(|l| CurvePoint {
        voltage_v: voltage_at(&p, l).unwrap_or(f64::NAN),
        stroke: stroke(l),
    });
    let (lam_lim, limit, why) = match (lam_b, pull) {
        (Some(l), _) => (
            l,
            Limit::Breakdown,
            "the field reaches the breakdown field first".to_string(),
        ),
        (None, Some(q)) => (
            q.stretch,
            Limit::PullIn,
            "pull-in comes first (below the breakdown field)".to_string(),
        ),
        (None, None) => (
            STRETCH_MIN,
            Limit::Range,
            format!("neither pull-in nor breakdown down to stretch {STRETCH_MIN}: a lower bound"),
        ),
    };
    e.max_stroke = Figure::new(
        stroke(lam_lim),
        "1",
        Provenance::Predicted,
        format!("static curve; {sim_src}"),
    )
    .noted(why);
    e.max_stroke_limit = limit;
    let curve = (0..KEPT_POINTS)
        .filter_map(|i| {
            let lam = lam0 + (lam_lim - lam0) * i as f64 / (KEPT_POINTS - 1) as f64;
            voltage_at(&p, lam).map(|v| CurvePoint {
                voltage_v: v,
                stroke: stroke(lam),
            })
        })
        .collect();

    // The static state at the drive.
    let (_, dc0, _) = p.capacitance(lam0);
    e.blocked_force = match vd / a.gap(lam0) >= eb {
        true => Figure::none(
            "N",
            Provenance::Predicted,
            &sim_src,
            "the drive field at rest reaches the breakdown field",
        ),
        false => Figure::new(
            -0.5 * vd * vd * dc0 / p.l0,
            "N",
            Provenance::Predicted,
            format!("−½V²·C′(λ0)/L0; {sim_src}"),
        ),
    };
    let lam_d = match pull {
        Some(q) if vd >= q.voltage_v => Err(format!(
            "pulled in: the pull-in voltage {} is at or below the drive {}",
            si(q.voltage_v, "V"),
            si(vd, "V")
        )),
        _ => p.static_stretch(vd, lam0).map_err(|why| match why {
            crate::sim::plant::NoEquilibrium::Unstable => {
                format!("pulled in: no stable equilibrium at {}", si(vd, "V"))
            }
            other => format!("no static equilibrium at {}: {other}", si(vd, "V")),
        }),
    };
    // The margins at the operating point: 1 − V/V_pull-in, and 1 − E/Eb with E
    // the true field at the static equilibrium (at or below 0: reached).
    let margin_src = format!("static curve; {sim_src}");
    e.pull_in_margin = match pull {
        Some(q) => Figure::new(
            1.0 - vd / q.voltage_v,
            "1",
            Provenance::Predicted,
            format!("1 − V/V_pull-in; {margin_src}"),
        ),
        None => Figure::none(
            "1",
            Provenance::Predicted,
            &margin_src,
            format!("no pull-in down to stretch {STRETCH_MIN}"),
        ),
    };
    e.breakdown_margin = match &lam_d {
        Ok(l) => Figure::new(
            1.0 - vd / a.gap(*l) / eb,
            "1",
            Provenance::Predicted,
            format!("1 − E/Eb, E = V/gap at the static stroke; {margin_src}"),
        ),
        Err(why) => Figure::none("1", Provenance::Predicted, &margin_src, why),
    };
    // Pulled in, or no equilibrium, or broken down at the static stroke: the
    // static and dynamic figures have no value, and the reason is the state's note.
    // A drive past the pull-in that meets the breakdown field first on the way up
    // (on the stable branch, below the drive) is labelled by that limit: breakdown.
    let bd_below = e.breakdown.filter(|b| b.voltage_v <= vd);
    let lam_d = lam_d
        .map_err(|why| match (why.starts_with("pulled in"), bd_below) {
            (true, Some(b)) => (
                State::Breakdown,
                format!(
                    "breaks down on the way up: the field reaches Eb = {} at {}, below the drive {}{}",
                    si(eb, "V/m"),
                    si(b.voltage_v, "V"),
                    si(vd, "V"),
                    pull.map_or(String::new(), |q| format!(
                        ", before the pull-in at {}",
                        si(q.voltage_v, "V")
                    ))
                ),
            ),
            (true, None) => (State::PullIn, why),
            (false, _) => (State::Failed, why),
        })
        .and_then(|l| {
            let field_d = vd / a.gap(l);
            match field_d >= eb {
                true => Err((
                    State::Breakdown,
                    format!(
                        "breaks down: the field {} at the static stroke reaches Eb = {}",
                        si(field_d, "V/m"),
                        si(eb, "V/m")
                    ),
                )),
                false => Ok(l),
            }
        });
    let lam_d = match lam_d {
        Ok(l) => l,
        Err((state, why)) => {
            e.state = state;
            e.static_stroke = Figure::none("1", Provenance::Predicted, &sim_src, &why);
            for f in [
                &mut e.response_time,
                &mut e.energy_in,
                &mut e.loss_per_cycle,
            ] {
                f.note = Some(why.clone());
            }
            e.state_note = why;
            return Evaluated {
                evaluation: e,
                curve,
            };
        }
    };
    e.state = State::Ok;
    e.state_note = format!(
        "static stroke at {} below pull-in and breakdown",
        si(vd, "V")
    );
    e.static_stroke = Figure::new(
        stroke(lam_d),
        "1",
        Provenance::Predicted,
        format!("static equilibrium; {sim_src}"),
    );
    let (cd, _, _) = p.capacitance(lam_d);
    let work = 0.5 * cd * vd * vd + sim::elastic_energy(&p, lam0, lam_d)
        - p.f_load * p.l0 * (lam_d - lam0);
    e.energy_in = Figure::new(
        work,
        "J",
        Provenance::Predicted,
        format!("½CV² + ∫(Vol·P − F·L0)dλ to the static stroke; {sim_src}"),
    );
    e.loss_per_cycle = Figure::new(
        PI * cd * (0.5 * vd).powi(2) * v(&c.tan_delta),
        "J",
        weakest(&[c.tan_delta.provenance, Provenance::Predicted]),
        "π·C·(V/2)²·tan δ of a 0–V sine at the drive frequency",
    );

    // The damped step.
    e.response_time = step_response(&mut scene, vd, eb, stroke(lam_d), &sim_src);
    if e.response_time.value.is_none()
        && e.response_time
            .note
            .as_deref()
            .is_some_and(|n| n.starts_with("failed"))
    {
        e.state = State::Failed;
        e.state_note = e.response_time.note.clone().unwrap_or_default();
    }
    Evaluated {
        evaluation: e,
        curve,
    }
}

/// 10–90 % time of the contraction after a step to `vd`, from the simulator.
fn step_response(scene: &mut Scene, vd: f64, eb: f64, static_stroke: f64, src: &str) -> Figure {
    scene.input = Waveform {
        terms: vec![Term::Step {
            at: 0.0,
            amplitude: vd,
        }],
    };
    let none = |why: String| Figure::none("s", Provenance::Predicted, src, why);
    // a whole run, for its extremes over every accepted step (a field peak between
    // samples is in them)
    let tr = match sim::simulate(scene, &RunOptions::default()) {
        Ok(t) => t,
        Err(err) => return none(format!("failed: the simulator refused the step: {err}")),
    };
    match tr.integrator.status {
        RunStatus::Completed => {}
        RunStatus::PullIn => {
            return none(
                "pulls in during the step (its dynamic overshoot passes the pull-in)".into(),
            )
        }
        RunStatus::Failed => return none(format!("failed: {}", tr.integrator.message)),
    }
    let lam0 = tr.rest_stretch;
    let peak_field = tr.extremes().field.field;
    if peak_field >= eb {
        return none(format!(
            "the field reaches Eb during the step ({} at its peak)",
            si(peak_field, "V/m")
        ));
    }
    let c: Vec<(f64, f64)> = tr
        .samples
        .iter()
        .map(|s| (s.time_s, 1.0 - s.stretch / lam0))
        .collect();
    let end = c.last().map_or(0.0, |x| x.1);
    if end <= 0.0 || static_stroke <= 0.0 {
        return none("no contraction at the end of the step window".into());
    }
    let cross = |level: f64| {
        c.windows(2).find_map(|w| {
            let ((t0, y0), (t1, y1)) = (w[0], w[1]);
            (y0 < level && y1 >= level).then(|| t0 + (level - y0) / (y1 - y0) * (t1 - t0))
        })
    };
    match (cross(0.1 * end), cross(0.9 * end)) {
        (Some(t10), Some(t90)) => Figure::new(t90 - t10, "s", Provenance::Predicted, format!("damped step; {src}")).noted(format!(
            "10 % at {} s, 90 % at {} s of the contraction at the window's end, which is {} % of the static stroke",
            short(t10),
            short(t90),
            short(100.0 * end / static_stroke)
        )),
        _ => none("the contraction does not pass 10 % and 90 % of its end value inside the window".into()),
    }
}
