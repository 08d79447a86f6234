//! Derivatives of the plant (Jacobian, parameter Jacobian, initial-state sensitivity)
//! against finite differences, and the quasi-static model without dashpot
//! (index-reduced force balance): constraint kept, energy balanced, limit of a
//! vanishing dashpot, static curve tracked, pull-in.
//!
//! Finite differences: 4th-order central (5-point) with a step of 10⁻⁴ of each
//! state's magnitude (small enough to stay inside the PID's branches) and 10⁻³ of
//! each parameter's (θ enters smoothly; the rest stretch λ0, a Newton solution, adds
//! rounding noise that a smaller step would amplify), so truncation is ≈ 10⁻¹²
//! and rounding ≈ 10⁻¹² of a row's scale (the largest of its entries times its column's magnitude, and
//! |f_i|: the right-hand side's terms cancel, so its rounding is relative to them).
//! Two measures, both asserted and printed (`--nocapture`):
//! * *significant entries*: the plain relative error |J − J_fd|/|J_fd| of the
//!   entries ≥ 10⁻³ of their row, < 10⁻⁶ (the helix's C''' is itself a difference,
//!   good to ≈ 10⁻⁷; everything else is exact up to the differences' ≈ 10⁻¹⁰);
//! * *all entries*: |J − J_fd|/(|J_fd| + floor), the floor being 10⁻⁵ of the row's
//!   scale over the column's magnitude, < 10⁻⁵: entries too small to matter are
//!   compared absolutely, at 10⁻¹⁰ of their row, above the differences' rounding.

use dea_fit::sim::integrate::{Method, System};
use dea_fit::sim::plant::{Plant, EPS0};
use dea_fit::sim::scene::{Scene, Source};
use dea_fit::sim::{simulate, static_curve, RunOptions, RunStatus};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

fn scene(text: &str) -> Scene {
    Scene::parse(text, Path::new("test.toml")).expect("valid scene")
}

const YEOH: &str = r#"{ preset = "vhb4910-yeoh" }"#;
const OGDEN2: &str = r#"{ model = "ogden2", parameters = { mu1 = "60 kPa", alpha1 = 1.8, mu2 = "-2 kPa", alpha2 = -2.5 } }"#;
const GENT: &str = r#"{ model = "gent", parameters = { mu = "70 kPa", Jm = 40 } }"#;
const TABLE_3_3: &str = r#"{ preset = "elatrache2021-table-3.3" }"#;
const TABLE_4_2: &str = r#"{ preset = "elatrache2021-table-4.2" }"#;
const RISE: &str = "[source]\nrise_time = \"1 ms\"";
const RES: &str = "[source]\nresistance_ohm = 1e7";
const SINE: &str = "[[input]]\nkind = \"sine\"\namplitude = \"1.5 kV\"\noffset = \"1.5 kV\"\nfrequency = \"2 Hz\"\nphase_rad = -1.5707963267948966";
const RAMP: &str = "[[input]]\nkind = \"ramp\"\nstart = 0\nend = \"1 s\"\nto = \"3 kV\"";
const PID: &str = "[control]\nkind = \"pid\"\nkp = 5e5\nki = 1e7\nkd = 50\nderivative_filter = \"1 ms\"\nmax_voltage = \"8 kV\"\n[[control.reference]]\nkind = \"triangle\"\namplitude = \"1 %\"\nfrequency = \"1 Hz\"\ncycles = 5";

/// The seed's stack (Table 3.1) with leakage and a 50 g load (so λ0 ≠ 1), 1 s.
fn stack(model: &str, viscous: &str, source: &str, drive: &str) -> Scene {
    stack_timed(model, viscous, source, drive, "")
}

fn stack_timed(model: &str, viscous: &str, source: &str, drive: &str, time: &str) -> Scene {
    scene(&format!(
        r#"
{actuator}[material]
hyperelastic = {model}
viscous = {viscous}
relative_permittivity = 4.7
density = "960 kg/m3"
resistivity_ohm_m = 3.1e8
[load]
mass = "0.05 kg"
{source}
{drive}
[time]
span = "1 s"
{time}
"#,
        actuator = super::support::SEED_STACK_ACTUATOR
    ))
}

/// The seed's HDEA (Table 4.1) with a 10 N weight.
fn helix(lateral: &str, viscous: &str, source: &str, drive: &str) -> Scene {
    scene(&format!(
        r#"
[actuator]
kind = "helix"
outer_radius = "30 mm"
inner_radius = "10 mm"
thickness = "1 mm"
periods = 50
per_period = 2
lateral = "{lateral}"
[material]
hyperelastic = {YEOH}
viscous = {viscous}
relative_permittivity = 4.7
density = "960 kg/m3"
actuator_mass = "0.2413 kg"
resistivity_ohm_m = 3.1e8
[load]
weight = "10 N"
{source}
{drive}
[time]
span = "1 s"
"#
    ))
}

/// One Neo-Hookean layer (μ = 100 kPa, H = 1 mm), no load (tests/sim.rs).
fn nh_layer(viscous: &str, input: &str, time: &str) -> Scene {
    scene(&super::sim::nh_layer(viscous, input, time))
}

/// Closed-form Neo-Hookean pull-in of `nh_layer`: (λc, Vc) (Zhao & Suo 2007).
fn nh_pull_in() -> (f64, f64) {
    let lc = 4f64.powf(-1.0 / 3.0);
    (
        lc,
        1e-3 * (1e5 / (4.0 * EPS0)).sqrt() * (lc - lc.powi(4)).sqrt(),
    )
}

fn plant(s: &Scene, inertia: bool) -> Plant {
    Plant::new(s, inertia, &vec![true; s.material.viscous.arms.len()]).unwrap()
}

/// Arms 3 and 4 of Table 3.3 (τ = 32 s, 216 s ≥ the 1 s span) frozen.
fn frozen(s: &Scene, inertia: bool) -> Plant {
    let p = Plant::new(s, inertia, &[true, true, false, false]).unwrap();
    assert!(p.frozen_k > 0.0 && p.arms.len() == 2);
    p
}

fn rhs(p: &Plant, t: f64, y: &[f64]) -> Vec<f64> {
    let mut dy = vec![0.0; y.len()];
    p.rhs(t, y, &mut dy);
    dy
}

/// A state near rest: λ = λ0·(1 + shift ± noise), velocity, arm stresses, source
/// voltage about `v_nom`, controller states about the current error, quadratures.
fn near_rest(
    p: &Plant,
    rng: &mut ChaCha8Rng,
    t: f64,
    v_nom: f64,
    shift: f64,
    noise: f64,
) -> Vec<f64> {
    let l = p.layout();
    let mut u = || 2.0 * rng.gen::<f64>() - 1.0;
    let mut y = p.initial_state();
    y[0] = p.lam0 * (1.0 + shift + noise * u());
    if let Some(i) = l.v {
        y[i] = 2.0 * u();
    }
    for (j, &(k, _)) in p.arms.iter().enumerate() {
        y[l.sig + j] = 0.02 * k * u();
    }
    if let Some(i) = l.src {
        let v = v_nom * (1.0 + 0.2 * u());
        y[i] = match p.source {
            Source::Resistance { .. } => v * p.capacitance(y[0]).0,
            _ => v,
        };
    }
    if let (Some(i), Some(pid)) = (l.ctl, &p.control) {
        let e = pid.reference.eval(t).0 - p.sensed_contraction(y[0]);
        y[i] = 1e-4 * (1.0 + 0.2 * u());
        y[i + 1] = e + 1e-4 * u();
    }
    for q in l.quad..l.n {
        y[q] = u();
    }
    y
}

/// Largest entry-wise relative error of `a` against `b` (n×m row-major) with the
/// floor of the module documentation (`f`: each row's own magnitude), and where
/// (row, column, a, b); also the plain relative error over the significant entries
/// (≥ 1e-3 of their row). Columns flagged in `skip` are not compared.
fn max_rel_err(a: &[f64], b: &[f64], m: usize, col: &[f64], f: &[f64], skip: &[bool]) -> Worst {
    let mut w = Worst::default();
    for (i, (ra, rb)) in a.chunks(m).zip(b.chunks(m)).enumerate() {
        let row = (0..m)
            .filter(|&k| !skip[k])
            .map(|k| rb[k].abs() * col[k])
            .fold(f[i].abs(), f64::max);
        for k in (0..m).filter(|&k| !skip[k]) {
            let d = (ra[k] - rb[k]).abs();
            if d == 0.0 {
                continue;
            }
            if rb[k].abs() * col[k] >= 1e-3 * row {
                w.significant = w.significant.max(d / rb[k].abs());
            }
            let e = d / (rb[k].abs() + 1e-5 * row / col[k]);
            if e > w.err || e.is_nan() {
                w.err = e;
                w.at = (i, k, ra[k], rb[k]);
            }
        }
    }
    w
}

/// A comparison's largest error (with the floor), where, and the largest plain
/// relative error of the significant entries.
#[derive(Debug, Default, Clone, Copy)]
struct Worst {
    err: f64,
    at: (usize, usize, f64, f64),
    significant: f64,
}

impl Worst {
    fn max(self, o: Worst) -> Worst {
        let significant = self.significant.max(o.significant);
        let mut w = if o.err > self.err || o.err.is_nan() {
            o
        } else {
            self
        };
        w.significant = significant;
        w
    }
}

/// Magnitude of each state at y (step and column scale of the differences): the
/// plant's scales, 1e-3 (0.1 % contraction) for the controller states.
fn state_scale(p: &Plant, y: &[f64]) -> Vec<f64> {
    let mut s = p.scales(3e3);
    if let Some(i) = p.layout().ctl {
        s[i] = 1e-3;
        s[i + 1] = 1e-3;
    }
    s.iter().zip(y).map(|(s, v)| s.max(v.abs())).collect()
}

/// 4th-order central difference of a vector function along one variable, step h.
fn fd5(h: f64, f: impl Fn(f64) -> Vec<f64>) -> Vec<f64> {
    let (m2, m1, p1, p2) = (f(-2.0 * h), f(-h), f(h), f(2.0 * h));
    (0..m1.len())
        .map(|i| (8.0 * (p1[i] - m1[i]) - (p2[i] - m2[i])) / (12.0 * h))
        .collect()
}

/// Write column k of an n×m matrix.
fn set_col(j: &mut [f64], m: usize, k: usize, col: &[f64]) {
    for (i, v) in col.iter().enumerate() {
        j[i * m + k] = *v;
    }
}

fn fd_jacobian(p: &Plant, t: f64, y: &[f64], s: &[f64]) -> Vec<f64> {
    let n = y.len();
    let mut j = vec![0.0; n * n];
    for k in 0..n {
        let col = fd5(1e-4 * s[k], |d| {
            let mut yd = y.to_vec();
            yd[k] += d;
            rhs(p, t, &yd)
        });
        set_col(&mut j, n, k, &col);
    }
    j
}

/// θ magnitudes (1 Pa·s for a zero Nv).
fn theta_scale(th: &[f64]) -> Vec<f64> {
    th.iter()
        .map(|v| if *v == 0.0 { 1.0 } else { v.abs() })
        .collect()
}

/// Columns of θ not compared: Nv of a quasi-static plant without dashpot (its rate
/// is not differentiable in Nv at 0: Nv > 0 is a different model).
fn skip_nv(p: &Plant) -> Vec<bool> {
    let m = p.n_theta();
    (0..m)
        .map(|k| k == m - 2 && !p.inertia && p.nv == 0.0)
        .collect()
}

/// A function of the plant differenced along each θk through `with_theta`.
fn fd_theta(p: &Plant, f: impl Fn(&Plant) -> Vec<f64>) -> Vec<f64> {
    let th = p.theta();
    let (m, s) = (th.len(), theta_scale(&th));
    let n = f(p).len();
    let mut j = vec![0.0; n * m];
    for k in 0..m {
        let col = fd5(1e-3 * s[k], |d| {
            let mut td = th.clone();
            td[k] += d;
            f(&p.with_theta(&td).unwrap())
        });
        set_col(&mut j, m, k, &col);
    }
    j
}

/// A plant, the time and the states to check it at.
struct Case {
    name: &'static str,
    plant: Plant,
    t: f64,
    states: Vec<Vec<f64>>,
}

fn case(name: &'static str, plant: Plant, t: f64, v_nom: f64, shift: f64, noise: f64) -> Case {
    let mut rng = ChaCha8Rng::seed_from_u64(name.len() as u64 * 7919 + 17);
    let states = (0..3)
        .map(|_| near_rest(&plant, &mut rng, t, v_nom, shift, noise))
        .collect();
    Case {
        name,
        plant,
        t,
        states,
    }
}

/// An ideal source under PID (the scene format refuses it; the plant supports it).
fn ideal_pid(s: &Scene, inertia: bool) -> Plant {
    let mut p = plant(s, inertia);
    p.source = Source::Ideal;
    p
}

/// The neo-Hookean layer past its pull-in under a quasi-static ramp: the
/// denominator of λ̇ is at its floor.
fn past_pull_in() -> Case {
    let (_, vc) = nh_pull_in();
    let s = nh_layer(
        "{ arms = [ { k = \"20 kPa\", tau = \"1 s\" } ] }",
        &format!(
            "[[input]]\nkind = \"ramp\"\nstart = 0\nend = \"120 s\"\nto = {}",
            1.2 * vc
        ),
        "span = \"120 s\"\nfidelity = \"quasi-static\"",
    );
    let p = plant(&s, false);
    let (t, lam) = (100.0, 0.6);
    let mut y = p.initial_state();
    y[0] = lam;
    y[1] = 50.0;
    assert!(p.instant_stiffness(lam, vc) < 0.0);
    Case {
        name: "NH layer past pull-in, quasi-static without dashpot (floor active)",
        plant: p,
        t,
        states: vec![y],
    }
}

fn cases() -> Vec<Case> {
    let pid_t = 0.3; // reference 0.6 %: active for a contraction ≈ 0.3 %
    vec![
        case(
            "stack dynamic, ideal, 4 arms",
            plant(&stack(YEOH, TABLE_3_3, "", SINE), true),
            0.3,
            0.0,
            0.0,
            0.01,
        ),
        case(
            "stack dynamic, rise time, frozen springs",
            frozen(&stack(YEOH, TABLE_3_3, RISE, SINE), true),
            0.3,
            2e3,
            0.0,
            0.01,
        ),
        case(
            "stack dynamic, resistance, Nv",
            plant(&stack(GENT, TABLE_4_2, RES, SINE), true),
            0.3,
            2e3,
            0.0,
            0.01,
        ),
        case(
            "stack dynamic, PID (active), rise time",
            plant(&stack(YEOH, TABLE_4_2, RISE, PID), true),
            pid_t,
            2e3,
            -0.003,
            5e-4,
        ),
        case(
            "stack dynamic, PID clamped at V_max",
            plant(&stack(YEOH, TABLE_4_2, RISE, PID), true),
            pid_t,
            2e3,
            0.02,
            5e-4,
        ),
        case(
            "stack dynamic, PID clamped at 0",
            plant(&stack(YEOH, TABLE_4_2, RISE, PID), true),
            pid_t,
            2e3,
            -0.03,
            5e-4,
        ),
        case(
            "stack dynamic, PID, resistance",
            plant(&stack(YEOH, TABLE_4_2, RES, PID), true),
            pid_t,
            2e3,
            -0.003,
            5e-4,
        ),
        case(
            "stack dynamic, PID, ideal",
            ideal_pid(&stack(YEOH, TABLE_4_2, RISE, PID), true),
            pid_t,
            2e3,
            -0.003,
            5e-4,
        ),
        case(
            "helix planar dynamic, rise time",
            plant(&helix("planar", TABLE_4_2, RISE, SINE), true),
            0.3,
            2e4,
            0.0,
            0.01,
        ),
        case(
            "helix free dynamic, resistance",
            plant(&helix("free", TABLE_3_3, RES, SINE), true),
            0.3,
            2e4,
            0.0,
            0.01,
        ),
        case(
            "stack quasi-static with dashpot, rise time",
            plant(&stack(OGDEN2, TABLE_4_2, RISE, SINE), false),
            0.3,
            2e3,
            0.0,
            0.01,
        ),
        case(
            "stack quasi-static with dashpot, frozen springs",
            frozen(&stack(YEOH, TABLE_4_2, "", RAMP), false),
            0.5,
            0.0,
            0.0,
            0.01,
        ),
        case(
            "stack quasi-static without dashpot, ideal ramp",
            plant(&stack(YEOH, TABLE_3_3, "", RAMP), false),
            0.5,
            0.0,
            0.0,
            0.01,
        ),
        case(
            "stack quasi-static without dashpot, rise time, frozen springs",
            frozen(&stack(OGDEN2, TABLE_3_3, RISE, SINE), false),
            0.3,
            2e3,
            0.0,
            0.01,
        ),
        case(
            "stack quasi-static without dashpot, resistance",
            plant(&stack(GENT, TABLE_3_3, RES, SINE), false),
            0.3,
            2e3,
            0.0,
            0.01,
        ),
        case(
            "stack quasi-static without dashpot, PID, rise time",
            plant(&stack(YEOH, TABLE_3_3, RISE, PID), false),
            pid_t,
            2e3,
            -0.003,
            5e-4,
        ),
        case(
            "stack quasi-static without dashpot, PID, ideal",
            ideal_pid(&stack(YEOH, TABLE_3_3, RISE, PID), false),
            pid_t,
            2e3,
            -0.003,
            5e-4,
        ),
        case(
            "helix planar quasi-static without dashpot, ideal ramp",
            plant(&helix("planar", TABLE_3_3, "", RAMP), false),
            0.5,
            0.0,
            0.0,
            0.01,
        ),
        case(
            "helix free quasi-static without dashpot, resistance",
            plant(&helix("free", TABLE_3_3, RES, SINE), false),
            0.3,
            2e4,
            0.0,
            0.01,
        ),
        past_pull_in(),
    ]
}

#[test]
fn jacobian_matches_finite_differences() {
    // Tolerances: module documentation.
    let mut all = Worst::default();
    for c in cases() {
        let p = &c.plant;
        let n = p.layout().n;
        let mut worst = Worst::default();
        for y in &c.states {
            let mut jac = vec![f64::NAN; n * n];
            p.jacobian(c.t, y, &mut jac);
            // J·v in one directional evaluation is the same linear map (to rounding)
            let v: Vec<f64> = (0..n).map(|i| (i as f64 + 1.0).sin()).collect();
            let mut jv = vec![f64::NAN; n];
            p.jacobian_times(c.t, y, &v, &mut jv);
            for i in 0..n {
                let row: f64 = (0..n).map(|k| jac[i * n + k] * v[k]).sum();
                let mag: f64 = (0..n).map(|k| (jac[i * n + k] * v[k]).abs()).sum();
                assert!(
                    (jv[i] - row).abs() <= 1e-12 * mag.max(1e-300),
                    "{}: J·v row {i}: {} vs {row}",
                    c.name,
                    jv[i]
                );
            }
            let s = state_scale(p, y);
            let fd = fd_jacobian(p, c.t, y, &s);
            let f = rhs(p, c.t, y);
            worst = worst.max(max_rel_err(&jac, &fd, n, &s, &f, &vec![false; n]));
        }
        eprintln!(
            "jacobian   {:<68} {:.1e} (significant entries {:.1e})",
            c.name, worst.err, worst.significant
        );
        assert!(
            worst.significant < 1e-6 && worst.err < 1e-5,
            "{}: {worst:?}",
            c.name
        );
        all = all.max(worst);
    }
    eprintln!(
        "jacobian: worst over all plants {:.1e} (significant entries {:.1e})",
        all.err, all.significant
    );
}

#[test]
fn param_jacobian_matches_finite_differences_through_with_theta() {
    // Tolerances: module documentation; λ0 (a Newton solve, converged to rounding)
    // enters the differences through λf and C_rest.
    let mut all = Worst::default();
    for c in cases() {
        let p = &c.plant;
        let (n, m) = (p.layout().n, p.n_theta());
        assert_eq!(p.sensitivity_params().len(), m);
        let skip = skip_nv(p);
        let col = theta_scale(&p.theta());
        let mut worst = Worst::default();
        for y in &c.states {
            let mut dfdp = vec![f64::NAN; n * m];
            p.param_jacobian(c.t, y, &mut dfdp);
            let fd = fd_theta(p, |q| rhs(q, c.t, y));
            let f = rhs(p, c.t, y);
            worst = worst.max(max_rel_err(&dfdp, &fd, m, &col, &f, &skip));
        }
        eprintln!(
            "∂f/∂θ      {:<68} {:.1e} (significant entries {:.1e})",
            c.name, worst.err, worst.significant
        );
        assert!(
            worst.significant < 1e-6 && worst.err < 1e-5,
            "{}: {worst:?}",
            c.name
        );
        all = all.max(worst);
    }
    eprintln!(
        "param_jacobian: worst over all plants {:.1e} (significant entries {:.1e})",
        all.err, all.significant
    );
}

#[test]
fn initial_state_sensitivity_matches_finite_differences() {
    // Tolerances: module documentation; λ0 is a Newton solution converged to rounding.
    let mut all = Worst::default();
    for c in cases() {
        let p = &c.plant;
        let (n, m) = (p.layout().n, p.n_theta());
        let mut out = vec![f64::NAN; n * m];
        p.initial_state_sensitivity(&mut out);
        let fd = fd_theta(p, Plant::initial_state);
        let y0 = p.initial_state();
        let worst = max_rel_err(&out, &fd, m, &theta_scale(&p.theta()), &y0, &vec![false; m]);
        eprintln!(
            "∂y0/∂θ     {:<68} {:.1e} (significant entries {:.1e})",
            c.name, worst.err, worst.significant
        );
        assert!(
            worst.significant < 1e-6 && worst.err < 1e-5,
            "{}: {worst:?}",
            c.name
        );
        all = all.max(worst);
    }
    eprintln!(
        "initial_state_sensitivity: worst over all plants {:.1e} (significant entries {:.1e})",
        all.err, all.significant
    );
}

#[test]
fn with_theta_of_theta_is_the_same_plant() {
    for c in cases() {
        let p = &c.plant;
        let q = p.with_theta(&p.theta()).unwrap();
        assert_eq!(q.theta(), p.theta(), "{}", c.name);
        assert_eq!(
            (q.lam0, q.lam_f, q.c_rest, q.eps, q.g_per_c, q.tau_c),
            (p.lam0, p.lam_f, p.c_rest, p.eps, p.g_per_c, p.tau_c),
            "{}",
            c.name
        );
        assert_eq!(q.initial_state(), p.initial_state(), "{}", c.name);
        for y in &c.states {
            assert_eq!(rhs(&q, c.t, y), rhs(p, c.t, y), "{}", c.name);
        }
    }
    // names and units
    let p = plant(&stack(YEOH, TABLE_3_3, "", SINE), true);
    let names = p.sensitivity_params();
    assert_eq!(names[0], "C10 (Pa)");
    assert_eq!(names[3], "arm1.k (Pa)");
    assert_eq!(names[4], "arm1.tau (s)");
    assert_eq!(names[names.len() - 2], "nv (Pa s)");
    assert_eq!(names[names.len() - 1], "eps_r");
    let p = plant(&stack(OGDEN2, TABLE_3_3, "", SINE), true);
    assert_eq!(&p.sensitivity_params()[..2], ["mu1 (Pa)", "alpha1"]);
}

/// Fixed-step classical Runge-Kutta through `System::rhs` (independent of the
/// library's integrators), calling `check(t, y)` after every step.
fn rk4(p: &Plant, t1: f64, h: f64, mut check: impl FnMut(f64, &[f64])) {
    let mut y = p.initial_state();
    let n = y.len();
    let steps = (t1 / h).round() as usize;
    let add = |y: &[f64], k: &[f64], c: f64| -> Vec<f64> {
        y.iter().zip(k).map(|(a, b)| a + c * b).collect()
    };
    for s in 0..steps {
        let t = s as f64 * h;
        let k1 = rhs(p, t, &y);
        let k2 = rhs(p, t + 0.5 * h, &add(&y, &k1, 0.5 * h));
        let k3 = rhs(p, t + 0.5 * h, &add(&y, &k2, 0.5 * h));
        let k4 = rhs(p, t + h, &add(&y, &k3, h));
        for i in 0..n {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        check(t + h, &y);
    }
}

#[test]
fn quasi_static_without_dashpot_keeps_the_force_balance() {
    // Table 3.3 (Nv = 0, four arms), a 2 Hz sine through a 1 ms supply: the drive D
    // stays at zero along the run (index reduction + Baumgarte), relative to the
    // Maxwell force at the peak voltage; RK4 with h = τc/20 (and ≤ R·C/20) makes
    // the integration error ≈ 1e-9 of that scale.
    for source in [RISE, RES] {
        let s = stack(
            YEOH,
            TABLE_3_3,
            source,
            &SINE.replace("phase_rad", "cycles = 2\nphase_rad"),
        );
        let p = plant(&s, false);
        assert!(p.nv == 0.0 && !p.inertia && p.arms.len() == 4);
        let scale = 0.5 * 3e3f64.powi(2) * p.capacitance(p.lam0).1.abs();
        // RK4 is stable for h·rate < 2.8: τc, and R·C of the resistance source
        let rc = match p.source {
            Source::Resistance { ohm } => ohm * p.c_rest,
            _ => f64::INFINITY,
        };
        let h = p.tau_c.min(rc) / 20.0;
        let (mut worst, mut lam_min) = (0.0f64, f64::INFINITY);
        rk4(&p, 1.0, h, |t, y| {
            worst = worst.max(p.drive(t, y).abs() / scale);
            lam_min = lam_min.min(y[0]);
        });
        eprintln!(
            "{source}: τc = {:.2e} s, max |D|/scale {worst:.1e}, stroke {:.1e}",
            p.tau_c,
            p.lam0 - lam_min
        );
        assert!(worst < 1e-8, "{source}: {worst:e}");
        assert!(lam_min < p.lam0 - 1e-3, "it moved: {lam_min}");
    }
}

#[test]
fn quasi_static_without_dashpot_balances_energy_and_is_the_limit_of_a_vanishing_dashpot() {
    // Two Table 3.3 arms, a 2 Hz sine through a 1 ms supply, through `simulate`
    // (DP54, rtol 1e-9). Without dashpot the energy balance closes (to 1e-6 of the
    // input: the drift of D times the stroke); quasi-static runs with Nv = 10 and
    // 1 Pa·s lag the constraint by Vol·Nv/K ≈ Nv/(P' + Σk) ≈ 16 µs and 1.6 µs, so
    // they approach it linearly in Nv.
    let sine = SINE.replace("phase_rad", "cycles = 2\nphase_rad");
    let run = |nv: f64| {
        let viscous = format!("{{ nv = {nv}, arms = [ {{ k = \"106.116 kPa\", tau = \"0.153 s\" }}, {{ k = \"45.51 kPa\", tau = \"0.464 s\" }} ] }}");
        let s = stack_timed(
            YEOH,
            &viscous,
            RISE,
            &sine,
            "samples = 200\nrtol = 1e-9\nfidelity = \"quasi-static\"",
        );
        let o = simulate(
            &s,
            &RunOptions {
                method: Some(Method::Dp54),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(
            o.integrator.status,
            RunStatus::Completed,
            "{}",
            o.integrator.message
        );
        assert_eq!(o.fidelity.model, "quasi-static");
        o
    };
    let o0 = run(0.0);
    let e = &o0.energy;
    eprintln!("energy residual / input {:.1e}", e.residual_j / e.input_j);
    assert!(e.residual_j.abs() < 1e-6 * e.input_j, "{e:?}");
    let stroke = o0.rest_stretch - o0.extremes().stretch_min;
    let gap = |nv: f64| {
        run(nv)
            .samples
            .iter()
            .zip(&o0.samples)
            .map(|(a, b)| (a.stretch - b.stretch).abs())
            .fold(0.0, f64::max)
            / stroke
    };
    let (d10, d1) = (gap(10.0), gap(1.0));
    eprintln!("vanishing dashpot: Nv = 10 → {d10:.1e}, Nv = 1 → {d1:.1e} of the stroke");
    assert!(d10 < 1e-3 && d1 < 1e-4, "{d10:e} {d1:e}");
    assert!(
        (d10 / d1 - 10.0).abs() < 2.0,
        "not linear in Nv: {d10:e} {d1:e}"
    );
}

#[test]
fn quasi_static_without_dashpot_tracks_the_static_curve_and_stops_at_pull_in() {
    let (lc, vc) = nh_pull_in();
    let ramp = |to: f64| {
        let s = nh_layer(
            "{ preset = \"elastic\" }",
            &format!("[[input]]\nkind = \"ramp\"\nstart = 0\nend = \"100 s\"\nto = {to}"),
            "span = \"100 s\"\nsamples = 400\nrtol = 1e-8\nfidelity = \"quasi-static\"",
        );
        let o = simulate(
            &s,
            &RunOptions {
                method: Some(Method::Dp54),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(o.fidelity.model, "quasi-static");
        (o, plant(&s, false))
    };
    // below pull-in: without arms and dashpot the model is the static curve itself
    let (o, p) = ramp(0.95 * vc);
    assert_eq!(
        o.integrator.status,
        RunStatus::Completed,
        "{}",
        o.integrator.message
    );
    let mut worst = 0.0f64;
    for smp in o.samples.iter().filter(|x| x.time_s > 0.0) {
        let v = static_curve::voltage_at(&p, smp.stretch).unwrap();
        worst = worst.max((v - smp.voltage_v).abs() / vc);
    }
    eprintln!("static curve: max |V(λ) − V|/Vc {worst:.1e}");
    assert!(worst < 1e-6, "{worst:e}");
    // above: the run stops at the pull-in event near the closed form
    let (o, _) = ramp(1.2 * vc);
    assert_eq!(
        o.integrator.status,
        RunStatus::PullIn,
        "{}",
        o.integrator.message
    );
    let e = &o.events[0];
    eprintln!(
        "pull-in: λ {} vs {lc} ({:.1e}), V/Vc − 1 = {:.1e}",
        e.stretch,
        e.stretch - lc,
        e.voltage_v / vc - 1.0
    );
    assert!(
        (e.voltage_v / vc - 1.0).abs() < 1e-4,
        "{} vs {vc}",
        e.voltage_v
    );
    assert!((e.stretch - lc).abs() < 1e-2, "{} vs {lc}", e.stretch);
}

#[test]
fn auto_drops_inertia_without_a_dashpot_when_the_arms_damp_the_mode() {
    // A neo-Hookean layer with one stiff arm (k = 300·μ) whose τ puts ω_n·τ ≈ 0.5:
    // the arm alone damps the axial mode (ζ ≈ 0.9), a 25 ms ramp is far below it,
    // and the arm cannot be lumped as a dashpot ((τ/t_in)·k/E ≈ 2e-4 > 1e-4).
    let (_, vc) = nh_pull_in();
    let run = |fid: &str| {
        let s = nh_layer(
            "{ arms = [ { k = \"30 MPa\", tau = \"4.46 us\" } ] }",
            &format!(
                "[[input]]\nkind = \"ramp\"\nstart = 0\nend = \"25 ms\"\nto = {}",
                0.5 * vc
            ),
            &format!("span = \"40 ms\"\nsamples = 400\nrtol = 1e-9\nfidelity = \"{fid}\""),
        );
        simulate(
            &s,
            &RunOptions {
                method: Some(Method::Dp54),
                ..Default::default()
            },
        )
        .unwrap()
    };
    let auto = run("auto");
    let f = &auto.fidelity;
    assert_eq!(f.model, "quasi-static", "{}", f.reason);
    assert!(auto.mode.damping_ratio >= 0.5 && auto.mode.dashpot_share == 0.0);
    assert!(f.arms[0].contains("integrated"), "{:?}", f.arms);
    let dynamic = run("dynamic");
    let stroke = dynamic.rest_stretch - dynamic.extremes().stretch_min;
    let worst = auto
        .samples
        .iter()
        .zip(&dynamic.samples)
        .map(|(a, b)| (a.stretch - b.stretch).abs())
        .fold(0.0, f64::max)
        / stroke;
    eprintln!(
        "auto without dashpot: ζ = {:.2}, estimate {:.1e}, measured {worst:.1e} of the stroke ({})",
        auto.mode.damping_ratio, f.estimated_error, f.reason
    );
    assert!(f.estimated_error > 0.0 && f.estimated_error <= 1e-3);
    assert!(
        worst < f.estimated_error,
        "{worst:e} vs {:e}",
        f.estimated_error
    );
}
