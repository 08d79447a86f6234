//! The simulator's own guards: one table of plausible ranges per physical quantity
//! (with the reason), the check of a whole [`Scene`] against it, and the cost of a
//! run estimated before it starts.
//!
//! The scene reader reports a violation at the offending key (file:line:col);
//! [`check`], called by `sim::simulate`, reports it as a settings error, because a
//! library caller (identification changes parameters thousands of times) builds
//! and changes scenes without the reader. No wall-clock timeout is involved: a
//! run is refused when its *estimated* step count or memory is absurd.
//!
//! Cost estimate (steps of an adaptive method at rtol 10⁻⁶, measured
//! [`STEPS_PER_PERIOD`] ≈ 20 per period resolved, scaled by (10⁻⁶/rtol)^(1/5) for
//! a 5th-order method, at least 4):
//!
//!   steps ≈ max(spp·[f_mode·T_ring + Σ sine periods in the span], span·ω/3.3) + 10·kinks
//!
//! with T_ring = min(span, (kinks + 1)·ln(1/rtol)/(ζ·ω)) the time the axial mode
//! rings after the kinks of the input (an undamped mode rings through the whole
//! span; with ζ ≥ 1 or without inertia it does not ring), span·ω/3.3 the stability
//! limit of an explicit method (the scene's, or `auto`'s for a lightly damped mode),
//! plus 10 steps per restart.
//! Memory: one [`super::Sample`] per output time and one f64 per kink.

use super::fidelity::{self, AxialMode, Fidelity};
use super::integrate::Method;
use super::plant::{NoEquilibrium, Plant};
use super::scene::{Actuator, Scene, Source};
use super::Sample;
use crate::error::{Error, Result};
use crate::material::check::{
    check_hyperelastic, d, ARM_MODULUS, ARM_TIME, DASHPOT, MASS_FRACTION, MODULUS, OGDEN_EXPONENT,
    PERMITTIVITY, SHEAR_MODULUS,
};
// the range type is the material's (`material::check`); the simulator's table holds
// the material's ranges too (TABLE, docs/scenes.md)
pub use crate::material::check::{fmt_g, Domain, Violation};

/// Geometric lengths (radii, layer and element thickness).
pub const LENGTH: Domain = d("length", "m", 1e-7, 10.0, false, "the thinnest elastomer films are ≈ 1 µm and actuators are smaller than metres; outside, a unit is wrong (um for mm?)");
/// Electrode thickness (0: no electrode layer).
pub const ELECTRODE: Domain = d(
    "electrode thickness",
    "m",
    1e-9,
    1.0,
    true,
    "compliant electrodes are 10 nm to 100 µm thick; 0 for none",
);
/// Layer, element and period counts.
pub const COUNT: Domain = d("count", "", 1.0, 1e6, false, "printed stacks reach thousands of layers; the product of helix periods and elements must stay a count");
/// Electrode-layer count (0: not counted in the length).
pub const ELECTRODE_COUNT: Domain = d(
    "electrode count",
    "",
    1.0,
    1e6,
    true,
    "one more than the layers at most, 0 to leave the electrodes out of the length",
);
/// Mass density.
pub const DENSITY: Domain = d(
    "density",
    "kg/m³",
    10.0,
    3e4,
    false,
    "between light foams and the densest metals (osmium 22.6 t/m³)",
);
/// Volume resistivity.
pub const RESISTIVITY: Domain = d(
    "volume resistivity",
    "Ω·m",
    1e3,
    1e22,
    false,
    "a dielectric: below 1e3 Ω·m the layer is a conductor and its leakage time ρε is below 10 ns",
);
/// Actuator mass given explicitly.
pub const ACTUATOR_MASS: Domain = d(
    "actuator mass",
    "kg",
    1e-12,
    1e4,
    false,
    "a microgram film to a ten-tonne machine",
);
/// Hanging load mass.
pub const LOAD_MASS: Domain = d(
    "load mass",
    "kg",
    1e-12,
    1e5,
    true,
    "0 for none; 100 t is beyond any actuator",
);
/// Constant load force (tension positive).
pub const FORCE: Domain = d(
    "force",
    "N",
    -1e7,
    1e7,
    true,
    "10 MN is beyond any elastomer actuator",
);
/// Gravity.
pub const GRAVITY: Domain = d(
    "gravity",
    "m/s²",
    1e-6,
    1e4,
    true,
    "Earth 9.81, 0 for a horizontal set-up, a centrifuge 1e4 at most",
);
/// Effective-mass fraction f.
pub const FRACTION: Domain = d(
    "effective-mass fraction",
    "",
    0.0,
    1.0,
    true,
    "f in m_eff = m_load + f·m_actuator is a share (El Atrache Ceballos (2021) Eq. 3.10: ½)",
);
/// Input and set-point voltages.
pub const VOLTAGE: Domain = d(
    "voltage",
    "V",
    -1e6,
    1e6,
    true,
    "DEAs run below 100 kV; 1 MV is beyond any supply",
);
/// The controller's output limit.
pub const MAX_VOLTAGE: Domain = d(
    "voltage limit",
    "V",
    1e-3,
    1e6,
    false,
    "DEAs run below 100 kV; 1 MV is beyond any supply",
);
/// A closed loop's reference contraction (fraction of the rest length).
pub const CONTRACTION: Domain = d(
    "contraction",
    "",
    -1.0,
    1.0,
    true,
    "a share of the rest length",
);
/// Instants (step time, ramp and term start/end, CSV times).
pub const INSTANT: Domain = d(
    "time",
    "s",
    -1e9,
    1e9,
    true,
    "30 years either side of t = 0",
);
/// The simulated span.
pub const SPAN: Domain = d(
    "time span",
    "s",
    1e-9,
    1e9,
    false,
    "1 ns to 30 years; the step estimate then decides",
);
/// Input frequencies.
pub const FREQUENCY: Domain = d(
    "frequency",
    "Hz",
    1e-9,
    1e9,
    false,
    "1 GHz is beyond any high-voltage drive",
);
/// Number of periods of a triangle or sine.
pub const CYCLES: Domain = d(
    "number of cycles",
    "",
    1e-6,
    1e9,
    false,
    "beyond 1e9 cycles is a slip of the exponent; the kink count and the step estimate then decide",
);
/// Phase of a sine.
pub const PHASE: Domain = d(
    "phase",
    "rad",
    -1e3,
    1e3,
    true,
    "a phase is an angle; beyond ±1000 rad a unit is wrong",
);
/// Output samples.
pub const SAMPLES: Domain = d(
    "sample count",
    "",
    1.0,
    1e6,
    false,
    "a trajectory row is 96 bytes in memory and ≈ 200 in the CSV: 1e6 samples are 100 MB",
);
/// Relative tolerance.
pub const RTOL: Domain = d(
    "relative tolerance",
    "",
    1e-14,
    0.1,
    false,
    "below 1e-14 is below double-precision rounding; above 0.1 nothing is resolved",
);
/// Absolute tolerance (relative to each state's scale).
pub const ATOL: Domain = d(
    "absolute tolerance",
    "",
    1e-20,
    1.0,
    false,
    "relative to each state's scale: 1 would accept any value",
);
/// PID gains (V per unit contraction, ·s or /s).
pub const GAIN: Domain = d(
    "controller gain",
    "",
    1e-12,
    1e12,
    true,
    "gains are volts per unit contraction (loops like El Atrache Ceballos (2021)'s: 1e5–1e7); 1e12 saturates at any error",
);
/// Time constants (derivative filter, supply rise time).
pub const TIME_CONSTANT: Domain = d("time constant", "s", 1e-9, 1e4, false, "1 ns to hours");
/// Source output resistance.
pub const SOURCE_RESISTANCE: Domain =
    d("source resistance", "Ω", 1e-3, 1e15, false, "1 mΩ to 1 PΩ");
/// The loaded rest stretch λ0 (a result, checked before a run).
pub const REST_STRETCH: Domain = d("rest stretch under the load", "", 0.05, 10.0, false, "beyond 10 (or below 0.05) the load is far past what the material can carry and the model is extrapolated without limit");

/// Every domain, in the order of docs/scenes.md's table.
pub const TABLE: [&Domain; 34] = [
    &LENGTH,
    &ELECTRODE,
    &COUNT,
    &ELECTRODE_COUNT,
    &PERMITTIVITY,
    &MASS_FRACTION,
    &DENSITY,
    &RESISTIVITY,
    &ACTUATOR_MASS,
    &LOAD_MASS,
    &FORCE,
    &GRAVITY,
    &FRACTION,
    &VOLTAGE,
    &MAX_VOLTAGE,
    &CONTRACTION,
    &INSTANT,
    &SPAN,
    &FREQUENCY,
    &CYCLES,
    &PHASE,
    &SAMPLES,
    &RTOL,
    &ATOL,
    &GAIN,
    &TIME_CONSTANT,
    &SOURCE_RESISTANCE,
    &MODULUS,
    &SHEAR_MODULUS,
    &OGDEN_EXPONENT,
    &DASHPOT,
    &ARM_MODULUS,
    &ARM_TIME,
    &REST_STRETCH,
];

/// Most kinks (restarts) a run may have; more are refused before anything is listed.
pub const MAX_KINKS: usize = 1_000_000;
/// Most steps a run may take (about 5–10 s of integration at 1–2 µs a step): an
/// estimate above it is refused before the run, and no run is given more (see
/// [`Cost::step_budget`]). The longest shipped scene takes 0.2 M steps.
pub const MAX_STEPS: usize = 5_000_000;
/// Largest memory a run's outputs may take (bytes).
pub const MAX_MEMORY: f64 = 2e9;
/// Steps per resolved period at rtol 10⁻⁶ (Tsit45 on the ringing stack: 196–202 k
/// steps for 10 s at 1.0 kHz, docs/scenes.md).
pub const STEPS_PER_PERIOD: f64 = 20.0;
/// Stability limit h·ω of the explicit 5(4) pairs on the imaginary axis (≈ 3.3
/// for Dormand–Prince and Tsitouras, Hairer & Wanner).
pub const EXPLICIT_STABILITY: f64 = 3.3;
/// Steps for each restart at a kink (a method starts again from first order).
pub const STEPS_PER_RESTART: f64 = 10.0;
/// Dormand–Prince 8(5,3)'s accepted steps per Tsitouras 5(4) step on a run resolved
/// by accuracy, at rtol 10⁻⁶; each method's step scales as rtol^(1/order), so the
/// ratio as rtol^(1/5 − 1/8). Measured at rtol 10⁻⁴ / 10⁻⁶ / 10⁻⁸ (with its PI.4.2
/// controller): the undamped 5 kV stack 0.44 / 0.27 / 0.18, the 100 Hz triangle
/// 0.39 / 0.26 / 0.18 (the rule: 0.38 / 0.27 / 0.19).
pub const DOP853_STEP_RATIO: f64 = 0.27;
/// Dormand–Prince 8(5,3)'s stability limit h·|λ| on the negative real axis (its
/// stability function: 6.4; on the imaginary axis 5.97).
pub const DOP853_STABILITY: f64 = 6.4;
/// The work of a Dormand–Prince 8(5,3) step in Tsitouras steps (twelve right-hand
/// sides and 58 stage terms against six and 21; callgrind on the undamped 5 kV
/// stack: 9.5 k against 4.6 k instructions a step attempt), and what its continuous
/// extension adds in a step with a sample in it (three more stages: 4.0 k).
pub const DOP853_STEP_WORK: f64 = 2.07;
/// See [`DOP853_STEP_WORK`].
pub const DOP853_DENSE_WORK: f64 = 0.87;
/// A run may take this many times its estimated steps before it is stopped: the
/// estimate is measured to within 3× on the ringing scenes and up to 30× low on
/// damped and closed-loop ones (tests/scene_input.rs), so 100× leaves room for
/// every shipped scene and still stops a run whose dynamics the estimate did not
/// foresee (a stiff loop from huge PID gains) in seconds rather than minutes.
pub const STEP_MARGIN: f64 = 100.0;
/// The smallest step budget a run gets (about a second of integration).
pub const MIN_STEP_BUDGET: usize = 1_000_000;

/// Check every quantity of a scene against its domain (no location: the reader
/// maps the key to its line and column).
pub fn validate(s: &Scene) -> std::result::Result<(), Violation> {
    match s.actuator {
        Actuator::Stack(g) => {
            LENGTH.check("actuator.radius", g.radius_m)?;
            LENGTH.check("actuator.layer_thickness", g.layer_m)?;
            ELECTRODE.check("actuator.electrode_thickness", g.electrode_m)?;
            COUNT.check("actuator.layers", g.layers as f64)?;
            ELECTRODE_COUNT.check("actuator.electrodes", g.electrodes as f64)?;
        }
        Actuator::Helix(h) => {
            LENGTH.check("actuator.outer_radius", h.outer_m)?;
            LENGTH.check("actuator.inner_radius", h.inner_m)?;
            LENGTH.check("actuator.thickness", h.thickness_m)?;
            COUNT.check("actuator.periods", h.periods as f64)?;
            COUNT.check("actuator.per_period", h.per_period as f64)?;
            if h.inner_m >= h.outer_m {
                return Err(Violation {
                    key: "actuator.inner_radius".into(),
                    msg: format!(
                        "inner_radius {} m must be smaller than outer_radius {} m",
                        h.inner_m, h.outer_m
                    ),
                    hint: "the helix is an annulus between the two radii".into(),
                });
            }
        }
    }
    let m = &s.material;
    check_hyperelastic(
        m.model.as_ref(),
        &m.params,
        "material.hyperelastic.parameters",
    )?;
    DASHPOT.check("material.viscous.nv", m.viscous.nv_pa_s)?;
    for (i, a) in m.viscous.arms.iter().enumerate() {
        ARM_MODULUS.check(&format!("material.viscous.arms[{i}].k"), a.k_pa)?;
        ARM_TIME.check(
            &format!("material.viscous.arms[{i}].tau"),
            a.eta_pa_s / a.k_pa,
        )?;
    }
    PERMITTIVITY.check("material.relative_permittivity", m.eps_r)?;
    if let Some(c) = &m.composite {
        MASS_FRACTION.check(
            "material.relative_permittivity.mass_fraction",
            c.mass_fraction,
        )?;
    }
    DENSITY.check("material.density", m.density)?;
    if let Some(r) = m.resistivity {
        RESISTIVITY.check("material.resistivity_ohm_m", r)?;
    }
    if let Some(ma) = s.load.actuator_mass_kg {
        ACTUATOR_MASS.check("material.actuator_mass", ma)?;
    }
    LOAD_MASS.check("load.mass", s.load.mass_kg)?;
    FORCE.check("load.force", s.load.force_n)?;
    GRAVITY.check("load.gravity", s.load.gravity)?;
    FRACTION.check("load.effective_mass_fraction", s.load.fraction)?;
    match s.source {
        Source::Ideal => {}
        Source::RiseTime { tau_s } => {
            TIME_CONSTANT.check("source.rise_time", tau_s)?;
        }
        Source::Resistance { ohm } => {
            SOURCE_RESISTANCE.check("source.resistance_ohm", ohm)?;
        }
    }
    let t = &s.time;
    SPAN.check("time.span", t.span)?;
    SAMPLES.check("time.samples", t.samples.len() as f64)?;
    RTOL.check("time.rtol", t.rtol)?;
    ATOL.check("time.atol", t.atol)?;
    if let Some(bad) = t.samples.iter().position(|&x| !(x > 0.0 && x <= t.span)) {
        return Err(Violation {
            key: "time.samples".into(),
            msg: format!(
                "sample time {} s is not in (0, span = {} s]",
                t.samples[bad], t.span
            ),
            hint: "samples are times after the start and up to the span".into(),
        });
    }
    match &s.control {
        Some(pid) => {
            GAIN.check("control.kp", pid.kp)?;
            GAIN.check("control.ki", pid.ki)?;
            GAIN.check("control.kd", pid.kd)?;
            TIME_CONSTANT.check("control.derivative_filter", pid.tau_d)?;
            MAX_VOLTAGE.check("control.max_voltage", pid.v_max)?;
            validate_input(&pid.reference, "control.reference", &CONTRACTION)?;
        }
        None => validate_input(&s.input, "input", &VOLTAGE)?,
    }
    Ok(())
}

/// The shortest input interval (ramp, PWL segment, quarter period) the simulator
/// takes as a change in time rather than a jump: a supply does not slew in under a
/// nanosecond, and an interval of 1e-300 s starts the integrator at a step it never
/// grows out of.
pub const MIN_INTERVAL_S: f64 = 1e-9;

fn validate_input(
    w: &super::input::Waveform,
    sec: &str,
    level: &Domain,
) -> std::result::Result<(), Violation> {
    use super::input::Term;
    for (i, term) in w.terms.iter().enumerate() {
        let k = |name: &str| format!("{sec}[{i}].{name}");
        let scale = term.time_scale();
        if scale > 0.0 && scale < MIN_INTERVAL_S {
            return Err(Violation {
                key: format!("{sec}[{i}]"),
                msg: format!(
                    "an input interval of {} s is shorter than {} s",
                    fmt_g(scale),
                    fmt_g(MIN_INTERVAL_S)
                ),
                hint: "a change faster than a nanosecond is a jump: use kind = \"step\" (and source.rise_time for the supply's slew)".into(),
            });
        }
        match *term {
            Term::Step { at, amplitude } => {
                INSTANT.check(&k("at"), at)?;
                level.check(&k("amplitude"), amplitude)?;
            }
            Term::Ramp {
                start,
                end,
                from,
                to,
            } => {
                INSTANT.check(&k("start"), start)?;
                INSTANT.check(&k("end"), end)?;
                level.check(&k("from"), from)?;
                level.check(&k("to"), to)?;
                if end <= start {
                    return Err(Violation {
                        key: k("end"),
                        msg: format!("end {end} s must be after start {start} s"),
                        hint: "a ramp runs from start to a later end".into(),
                    });
                }
            }
            Term::Triangle {
                start,
                amplitude,
                frequency,
                cycles,
                offset,
            } => {
                INSTANT.check(&k("start"), start)?;
                level.check(&k("amplitude"), amplitude)?;
                FREQUENCY.check(&k("frequency"), frequency)?;
                CYCLES.check(&k("cycles"), cycles)?;
                level.check(&k("offset"), offset)?;
            }
            Term::Sine {
                start,
                amplitude,
                frequency,
                phase,
                offset,
                cycles,
            } => {
                INSTANT.check(&k("start"), start)?;
                level.check(&k("amplitude"), amplitude)?;
                FREQUENCY.check(&k("frequency"), frequency)?;
                PHASE.check(&k("phase_rad"), phase)?;
                level.check(&k("offset"), offset)?;
                if let Some(c) = cycles {
                    CYCLES.check(&k("cycles"), c)?;
                }
            }
            Term::Pwl { ref points } => {
                for (j, &(t, v)) in points.iter().enumerate() {
                    let point = |mut e: Violation| {
                        e.msg = format!("point {}: {}", j + 1, e.msg);
                        e
                    };
                    INSTANT.check(&k("file"), t).map_err(point)?;
                    level.check(&k("file"), v).map_err(point)?;
                }
            }
            Term::Measured(ref m) => {
                let (t0, t1) = m.span();
                INSTANT.check(&k("file"), t0)?;
                INSTANT.check(&k("file"), t1)?;
                for v in m.knot_values() {
                    level.check(&k("file"), v)?;
                }
            }
        }
    }
    Ok(())
}

/// The loaded rest state (stable static equilibrium at 0 V from λ = 1), or why
/// there is none (a load beyond the material, constants outside the model).
pub fn rest_state(s: &Scene) -> std::result::Result<f64, Violation> {
    let arms = vec![true; s.material.viscous.arms.len()];
    let lam0 = Plant::new(s, true, &arms).map_err(rest_violation)?.lam0;
    REST_STRETCH.check("load", lam0).map_err(|mut v| {
        v.msg = format!(
            "the rest stretch under the load is {}: {}",
            fmt_g(lam0),
            REST_STRETCH.reason
        );
        v.hint = REST_HINT.into();
        v
    })
}

/// What to do about a scene without rest state.
const REST_HINT: &str =
    "lower the load (load.mass, load.weight, load.force) or check the hyperelastic constants";

/// No stable rest state, located at the load.
fn rest_violation(why: NoEquilibrium) -> Violation {
    Violation {
        key: "load".into(),
        msg: format!("no stable rest state under the load at 0 V: {why}"),
        hint: REST_HINT.into(),
    }
}

/// The error of a scene whose parameters have no stable rest state (a library
/// caller that changed them after reading, e.g. identification moving θ).
pub fn no_rest_state(s: &Scene, why: NoEquilibrium) -> Error {
    let v = rest_violation(why);
    Error::settings(format!("scene '{}': {}", s.name, v.msg)).with_hint(v.hint)
}

/// The estimated cost of a run, with the fidelity and axial mode it rests on
/// (computed once: `sim::simulate` runs with them).
#[derive(Debug, Clone, PartialEq)]
pub struct Cost {
    /// The fidelity choice ([`fidelity::choose`]).
    pub fidelity: Fidelity,
    /// The axial mode of the full plant.
    pub mode: AxialMode,
    /// Estimated integration steps.
    pub steps: f64,
    /// Estimated memory of the outputs (bytes).
    pub memory: f64,
    /// Kinks (restarts) in the span.
    pub kinks: f64,
    /// Periods of the axial mode that ring (resolved) during the span.
    pub ring_periods: f64,
    /// Periods of smooth periodic input in the span.
    pub input_periods: f64,
    /// Steps an explicit method needs for stability alone (0 for an implicit one).
    pub stability_steps: f64,
    /// Steps the explicit Tsitouras 5(4) would take by estimate, whatever ran: the
    /// larger of its accuracy and stability steps (the Jacobian's spectral radius
    /// where `auto` computed it, else the axial mode), plus the restarts. Where
    /// `auto` chose BDF, a BDF run that takes this many steps stalls
    /// (`sim::simulate` then goes on with Tsitouras).
    pub explicit_steps: f64,
    /// For a scene that names no integrator: the one `auto` chose ([`auto_method`])
    /// and why.
    pub auto: Option<(Method, String)>,
}

impl Cost {
    /// The step budget of the run: [`STEP_MARGIN`] × the estimate, within
    /// [[`MIN_STEP_BUDGET`], [`MAX_STEPS`]].
    pub fn step_budget(&self) -> usize {
        (STEP_MARGIN * self.steps).clamp(MIN_STEP_BUDGET as f64, MAX_STEPS as f64) as usize
    }
}

/// Estimate the cost of a scene's run (see the module documentation).
pub fn estimate(s: &Scene) -> Result<Cost> {
    let span = s.time.span;
    let w = match &s.control {
        Some(pid) => &pid.reference,
        None => &s.input,
    };
    let kinks = w.kink_count(0.0, span);
    let input_periods: f64 = w
        .terms
        .iter()
        .map(|t| match *t {
            super::input::Term::Sine {
                start,
                frequency,
                cycles,
                ..
            } => {
                let active = (span - start.max(0.0)).max(0.0) * frequency;
                cycles.map_or(active, |c| active.min(c))
            }
            _ => 0.0,
        })
        .sum();
    let fid = fidelity::choose(s)?;
    let mode = fid.mode;
    let rtol = s.time.rtol;
    let omega = 2.0 * std::f64::consts::PI * mode.frequency_hz;
    let ring_time = if !fid.inertia || mode.damping_ratio >= 1.0 || !omega.is_finite() {
        0.0
    } else {
        let decay = (1.0 / rtol).ln() / (mode.damping_ratio.max(0.0) * omega);
        span.min((kinks + 1.0) * decay)
    };
    let ring_periods = ring_time * mode.frequency_hz;
    let spp = (STEPS_PER_PERIOD * (1e-6 / rtol).powf(0.2)).max(4.0);
    let accuracy = spp * (ring_periods + input_periods);
    // auto's choice from the stiffness of the plant that runs (`sim::simulate`
    // runs with it)
    let (method, auto, rho) = match s.time.method {
        Some(m) => (m, None, 0.0),
        None => {
            let plant =
                Plant::new(s, fid.inertia, &fid.keep).map_err(|why| no_rest_state(s, why))?;
            let k = stiffness(&plant);
            let (m, why) = auto_method(
                span * k.radius / EXPLICIT_STABILITY,
                span * k.light / BDF_LIGHT_STEP,
                accuracy,
                kinks,
                rtol,
                s.time.samples.len() as f64,
                mode.damping_ratio,
            );
            (m, Some((m, why)), k.radius)
        }
    };
    // an explicit method cannot step past its stability limit h·|λ| ≈ 3.3 (the
    // axial mode's ω, or the Jacobian's fastest rate where known) even after the
    // ringing has died away
    let fastest = match fid.inertia && omega.is_finite() {
        true => omega.max(rho),
        false => rho,
    };
    // Dormand–Prince 8(5,3) takes a share of Tsitouras's accuracy steps, and its
    // stability limit is 6.4
    let (method_accuracy, stability) = match method {
        Method::Dop853 => (
            accuracy * dop853_step_ratio(rtol),
            span * fastest / DOP853_STABILITY,
        ),
        m if !m.implicit() => (accuracy, span * fastest / EXPLICIT_STABILITY),
        _ => (accuracy, 0.0),
    };
    let steps = method_accuracy.max(stability) + STEPS_PER_RESTART * kinks;
    let explicit_steps =
        accuracy.max(span * fastest / EXPLICIT_STABILITY) + STEPS_PER_RESTART * kinks;
    let memory =
        (s.time.samples.len() as f64 + 2.0) * std::mem::size_of::<Sample>() as f64 + 8.0 * kinks;
    Ok(Cost {
        fidelity: fid,
        mode,
        steps,
        memory,
        kinks,
        ring_periods,
        input_periods,
        stability_steps: stability,
        explicit_steps,
        auto,
    })
}

/// The stiffness of a plant (see [`stiffness`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffness {
    /// Spectral radius ρ of the Jacobian (1/s).
    pub radius: f64,
    /// Largest |λ| of its lightly damped oscillatory eigenvalues, |Re λ| <
    /// [`LIGHT`]·|λ| (1/s; 0 without one).
    pub light: f64,
}

/// An eigenvalue with |Re λ| below this fraction of |λ| (damping ratio < 0.07,
/// within 4° of the imaginary axis) lies outside the A(α) sector of BDF orders ≥ 3
/// (α = 86° for BDF3, 52° for BDF5; Hairer & Wanner II, §V.2): BDF must resolve it.
pub const LIGHT: f64 = 0.07;
/// The step BDF holds on a lightly damped eigenvalue, h·|λ| (measured: the
/// undamped 4 kV stack over 10⁴ s, 4.77 M steps for the first 214 s at 6340 s⁻¹,
/// long after the ringing had decayed).
pub const BDF_LIGHT_STEP: f64 = 0.3;

/// Iterations the Schur decomposition of [`stiffness`] may take (a few per
/// eigenvalue converge on the plant's Jacobians of at most a dozen states).
const SCHUR_ITERATIONS: usize = 1000;

/// The stiffness of a plant from the eigenvalues of its Jacobian ∂f/∂y at the
/// start state: the spectral radius ρ, the fastest rate of the linearised plant,
/// decaying (a dashpot-damped mode, a source's RC, a controller) or oscillating
/// (the axial mode), which bounds an explicit step by h·ρ ≲ 3.3 however smooth the
/// solution (Hairer & Wanner II, §IV.2); and the fastest lightly damped
/// oscillation, which bounds a BDF step too.
pub fn stiffness(p: &Plant) -> Stiffness {
    let y = p.initial_state();
    let n = y.len();
    let mut jac = vec![0.0; n * n];
    p.jacobian(0.0, &y, &mut jac);
    let m = nalgebra::DMatrix::from_row_slice(n, n, &jac);
    // The Schur iteration never converges on a non-finite matrix (ρ is then
    // unbounded) and need not on a finite one: there the row-sum norm, which
    // bounds every |λ|, stands for ρ.
    if !m.iter().all(|v| v.is_finite()) {
        return Stiffness {
            radius: f64::INFINITY,
            light: 0.0,
        };
    }
    let Some(schur) = nalgebra::Schur::try_new(m.clone(), f64::EPSILON, SCHUR_ITERATIONS) else {
        return Stiffness {
            radius: m.row_iter().map(|r| r.abs().sum()).fold(0.0, f64::max),
            light: 0.0,
        };
    };
    let ev = schur.complex_eigenvalues();
    let finite = ev.iter().filter(|l| l.norm().is_finite());
    Stiffness {
        radius: finite.clone().map(|l| l.norm()).fold(0.0, f64::max),
        light: finite
            .filter(|l| l.im != 0.0 && l.re.abs() < LIGHT * l.norm())
            .map(|l| l.norm())
            .fold(0.0, f64::max),
    }
}

/// The steps a BDF run takes whatever the dynamics (its start from first order, the
/// slow arms), in explicit steps of the same cost: below it an explicit method wins
/// even where stability bounds its step. Calibrated with `dea-fit bench
/// integrators` (reports/bench-integrators): on the shipped scenes and the 5 kV
/// stack at ζ = 10⁻⁴…10 the cheaper method is the explicit one exactly where its
/// stability steps stay below its accuracy steps plus this floor (hdea_step_10N:
/// 303 against 411, Tsitouras 1.6× faster; the stack at ζ = 0.1 over 1 s: 1921
/// against 890, BDF 2.7× faster).
const IMPLICIT_FLOOR: f64 = 300.0;
/// The integrator `auto` chooses, with the reason: an explicit method when the
/// steps its stability needs (`stiff_steps` = span·ρ/3.3, ρ the [`stiffness`]) do
/// not exceed what accuracy needs anyway (`accuracy_steps`: the ringing and the
/// input's periods, plus the restarts at `kinks`) by more than [`IMPLICIT_FLOOR`],
/// or those BDF needs to hold a lightly damped oscillation stable (`bdf_steps` =
/// span·|λ|/0.3); the variable-order BDF otherwise. A lightly damped oscillation
/// rings through the span and bounds both methods (explicit steps are cheaper); a
/// damped or stiff plant (dashpot, controller, source RC) holds an explicit method
/// at its stability limit long after the motion is smooth, and BDF strides on. The
/// explicit method is Tsitouras 5(4), or Dormand–Prince 8(5,3) where the axial
/// mode is lightly damped (ζ < [`LIGHT`]: it rings for many periods, which its
/// 8th order resolves in a third of the steps) and [`explicit_work`] at the run's
/// `rtol` and `samples` finds it cheaper. On more strongly damped ringing its steps
/// fall less than the estimate (the HDEA ramps at ζ = 0.10–0.17: 0.53–0.60 of
/// Tsitouras's, for twice the work a step; `dea-fit bench integrators`).
#[allow(clippy::too_many_arguments)]
pub fn auto_method(
    stiff_steps: f64,
    bdf_steps: f64,
    accuracy_steps: f64,
    kinks: f64,
    rtol: f64,
    samples: f64,
    damping_ratio: f64,
) -> (Method, String) {
    let accuracy = accuracy_steps + STEPS_PER_RESTART * kinks;
    let explicit = stiff_steps <= accuracy + IMPLICIT_FLOOR || stiff_steps <= bdf_steps;
    let (m, what) = match explicit {
        false => (Method::Bdf, "variable-order BDF".to_string()),
        true => {
            let (tsit, dop) = explicit_work(stiff_steps, accuracy, rtol, samples);
            match damping_ratio < LIGHT && dop < tsit {
                true => (
                    Method::Dop853,
                    format!(
                        "explicit Dormand–Prince 8(5,3) (the work of ≈ {} Tsitouras steps)",
                        fmt_g(dop.round())
                    ),
                ),
                false => (Method::Tsit45, "explicit Tsitouras 5(4)".to_string()),
            }
        }
    };
    (
        m,
        format!(
            "auto: stability needs ≈ {} explicit steps (BDF: {}), accuracy ≈ {}: {what}",
            fmt_g(stiff_steps.round()),
            fmt_g(bdf_steps.round()),
            fmt_g(accuracy.round())
        ),
    )
}

/// Dormand–Prince 8(5,3)'s accuracy steps per Tsitouras 5(4) step at `rtol`:
/// [`DOP853_STEP_RATIO`]·(rtol/10⁻⁶)^(1/5 − 1/8).
pub fn dop853_step_ratio(rtol: f64) -> f64 {
    DOP853_STEP_RATIO * (rtol / 1e-6).powf(1.0 / 5.0 - 1.0 / 8.0)
}

/// The work of the two explicit methods in Tsitouras steps, (Tsitouras 5(4),
/// Dormand–Prince 8(5,3)), from the steps Tsitouras needs for stability and for
/// accuracy at `rtol`, with `samples` output times: Dormand–Prince takes
/// [`DOP853_STEP_RATIO`]·(rtol/10⁻⁶)^(1/5 − 1/8) of the accuracy steps, or its
/// stability limit's (3.3/6.4 of Tsitouras's), each of [`DOP853_STEP_WORK`], plus
/// [`DOP853_DENSE_WORK`] in every step with a sample. It wins on long runs resolved
/// by accuracy at tight tolerances (a lightly damped mode ringing for thousands of
/// periods); Tsitouras on runs held at the stability limit and at loose tolerances.
pub fn explicit_work(stiff_steps: f64, accuracy: f64, rtol: f64, samples: f64) -> (f64, f64) {
    let tsit = accuracy.max(stiff_steps);
    let steps = (accuracy * dop853_step_ratio(rtol))
        .max(stiff_steps * EXPLICIT_STABILITY / DOP853_STABILITY);
    let dense = match steps > 0.0 {
        true => (samples / steps).min(1.0),
        false => 0.0,
    };
    (tsit, steps * (DOP853_STEP_WORK + DOP853_DENSE_WORK * dense))
}

/// The guard `sim::simulate` runs first: every quantity in its domain, a stable
/// rest state under the load, and an estimated cost within the budgets.
pub fn check(s: &Scene) -> Result<Cost> {
    validate(s).map_err(|v| {
        Error::settings(format!("scene '{}': {}: {}", s.name, v.key, v.msg)).with_hint(v.hint)
    })?;
    rest_state(s)
        .map_err(|v| Error::settings(format!("scene '{}': {}", s.name, v.msg)).with_hint(v.hint))?;
    let c = estimate(s)?;
    let refuse = |msg: String, hint: &str| {
        Err(Error::settings(format!("scene '{}': {msg}", s.name)).with_hint(hint.to_string()))
    };
    if c.kinks > MAX_KINKS as f64 {
        return refuse(
            format!(
                "the input has {} kinks (restarts) in the span, more than {MAX_KINKS}",
                fmt_g(c.kinks)
            ),
            "fewer cycles, a lower frequency or a shorter time.span",
        );
    }
    if c.memory > MAX_MEMORY {
        return refuse(
            format!(
                "the outputs would take about {} bytes, more than {}",
                fmt_g(c.memory),
                fmt_g(MAX_MEMORY)
            ),
            "ask for fewer time.samples",
        );
    }
    if c.steps > MAX_STEPS as f64 {
        let mode = c.mode;
        let why = if c.stability_steps >= c.steps / 2.0 {
            format!(
                "span {} s is {} periods of the {:.0} Hz axial mode, which an explicit method must resolve for stability",
                fmt_g(s.time.span),
                fmt_g(s.time.span * mode.frequency_hz),
                mode.frequency_hz
            )
        } else if c.ring_periods >= c.input_periods
            && c.ring_periods * STEPS_PER_PERIOD >= STEPS_PER_RESTART * c.kinks
        {
            format!(
                "span {} s rings through {} periods of the {:.0} Hz axial mode (ζ = {:.1e})",
                fmt_g(s.time.span),
                fmt_g(c.ring_periods),
                mode.frequency_hz,
                mode.damping_ratio
            )
        } else if c.input_periods >= c.kinks {
            format!(
                "span {} s holds {} periods of the input sine",
                fmt_g(s.time.span),
                fmt_g(c.input_periods)
            )
        } else {
            format!(
                "span {} s holds {} input kinks, each a restart",
                fmt_g(s.time.span),
                fmt_g(c.kinks)
            )
        };
        return refuse(
            format!(
                "{why}: about {} steps, more than the budget of {}",
                fmt_g(c.steps),
                fmt_g(MAX_STEPS as f64)
            ),
            "shorten time.span, add damping (material.viscous) or lower the input frequency",
        );
    }
    Ok(c)
}
