//! Closed forms, derivatives and invariants of every hyperelastic model.

use dea_fit::fit::drucker::{drucker, drucker_dense, GRID};
use dea_fit::material::hyperelastic::ogden::Ogden;
use dea_fit::material::hyperelastic::powers::{Laurent, TangentPowers};
use dea_fit::material::hyperelastic::ParamInfo;
use dea_fit::material::hyperelastic::{Mode, ModelSpec, OgdenForm, StrainEnergy};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Every model with a representative, Drucker-stable parameter vector (SI).
fn cases() -> Vec<(Box<dyn StrainEnergy>, Vec<f64>)> {
    let b = |n: &str, f: OgdenForm| ModelSpec::new(n, f).build().unwrap();
    vec![
        (b("neo-hookean", OgdenForm::Abaqus), vec![4e5]),
        (b("mooney-rivlin", OgdenForm::Abaqus), vec![1.5e5, 3e4]),
        (b("yeoh", OgdenForm::Abaqus), vec![6.93e4, -888.0, 16.7]),
        (b("gent", OgdenForm::Abaqus), vec![2e5, 40.0]),
        (b("ogden1", OgdenForm::Abaqus), vec![3e5, 1.8]),
        (b("ogden2", OgdenForm::Abaqus), vec![3e5, 1.5, 2e3, 5.0]),
        (
            b("ogden3", OgdenForm::Abaqus),
            vec![3.3e5, 1.9, 3.0, 8.6, 7e3, -2.2],
        ),
        (
            b("ogden4", OgdenForm::Abaqus),
            vec![3e5, 1.3, 1e3, 5.0, 5e3, -2.0, 10.0, 0.5],
        ),
        (
            b("ogden3", OgdenForm::Original),
            vec![6.18e5, 1.3, 1.18e3, 5.0, -9.81e3, -2.0],
        ),
    ]
}

const STRETCHES: [f64; 7] = [0.35, 0.7, 0.95, 1.05, 1.6, 2.9, 4.5];

#[test]
fn zero_stress_in_the_reference_state() {
    for (m, p) in cases() {
        let mu0 = m.initial_shear_modulus(&p);
        for mode in Mode::ALL {
            let s = m.nominal_stress(&p, mode, 1.0);
            // Exact cancellation up to rounding of O(μ0) terms.
            assert!(s.abs() <= 1e-10 * mu0, "{} {mode}: P(1) = {s}", m.name());
        }
    }
}

#[test]
fn initial_slopes_are_3_6_4_times_mu0() {
    // Small-strain limit: dP/dλ at λ = 1 is 3μ0 (uniaxial, Young's modulus), 6μ0
    // (equibiaxial) and 4μ0 (planar) for every incompressible isotropic model.
    for (m, p) in cases() {
        let mu0 = m.initial_shear_modulus(&p);
        for (mode, k) in [
            (Mode::Uniaxial, 3.0),
            (Mode::Equibiaxial, 6.0),
            (Mode::Planar, 4.0),
        ] {
            let t = m.tangent(&p, mode, 1.0);
            assert!(
                (t - k * mu0).abs() <= 1e-9 * k * mu0,
                "{} {mode}: {t} vs {}",
                m.name(),
                k * mu0
            );
        }
    }
}

fn central(f: impl Fn(f64) -> f64, x: f64) -> f64 {
    let h = 1e-6 * x.abs().max(1e-3);
    (f(x + h) - f(x - h)) / (2.0 * h)
}

#[test]
fn tangent_matches_finite_differences() {
    for (m, p) in cases() {
        for mode in Mode::ALL {
            for &l in &STRETCHES {
                if !m.nominal_stress(&p, mode, l).is_finite() {
                    continue; // beyond the Gent limit: no stress, no tangent
                }
                let fd = central(|x| m.nominal_stress(&p, mode, x), l);
                let an = m.tangent(&p, mode, l);
                // Central differences with h = 1e-6·λ: truncation ~1e-12, rounding
                // ~ε·|P|/h; the bound allows 50× that rounding plus 1e-6 relative.
                let tol = 1e-6 * an.abs() + 1e-8 * m.nominal_stress(&p, mode, l).abs() / l;
                assert!(
                    (fd - an).abs() <= tol.max(1e-9),
                    "{} {mode} λ={l}: {an} vs {fd}",
                    m.name()
                );
            }
        }
    }
}

#[test]
fn parameter_jacobian_matches_finite_differences() {
    for (m, p) in cases() {
        let k = p.len();
        let mut row = vec![0.0; k];
        for mode in Mode::ALL {
            for &l in &STRETCHES {
                let stress = m.nominal_stress(&p, mode, l);
                if !stress.is_finite() {
                    continue;
                }
                m.stress_jacobian(&p, mode, l, &mut row);
                for j in 0..k {
                    let fd = central(
                        |x| {
                            let mut q = p.clone();
                            q[j] = x;
                            m.nominal_stress(&q, mode, l)
                        },
                        p[j],
                    );
                    // 1e-6 relative plus 50× the rounding bound ε·|P|/h of the difference.
                    let tol = 1e-6 * row[j].abs() + 1e-8 * stress.abs() / p[j].abs();
                    assert!(
                        (fd - row[j]).abs() <= tol.max(1e-12),
                        "{} {mode} λ={l} p{j}: {} vs {fd}",
                        m.name(),
                        row[j]
                    );
                }
            }
        }
    }
}

#[test]
fn linear_models_are_linear_in_their_parameters() {
    for (m, p) in cases().into_iter().filter(|(m, _)| m.linear_in_params()) {
        let mut row = vec![0.0; p.len()];
        for mode in Mode::ALL {
            for &l in &STRETCHES {
                m.stress_jacobian(&p, mode, l, &mut row);
                let lin: f64 = row.iter().zip(&p).map(|(a, b)| a * b).sum();
                let s = m.nominal_stress(&p, mode, l);
                assert!((lin - s).abs() <= 1e-12 * s.abs().max(1.0));
            }
        }
    }
}

fn same_stress(a: &dyn StrainEnergy, pa: &[f64], b: &dyn StrainEnergy, pb: &[f64], tol: f64) {
    for mode in Mode::ALL {
        for &l in &STRETCHES {
            let (x, y) = (a.nominal_stress(pa, mode, l), b.nominal_stress(pb, mode, l));
            assert!(
                (x - y).abs() <= tol * x.abs().max(1.0),
                "{} vs {} {mode} λ={l}: {x} vs {y}",
                a.name(),
                b.name()
            );
        }
    }
}

#[test]
fn models_agree_where_they_coincide() {
    let b = |n: &str, f: OgdenForm| ModelSpec::new(n, f).build().unwrap();
    let nh = b("neo-hookean", OgdenForm::Abaqus);
    let mu = 4e5;
    // Ogden-1 with α = 2 in the seed form is Neo-Hookean with μ.
    same_stress(
        nh.as_ref(),
        &[mu],
        b("ogden1", OgdenForm::Abaqus).as_ref(),
        &[mu, 2.0],
        1e-12,
    );
    // ... and in the original form with μ1 = μ (μ0 = ½·μ1·α1).
    same_stress(
        nh.as_ref(),
        &[mu],
        b("ogden1", OgdenForm::Original).as_ref(),
        &[mu, 2.0],
        1e-12,
    );
    // Mooney-Rivlin with C01 = 0 and Yeoh with C20 = C30 = 0 are Neo-Hookean with μ = 2C10.
    same_stress(
        nh.as_ref(),
        &[mu],
        b("mooney-rivlin", OgdenForm::Abaqus).as_ref(),
        &[mu / 2.0, 0.0],
        1e-12,
    );
    same_stress(
        nh.as_ref(),
        &[mu],
        b("yeoh", OgdenForm::Abaqus).as_ref(),
        &[mu / 2.0, 0.0, 0.0],
        1e-12,
    );
    // Ogden-2 with α = (2, −2) in Ogden's form is Mooney-Rivlin, C10 = μ1/2, C01 = −μ2/2.
    same_stress(
        b("mooney-rivlin", OgdenForm::Abaqus).as_ref(),
        &[1.5e5, 3e4],
        b("ogden2", OgdenForm::Original).as_ref(),
        &[3e5, 2.0, -6e4, -2.0],
        1e-12,
    );
    // Gent tends to Neo-Hookean as Jm → ∞ (relative difference ~ (I1−3)/Jm).
    same_stress(
        nh.as_ref(),
        &[mu],
        b("gent", OgdenForm::Abaqus).as_ref(),
        &[mu, 1e9],
        1e-7,
    );
    // The two Ogden forms describe the same function after conversion.
    let orig = [6.18e5, 1.3, 1.18e3, 5.0, -9.81e3, -2.0];
    let seed = Ogden::convert(&orig, OgdenForm::Original, OgdenForm::Abaqus);
    same_stress(
        b("ogden3", OgdenForm::Original).as_ref(),
        &orig,
        b("ogden3", OgdenForm::Abaqus).as_ref(),
        &seed,
        1e-12,
    );
    let back = Ogden::convert(&seed, OgdenForm::Abaqus, OgdenForm::Original);
    for (a, b) in orig.iter().zip(&back) {
        assert!((a - b).abs() <= 1e-12 * a.abs());
    }
}

#[test]
fn published_values() {
    let b = |n: &str, f: OgdenForm| ModelSpec::new(n, f).build().unwrap();
    // Ogden (1972) for Treloar's rubber, original form, μ in N/mm² → Pa:
    // μ0 = ½Σμiαi = ½(0.618·1.3 + 0.00118·5.0 + 0.00981·2.0) MPa = 0.4145 MPa.
    let ogden = b("ogden3", OgdenForm::Original);
    let p = [6.18e5, 1.3, 1.18e3, 5.0, -9.81e3, -2.0];
    assert!((ogden.initial_shear_modulus(&p) - 0.41446e6).abs() < 50.0);
    // Seed Table 3.2 (Wissler & Mazza 2005, VHB 4910 Yeoh): μ0 = 2·C10 = 0.1386 MPa,
    // Y0 = 6·C10 = 0.416 MPa as the table states.
    let yeoh = b("yeoh", OgdenForm::Abaqus);
    let q = [0.0693e6, -8.88e-4 * 1e6, 16.7e-6 * 1e6];
    assert!((3.0 * yeoh.initial_shear_modulus(&q) - 0.4158e6).abs() < 1.0);
    // Neo-Hookean uniaxial closed form P = μ(λ − λ⁻²): at λ = 2, P = 1.75μ.
    let nh = b("neo-hookean", OgdenForm::Abaqus);
    assert!((nh.nominal_stress(&[1.0], Mode::Uniaxial, 2.0) - 1.75).abs() < 1e-15);
    // Equibiaxial P = μ(λ − λ⁻⁵), planar P = μ(λ − λ⁻³).
    assert!((nh.nominal_stress(&[1.0], Mode::Equibiaxial, 2.0) - (2.0 - 1.0 / 32.0)).abs() < 1e-15);
    assert!((nh.nominal_stress(&[1.0], Mode::Planar, 2.0) - (2.0 - 0.125)).abs() < 1e-15);
}

#[test]
fn drucker_check_finds_the_unstable_range() {
    let b = |n: &str| ModelSpec::new(n, OgdenForm::Abaqus).build().unwrap();
    for (m, p) in cases() {
        // Every case above is stable over 0.1–10 except possibly where the Gent limit
        // is reached (no finite stress there: reported as not stable).
        let d = drucker(m.as_ref(), &p);
        if m.name() != "gent" {
            assert!(d.iter().all(|d| d.stable), "{}: {d:?}", m.name());
        }
    }
    // Yeoh with a large negative C20 softens and loses stability in uniaxial tension:
    // dP/dλ = 0 where the quadratic W1(x) has its minimum below zero.
    let yeoh = b("yeoh");
    let p = [1e5, -5e3, 50.0];
    let d = drucker(yeoh.as_ref(), &p);
    let u = d.iter().find(|d| d.mode == Mode::Uniaxial).unwrap();
    assert!(
        !u.stable && u.stretch_max > 1.5 && u.stretch_max < 10.0,
        "{u:?}"
    );
    // The reported bound is where the tangent changes sign (to the grid's resolution).
    assert!(yeoh.tangent(&p, Mode::Uniaxial, u.stretch_max * 0.99) > 0.0);
    assert!(yeoh.tangent(&p, Mode::Uniaxial, u.stretch_max * 1.02) <= 0.0);
    // Gent is undefined beyond its limit: reported, not hidden.
    let gent = b("gent");
    let d = drucker(gent.as_ref(), &[2e5, 10.0]);
    assert!(d.iter().any(|d| !d.stable));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn ogden_jacobian_is_right_for_any_exponent(alpha in -12.0f64..12.0, lam in 0.2f64..6.0, mode in 0usize..3) {
        // Includes exponents near 0, where the seed form switches to its series.
        let m = Ogden::new(1, OgdenForm::Abaqus);
        let p = [1e5, alpha];
        let mode = Mode::ALL[mode];
        let mut row = [0.0; 2];
        m.stress_jacobian(&p, mode, lam, &mut row);
        // The exponent step is absolute (α can be near 0, where a relative step would
        // drown in rounding): h = 1e-4 gives truncation ~1e-9 relative.
        let h = 1e-4;
        let fd = (m.nominal_stress(&[1e5, alpha + h], mode, lam) - m.nominal_stress(&[1e5, alpha - h], mode, lam)) / (2.0 * h);
        prop_assert!((fd - row[1]).abs() <= 1e-5 * row[1].abs().max(1e-3 * 1e5));
        let fd = central(|x| m.nominal_stress(&p, mode, x), lam);
        let t = m.tangent(&p, mode, lam);
        prop_assert!((fd - t).abs() <= 1e-5 * t.abs().max(1.0));
    }

    #[test]
    fn stress_vanishes_at_unit_stretch_for_random_parameters(c10 in 1e3f64..1e6, c20 in -1e4f64..1e4, c30 in 0.0f64..1e3) {
        let m = ModelSpec::new("yeoh", OgdenForm::Abaqus).build().unwrap();
        for mode in Mode::ALL {
            prop_assert!(m.nominal_stress(&[c10, c20, c30], mode, 1.0).abs() <= 1e-9 * c10);
        }
    }
}

/// A random parameter vector for `name`: moduli of either sign over seven decades,
/// Ogden exponents over their whole bound, Gent limits from 10⁻³ to 10⁴.
fn random_params(name: &str, draws: &[(bool, f64, f64)]) -> Vec<f64> {
    let modulus =
        |&(neg, mag, _): &(bool, f64, f64)| if neg { -1.0 } else { 1.0 } * 10f64.powf(mag);
    let k = ModelSpec::new(name, OgdenForm::Abaqus)
        .build()
        .unwrap()
        .params()
        .len();
    (0..k)
        .map(|j| {
            let d = &draws[j];
            match name {
                "gent" if j == 1 => 10f64.powf(-3.0 + 7.0 * (d.2 + 20.0) / 40.0),
                n if n.starts_with("ogden") && j % 2 == 1 => d.2,
                _ => modulus(d),
            }
        })
        .collect()
}

/// A model that counts its tangent evaluations.
struct Counting<'a>(&'a dyn StrainEnergy, AtomicUsize);

impl StrainEnergy for Counting<'_> {
    fn name(&self) -> String {
        self.0.name()
    }
    fn params(&self) -> &[ParamInfo] {
        self.0.params()
    }
    fn nominal_stress(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        self.0.nominal_stress(p, mode, lam)
    }
    fn tangent(&self, p: &[f64], mode: Mode, lam: f64) -> f64 {
        self.1.fetch_add(1, Ordering::Relaxed);
        self.0.tangent(p, mode, lam)
    }
    fn tangent_powers(&self, p: &[f64], mode: Mode) -> Option<TangentPowers> {
        self.0.tangent_powers(p, mode)
    }
    fn tangent_basis(&self, mode: Mode) -> Option<&'static [Laurent]> {
        self.0.tangent_basis(mode)
    }
    fn stress_jacobian(&self, p: &[f64], mode: Mode, lam: f64, out: &mut [f64]) {
        self.0.stress_jacobian(p, mode, lam, out)
    }
    fn initial_shear_modulus(&self, p: &[f64]) -> f64 {
        self.0.initial_shear_modulus(p)
    }
}

/// The bounded check decides most of the grid without evaluating it: on every
/// representative case (stable) and on an unstable Yeoh it evaluates the tangent at
/// under a tenth of the 3 × 801 grid stretches the dense sweep does, with the same
/// result.
#[test]
fn drucker_check_evaluates_few_stretches() {
    let yeoh = ModelSpec::new("yeoh", OgdenForm::Abaqus).build().unwrap();
    let mut all = cases();
    all.push((yeoh, vec![1e5, -5e3, 50.0]));
    for (m, p) in &all {
        let c = Counting(m.as_ref(), AtomicUsize::new(0));
        let d = drucker(&c, p);
        let used = c.1.load(Ordering::Relaxed);
        assert_eq!(d, drucker_dense(m.as_ref(), p), "{}", m.name());
        assert!(used < 3 * GRID / 10, "{}: {used} evaluations", m.name());
    }
}

/// The coefficient `p[j]` (negative) at which the dense sweep's verdict turns from
/// stable (at 0) to unstable, by bisection; None when no value down to −2⁶⁰·`p[0]` is
/// unstable.
fn stability_border(m: &dyn StrainEnergy, p: &[f64], j: usize) -> Option<f64> {
    let stable = |v: f64| {
        let mut q = p.to_vec();
        q[j] = v;
        drucker_dense(m, &q).iter().all(|d| d.stable)
    };
    let (mut good, mut bad) = (0.0, -p[0]);
    while stable(bad) {
        (good, bad) = (bad, 2.0 * bad);
        if bad < -1e18 * p[0] {
            return None;
        }
    }
    for _ in 0..80 {
        let mid = 0.5 * (good + bad);
        if mid == good || mid == bad {
            break;
        }
        if stable(mid) {
            good = mid
        } else {
            bad = mid
        }
    }
    Some(good)
}

/// The certified check gives the dense sweep's verdict at every grid stretch
/// (`drucker` against `drucker_dense`, every field): on random coefficient sets
/// of the polynomial models, signs mixed, magnitudes over six decades, and on
/// borderline ones, a coefficient set where the sweep's verdict turns and moved
/// by ±10⁻¹⁵…10⁻⁶ of itself (the tangent's least value at, just above and just
/// below zero, where a certificate without margin enough would say `stable`).
#[test]
fn certificate_agrees_with_the_dense_sweep() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    for name in ["neo-hookean", "mooney-rivlin", "yeoh"] {
        let m = ModelSpec::new(name, OgdenForm::Abaqus).build().unwrap();
        let k = m.params().len();
        for _ in 0..150 {
            let p: Vec<f64> = (0..k)
                .map(|_| {
                    let v = 10f64.powf(rng.gen_range(-1.0..6.0));
                    if rng.gen_bool(0.3) {
                        -v
                    } else {
                        v
                    }
                })
                .collect();
            assert_eq!(
                drucker(m.as_ref(), &p),
                drucker_dense(m.as_ref(), &p),
                "{name} {p:?}"
            );
        }
        if k < 2 {
            continue;
        }
        for _ in 0..6 {
            let mut p: Vec<f64> = (0..k)
                .map(|_| 10f64.powf(rng.gen_range(3.0..6.0)))
                .collect();
            for v in p.iter_mut().skip(2) {
                *v *= 1e-4;
            }
            let Some(b) = stability_border(m.as_ref(), &p, 1) else {
                continue;
            };
            for rel in [-1e-6, -1e-9, -1e-12, -1e-15, 0.0, 1e-15, 1e-12, 1e-9, 1e-6] {
                p[1] = b * (1.0 + rel);
                assert_eq!(
                    drucker(m.as_ref(), &p),
                    drucker_dense(m.as_ref(), &p),
                    "{name} {p:?}"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Borderline models: Yeoh's C20 and Mooney-Rivlin's C01 set where the dense
    /// sweep's verdict turns (the tangent just touching zero at a grid stretch), then
    /// moved by ±10⁻¹⁵…10⁻⁶ of itself, so that the tangent's smallest value sits at,
    /// just above and just below zero: where a bound that is not sound, or a margin
    /// too thin for the rounding of either way of computing the tangent, would give
    /// another verdict than the sweep. The check gives the sweep's result at every one.
    #[test]
    fn drucker_check_agrees_with_the_dense_sweep_at_the_border(
        yeoh in proptest::bool::ANY,
        c10 in 1e3f64..1e6,
        other in 1e-4f64..1.0,
    ) {
        let (name, j) = if yeoh { ("yeoh", 1) } else { ("mooney-rivlin", 1) };
        let m = ModelSpec::new(name, OgdenForm::Abaqus).build().unwrap();
        let mut p = if yeoh { vec![c10, 0.0, other * c10 * 1e-3] } else { vec![c10, 0.0] };
        let Some(border) = stability_border(m.as_ref(), &p, j) else {
            return Ok(());
        };
        for rel in [-1e-6, -1e-9, -1e-12, -1e-15, 0.0, 1e-15, 1e-12, 1e-9, 1e-6] {
            p[j] = border * (1.0 + rel);
            prop_assert_eq!(drucker(m.as_ref(), &p), drucker_dense(m.as_ref(), &p), "{} {:?}", name, p);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// The bounded check gives the dense sweep's result, stable or not, for random
    /// parameters of every model and Ogden form.
    #[test]
    fn drucker_check_agrees_with_the_dense_sweep(
        model in 0usize..8,
        original in proptest::bool::ANY,
        draws in proptest::collection::vec((proptest::bool::ANY, 0.0f64..7.0, -20.0f64..20.0), 8),
    ) {
        let name = dea_fit::material::hyperelastic::MODEL_NAMES[model];
        let form = if original { OgdenForm::Original } else { OgdenForm::Abaqus };
        let m = ModelSpec::new(name, form).build().unwrap();
        let p = random_params(name, &draws);
        prop_assert_eq!(drucker(m.as_ref(), &p), drucker_dense(m.as_ref(), &p), "{} {:?}", name, p);
    }

    /// The power form of the tangent is the tangent: the same value (a positive
    /// factor apart for Gent, whose sign is compared) at random stretches.
    #[test]
    fn tangent_powers_are_the_tangent(
        model in 0usize..8,
        draws in proptest::collection::vec((proptest::bool::ANY, 0.0f64..7.0, -20.0f64..20.0), 8),
        lam in 0.1f64..10.0,
        mode in 0usize..3,
    ) {
        let name = dea_fit::material::hyperelastic::MODEL_NAMES[model];
        let m = ModelSpec::new(name, OgdenForm::Abaqus).build().unwrap();
        let p = random_params(name, &draws);
        let mode = Mode::ALL[mode];
        let t = m.tangent(&p, mode, lam);
        let Some(tp) = m.tangent_powers(&p, mode) else {
            return Ok(());
        };
        let q = tp.sum.split().parts(lam.ln(), lam);
        let s = q.p - q.n;
        if tp.bounded {
            prop_assert!(!t.is_finite() || t.signum() == s.signum() || s.abs() <= 1e-9 * (q.p + q.n), "{} {:?}: {} vs {}", name, p, t, s);
        } else {
            prop_assert!((t - s).abs() <= 1e-9 * (q.p + q.n), "{} {:?} λ {}: {} vs {}", name, p, lam, t, s);
        }
    }
}

/// A parameter vector of the wrong length (an Ogden-3 fit file holding one value
/// panicked in ogden.rs) gives NaN from every evaluator, and `check_params` says
/// what is wrong, for every model.
#[test]
fn wrong_length_parameters_give_nan_and_an_error_never_a_panic() {
    for (m, p) in cases() {
        let k = p.len();
        assert!(m.check_params(&p).is_ok(), "{}", m.name());
        for bad in [
            &p[..k - 1],
            &p[..1],
            &[][..],
            &[p.clone(), vec![1.0]].concat()[..],
        ] {
            if bad.len() == k {
                continue;
            }
            let e = m.check_params(bad).expect_err("wrong length");
            assert!(
                e.to_string().contains(&format!("takes {k} parameters")),
                "{e}"
            );
            for mode in Mode::ALL {
                assert!(m.nominal_stress(bad, mode, 1.7).is_nan(), "{}", m.name());
                assert!(m.tangent(bad, mode, 1.7).is_nan(), "{}", m.name());
                let mut out = vec![0.0; k];
                m.stress_jacobian(bad, mode, 1.7, &mut out);
                assert!(out.iter().all(|v| v.is_nan()), "{} {out:?}", m.name());
            }
            assert!(m.initial_shear_modulus(bad).is_nan(), "{}", m.name());
        }
        // A Jacobian buffer of the wrong length is filled with NaN, not indexed past.
        let mut short = vec![0.0; k - 1];
        m.stress_jacobian(&p, Mode::Uniaxial, 1.7, &mut short);
        assert!(short.iter().all(|v| v.is_nan()), "{}", m.name());
        let mut nan = p.clone();
        nan[0] = f64::NAN;
        assert!(m.check_params(&nan).is_err(), "{}", m.name());
    }
}

/// The Gent limit's bounds are never inverted, whatever the data's largest I1 − 3
/// (data beyond the upper bound, or NaN): `f64::clamp` panicked on them.
#[test]
fn gent_bounds_are_never_inverted() {
    let g = ModelSpec::new("gent", OgdenForm::Abaqus).build().unwrap();
    for x in [0.0, 1e4, 1e6, 1e7, 1e300, f64::INFINITY, f64::NAN] {
        for (lo, hi) in g.bounds(x) {
            assert!(lo <= hi, "max I1 − 3 = {x}: [{lo}, {hi}]");
        }
    }
}
