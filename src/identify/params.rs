//! The material constants identification can move: their names, where they live in
//! a scene, and how the search sees them.
//!
//! **θ** is the simulator's parameter vector ([`crate::sim::Sensitivities`]): the
//! hyperelastic parameters in model order (`C10`, `C20`, `mu`, `Jm`, Ogden `mu1`,
//! `alpha1`, …), then per Maxwell arm `armJ.k` (Pa) and `armJ.tau` (s), then `nv`
//! (Pa·s), then `eps_r`. Identification keeps every arm integrated (no lumping), so
//! θ's layout follows the scene's arms one to one.
//!
//! **The filler mass fraction.** When the scene's εr is a composite's mixing rule
//! (`relative_permittivity = { composite = ..., mass_fraction = ... }`), the last
//! entry of θ is the filler mass fraction w (`mass_fraction`, dimensionless) in
//! place of `eps_r`: [`set_theta`] puts εr = εr(w) into the scene
//! ([`crate::material::dielectric::Mixture`]), and the Jacobian column of w is the
//! simulator's εr column times dεr/dw = ∂εr/∂φ·dφ/dw ([`Constant::dsim_dvalue`]),
//! exact. εr is then not a constant of its own: it is the same physics, so `eps_r`
//! is refused by name with the reason, and reported as derived from w.
//!
//! **Search coordinates x.** A constant that is positive by physics (arm k and τ, εr,
//! Gent's Jm, a positive leading modulus C10 or μ, a positive nv) is searched as
//! x = ln θ, so that a step is a ratio and the bound θ > 0 can never be crossed.
//! A constant that may take either sign or be zero (higher polynomial terms such as
//! C20, C30 or C01, Ogden pairs, nv = 0) is searched as x = θ/s with a scale s
//! (its magnitude, or a fraction of μ0 when it is zero). A mass fraction is searched
//! linearly too, x = w/[`MASS_FRACTION_SCALE`] within [0, 0.999]
//! ([`crate::material::check::MASS_FRACTION`]): 0, the pure matrix, must stay
//! reachable, which ln w cannot.
//!
//! **Search boxes** (the bounds no estimate may leave), stated multiples of the
//! scene's values θ0: a positive constant within θ0/100 … 100·θ0 (a relaxation
//! time θ0/1000 … 1000·θ0), a model parameter also within its model's own limits;
//! a sign-free one within θ0 ± 100·s, s = max(|θ0|, 10⁻³·μ0) for a modulus
//! (max(|θ0|, 0.1) otherwise); nv of a scene without dashpot 0 … 100·μ0 s; a mass
//! fraction its whole domain. The box is not physics: an estimate that ends on it
//! is held by the box, not the trace, so it is not identifiable and the run is
//! `ill_posed` ([`super::assessment`]). Physics bounds the hyperelastic law
//! itself: Drucker-stable over the traced stretches ([`super::drucker_unstable`]).

use crate::error::{Error, Result};
use crate::material::check::MASS_FRACTION;
use crate::material::dielectric::Mixture;
use crate::material::file::Arm;
use crate::sim::scene::Scene;

/// Mass fraction per unit of the search coordinate of `mass_fraction` (the starts
/// spread ±3 units, ±30 % about the scene's value).
pub const MASS_FRACTION_SCALE: f64 = 0.1;

/// How a constant is seen by the search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Space {
    /// x = ln θ.
    Log,
    /// x = θ / scale.
    Linear {
        /// θ per unit of x.
        scale: f64,
    },
}

impl Space {
    /// θ from x.
    pub fn theta(self, x: f64) -> f64 {
        match self {
            Space::Log => x.exp(),
            Space::Linear { scale } => x * scale,
        }
    }

    /// x from θ.
    pub fn x(self, theta: f64) -> f64 {
        match self {
            Space::Log => theta.ln(),
            Space::Linear { scale } => theta / scale,
        }
    }

    /// dθ/dx at x.
    pub fn dtheta_dx(self, x: f64) -> f64 {
        match self {
            Space::Log => x.exp(),
            Space::Linear { scale } => scale,
        }
    }
}

/// One named constant of θ.
#[derive(Debug, Clone, PartialEq)]
pub struct Constant {
    /// Name as the user writes it (`C10`, `arm2.tau`, `nv`, `eps_r`).
    pub name: String,
    /// SI unit (`Pa`, `s`, `Pa s`, `1`).
    pub unit: &'static str,
    /// Index in θ.
    pub index: usize,
    /// The scene's value (the start of the search).
    pub start: f64,
    /// Search coordinates.
    pub space: Space,
    /// Bounds in θ (SI).
    pub bounds: (f64, f64),
    /// Box the multi-start spreads its starts over, in θ (inside `bounds`).
    pub start_box: (f64, f64),
    /// What this constant is, for the identifiability reasons.
    pub role: Role,
    /// The mixing rule through which this constant (a filler mass fraction) sets
    /// the simulator's εr; None: the constant is its θ entry in the simulator.
    pub mixture: Option<Mixture>,
}

impl Constant {
    /// d(the simulator's parameter)/d(this constant) at its value v: dεr/dw for a
    /// mass fraction ([`Mixture::deps_dw`]), else 1.
    pub fn dsim_dvalue(&self, v: f64) -> f64 {
        self.mixture.map_or(1.0, |m| m.deps_dw(v))
    }
}

/// What a constant is in the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The leading (small-strain) modulus: `C10`, `mu`, `mu1`.
    LeadingModulus,
    /// A hyperelastic term that only shows at larger strain (`C20`, `C30`, `C01`,
    /// Ogden pairs beyond the first, `Jm`).
    HigherOrder,
    /// Spring of Maxwell arm j (0-based).
    ArmK(usize),
    /// Relaxation time of Maxwell arm j (0-based).
    ArmTau(usize),
    /// Kelvin-Voigt dashpot.
    Nv,
    /// Relative permittivity.
    EpsR,
    /// Filler mass fraction (εr through a mixing rule).
    MassFraction,
}

impl Role {
    /// εr or what sets it.
    pub fn is_dielectric(self) -> bool {
        matches!(self, Role::EpsR | Role::MassFraction)
    }
}

/// Every constant of a scene's material, in θ order.
pub fn constants(scene: &Scene) -> Vec<Constant> {
    let m = &scene.material;
    let mu0 = m.model.initial_shear_modulus(&m.params).abs().max(1.0);
    let mut out = Vec::new();
    for (i, info) in m.model.params().iter().enumerate() {
        let v = m.params[i];
        let role = if i == 0 {
            Role::LeadingModulus
        } else {
            Role::HigherOrder
        };
        let positive = v > 0.0 && (info.lower >= 0.0 || i == 0);
        let (space, bounds, start_box) = if positive {
            let lo = (v / 100.0).max(info.lower);
            let hi = (v * 100.0).min(info.upper);
            (
                Space::Log,
                (lo, hi),
                ((v / 10.0).max(lo), (v * 10.0).min(hi)),
            )
        } else {
            let scale = match info.unit {
                "Pa" => v.abs().max(1e-3 * mu0),
                _ => v.abs().max(0.1),
            };
            let lo = (v - 100.0 * scale).max(info.lower);
            let hi = (v + 100.0 * scale).min(info.upper);
            (
                Space::Linear { scale },
                (lo, hi),
                ((v - 3.0 * scale).max(lo), (v + 3.0 * scale).min(hi)),
            )
        };
        out.push(Constant {
            name: info.name.clone(),
            unit: info.unit,
            index: i,
            start: v,
            space,
            bounds,
            start_box,
            role,
            mixture: None,
        });
    }
    let np = m.params.len();
    for (j, a) in m.viscous.arms.iter().enumerate() {
        let tau = a.eta_pa_s / a.k_pa;
        out.push(positive(
            format!("arm{}.k", j + 1),
            "Pa",
            np + 2 * j,
            a.k_pa,
            100.0,
            Role::ArmK(j),
        ));
        out.push(positive(
            format!("arm{}.tau", j + 1),
            "s",
            np + 2 * j + 1,
            tau,
            1000.0,
            Role::ArmTau(j),
        ));
    }
    let k = np + 2 * m.viscous.arms.len();
    let nv = m.viscous.nv_pa_s;
    out.push(if nv > 0.0 {
        positive("nv".into(), "Pa s", k, nv, 100.0, Role::Nv)
    } else {
        // No dashpot in the scene: searched from 0 on the scale μ0·10 ms (the shipped
        // damped stack has nv/μ0 ≈ 13 ms).
        let scale = 0.01 * mu0;
        Constant {
            name: "nv".into(),
            unit: "Pa s",
            index: k,
            start: 0.0,
            space: Space::Linear { scale },
            bounds: (0.0, 1e4 * scale),
            start_box: (0.0, 3.0 * scale),
            role: Role::Nv,
            mixture: None,
        }
    });
    out.push(match &m.composite {
        Some(c) => {
            let (w, s) = (c.mass_fraction, MASS_FRACTION_SCALE);
            let (lo, hi) = (MASS_FRACTION.min, MASS_FRACTION.max);
            Constant {
                name: "mass_fraction".into(),
                unit: "1",
                index: k + 1,
                start: w,
                space: Space::Linear { scale: s },
                bounds: (lo, hi),
                start_box: ((w - 3.0 * s).max(lo), (w + 3.0 * s).min(hi)),
                role: Role::MassFraction,
                mixture: Some(c.mixture),
            }
        }
        None => {
            let mut eps = positive("eps_r".into(), "1", k + 1, m.eps_r, 100.0, Role::EpsR);
            eps.bounds.0 = eps.bounds.0.max(1.0);
            eps.start_box.0 = eps.start_box.0.max(1.0);
            eps
        }
    });
    out
}

/// A positive constant searched in log space within a factor `range` of its value
/// (starts within a factor 10, or `range`'s square root when that is smaller).
fn positive(
    name: String,
    unit: &'static str,
    index: usize,
    v: f64,
    range: f64,
    role: Role,
) -> Constant {
    let spread = range.sqrt().min(10.0);
    Constant {
        name,
        unit,
        index,
        start: v,
        space: Space::Log,
        bounds: (v / range, v * range),
        start_box: (v / spread, v * spread),
        role,
        mixture: None,
    }
}

/// The Maxwell arms whose spring and relaxation time are both free are
/// interchangeable (the stress is a sum over arms), so a search can end with their
/// labels swapped against the scene's: on the rig trace
/// (datasets/scenes/stack_rig_7s.toml) a far start reaches the best cost with arm 1
/// at τ = 2.21 s and arm 2 at 0.32 s, the scene's 0.32 s and 2.26 s exchanged. Put
/// their (k, τ) pairs in the order of increasing τ over the arms' labels, in place,
/// so the same optimum is always reported the same way; left as it is if a value
/// would leave the bounds of the constant it moves to. Returns whether x changed.
pub fn order_arms(free: &[Constant], x: &mut [f64]) -> bool {
    // (position of k, position of τ) in `free` of each arm with both free
    let mut arms: Vec<(usize, usize)> = free
        .iter()
        .enumerate()
        .filter_map(|(pk, c)| match c.role {
            Role::ArmK(j) => free
                .iter()
                .position(|t| t.role == Role::ArmTau(j))
                .map(|pt| (pk, pt)),
            _ => None,
        })
        .collect();
    arms.sort_by_key(|&(pk, _)| free[pk].index);
    let value = |p: usize, x: &[f64]| free[p].space.theta(x[p]);
    let mut pairs: Vec<(f64, f64)> = arms
        .iter()
        .map(|&(pk, pt)| (value(pk, x), value(pt, x)))
        .collect();
    pairs.sort_by(|a, b| a.1.total_cmp(&b.1));
    let within = |p: usize, v: f64| (free[p].bounds.0..=free[p].bounds.1).contains(&v);
    let moved = arms
        .iter()
        .zip(&pairs)
        .any(|(&(pk, pt), &(k, tau))| k != value(pk, x) || tau != value(pt, x));
    let fits = arms
        .iter()
        .zip(&pairs)
        .all(|(&(pk, pt), &(k, tau))| within(pk, k) && within(pt, tau));
    if !(moved && fits) {
        return false;
    }
    for (&(pk, pt), &(k, tau)) in arms.iter().zip(&pairs) {
        x[pk] = free[pk].space.x(k);
        x[pt] = free[pt].space.x(tau);
    }
    true
}

/// θ of a scene (see the module documentation).
pub fn theta(scene: &Scene) -> Vec<f64> {
    let m = &scene.material;
    let mut th = m.params.clone();
    for a in &m.viscous.arms {
        th.push(a.k_pa);
        th.push(a.eta_pa_s / a.k_pa);
    }
    th.push(m.viscous.nv_pa_s);
    th.push(m.composite.map_or(m.eps_r, |c| c.mass_fraction));
    th
}

/// Put θ into a scene's material (no allocation).
pub fn set_theta(scene: &mut Scene, th: &[f64]) {
    let m = &mut scene.material;
    let np = m.params.len();
    m.params.copy_from_slice(&th[..np]);
    for (j, a) in m.viscous.arms.iter_mut().enumerate() {
        let (k, tau) = (th[np + 2 * j], th[np + 2 * j + 1]);
        *a = Arm {
            k_pa: k,
            eta_pa_s: k * tau,
        };
    }
    let n = th.len();
    m.viscous.nv_pa_s = th[n - 2];
    match &mut m.composite {
        Some(c) => {
            c.mass_fraction = th[n - 1];
            m.eps_r = c.eps_r();
        }
        None => m.eps_r = th[n - 1],
    }
}

/// The constants a run moves, and the values `--fix` sets (index in θ, value).
#[derive(Debug, Clone)]
pub struct Chosen {
    /// Free constants, in search order.
    pub free: Vec<Constant>,
    /// Fixed values given with `NAME=VALUE`.
    pub fixed: Vec<(usize, f64)>,
}

/// Which constants are free: all of them unless `free` names some; then `fix`
/// removes names (each `NAME` or `NAME=VALUE`, the value in SI or with a unit, which
/// also sets the constant in every scene). Unknown names are refused with the list
/// of known ones.
pub fn choose(all: &[Constant], free: Option<&[String]>, fix: &[String]) -> Result<Chosen> {
    let known: Vec<&str> = all.iter().map(|c| c.name.as_str()).collect();
    let find = |name: &str, flag: &str| -> Result<&Constant> {
        if name == "eps_r" && all.iter().any(|c| c.role == Role::MassFraction) {
            return Err(Error::settings(format!(
                "{flag} eps_r: this scene's εr is its composite's mixing rule at the filler mass fraction, εr = εr(mass_fraction): they are one constant, not two"
            ))
            .with_hint(format!(
                "{flag} mass_fraction (εr is reported as derived from it), or give material.relative_permittivity as a number to identify eps_r itself"
            )));
        }
        all.iter().find(|c| c.name == name).ok_or_else(|| {
            let near = crate::material::check::did_you_mean(name, &known)
                .map(|k| format!("did you mean {k}? "))
                .unwrap_or_default();
            Error::settings(format!(
                "{flag} {name}: this scene has no constant '{name}'"
            ))
            .with_hint(format!("{near}its constants: {}", known.join(", ")))
        })
    };
    let mut chosen: Vec<Constant> = match free {
        None => all.to_vec(),
        Some(list) => {
            let mut v = Vec::new();
            for n in list {
                let c = find(n.trim(), "--free")?;
                if v.iter().any(|x: &Constant| x.name == c.name) {
                    return Err(Error::settings(format!("--free names {} twice", c.name)));
                }
                v.push(c.clone());
            }
            v
        }
    };
    let mut set = Vec::new();
    for f in fix {
        let (name, value) = match f.split_once('=') {
            Some((n, v)) => (n.trim(), Some(v.trim())),
            None => (f.trim(), None),
        };
        let c = find(name, "--fix")?;
        if let Some(v) = value {
            let x = parse_value(v, c).map_err(|e| {
                Error::settings(format!("--fix {name}={v}: {e}")).with_hint(format!(
                    "give {name} in {} (e.g. {name}=1.5e5) or with a unit",
                    c.unit
                ))
            })?;
            if c.role == Role::MassFraction {
                MASS_FRACTION.check(name, x).map_err(|bad| {
                    Error::settings(format!("--fix {name}={v}: {}", bad.msg)).with_hint(bad.hint)
                })?;
            }
            // nv = 0 is a model without dashpot (what the reduction sets)
            let zero_ok = c.role == Role::Nv && x == 0.0;
            if !x.is_finite()
                || (matches!(c.space, Space::Log) && x <= 0.0 && !zero_ok)
                || x < c.bounds.0.min(0.0)
            {
                return Err(Error::settings(format!(
                    "--fix {name}={v}: {name} must be finite{}",
                    if matches!(c.space, Space::Log) {
                        " and positive"
                    } else {
                        ""
                    }
                )));
            }
            set.push((c.index, x));
        }
        chosen.retain(|x| x.name != c.name);
    }
    if chosen.is_empty() {
        return Err(Error::settings("no constant is left free to identify")
            .with_hint("drop a --fix, or name the constants to fit with --free"));
    }
    Ok(Chosen {
        free: chosen,
        fixed: set,
    })
}

/// A value in SI: a bare number, or a number with a unit of the constant's dimension
/// (a mass fraction also as a percentage).
fn parse_value(v: &str, c: &Constant) -> std::result::Result<f64, String> {
    use crate::units::{parse_quantity, Dimension};
    if let Ok(x) = v.parse::<f64>() {
        return Ok(x);
    }
    let dim = match (c.role, c.unit) {
        (Role::MassFraction, _) => Dimension::Fraction,
        (_, "Pa") => Dimension::Stress,
        (_, "s") => Dimension::Time,
        (_, "Pa s") => Dimension::Viscosity,
        (_, unit) => return Err(format!("expected a number (SI unit {unit})")),
    };
    parse_quantity(v, dim)
}
