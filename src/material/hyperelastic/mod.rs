//! Incompressible hyperelastic strain-energy functions.
//!
//! A model supplies its energy derivatives; [`loadcase`] turns them into nominal
//! stress, tangent and parameter Jacobian for every test mode. Neo-Hookean,
//! Mooney-Rivlin and Yeoh are members of one polynomial in (I1 − 3, I2 − 3)
//! ([`polynomial`]); Gent is invariant-based ([`gent`]); Ogden is stretch-based
//! ([`ogden`]). Adding a model is one file, one line in [`ModelSpec::build`] and one
//! row in the table-driven tests.

pub mod gent;
pub mod loadcase;
pub mod ogden;
pub mod polynomial;
pub mod powers;

pub use loadcase::{Kinematics, Mode};

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Description of one parameter of a model.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamInfo {
    /// Name as written in fit files (`mu`, `C10`, `alpha1`, `Jm`, ...).
    pub name: String,
    /// SI unit (`Pa` or `1` for dimensionless).
    pub unit: &'static str,
    /// Lower bound used by the nonlinear search.
    pub lower: f64,
    /// Upper bound used by the nonlinear search.
    pub upper: f64,
    /// Whether the stress is linear in this parameter (solved exactly, never searched).
    pub linear: bool,
}

impl ParamInfo {
    /// A linear stress coefficient in Pa, unbounded.
    pub fn modulus(name: impl Into<String>) -> Self {
        ParamInfo {
            name: name.into(),
            unit: "Pa",
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
            linear: true,
        }
    }
}

/// Points evaluated together ([`StrainEnergy::nominal_stresses`],
/// [`StrainEnergy::stress_jacobians`]): each one's mode, stretch λ and ln λ (the
/// logarithm taken once per point by the fit problem, not at every evaluation).
#[derive(Debug, Clone, Copy)]
pub struct Points<'a> {
    modes: &'a [Mode],
    stretch: &'a [f64],
    ln_stretch: &'a [f64],
}

impl<'a> Points<'a> {
    /// The points of three columns of one length, `ln_stretch` holding ln λ of
    /// `stretch` (as [`f64::ln`] gives it); None where the lengths differ.
    pub fn new(modes: &'a [Mode], stretch: &'a [f64], ln_stretch: &'a [f64]) -> Option<Self> {
        (modes.len() == stretch.len() && stretch.len() == ln_stretch.len()).then_some(Points {
            modes,
            stretch,
            ln_stretch,
        })
    }

    /// Number of points.
    #[inline]
    pub fn len(&self) -> usize {
        self.stretch.len()
    }

    /// True if there are no points.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.stretch.is_empty()
    }

    /// The points `rows` (a range within `0..len()`).
    #[inline]
    pub fn rows(&self, rows: std::ops::Range<usize>) -> Points<'a> {
        Points {
            modes: &self.modes[rows.clone()],
            stretch: &self.stretch[rows.clone()],
            ln_stretch: &self.ln_stretch[rows],
        }
    }

    /// Mode of point `i`.
    #[inline(always)]
    pub fn mode(&self, i: usize) -> Mode {
        self.modes[i]
    }

    /// Stretch λ of point `i`.
    #[inline(always)]
    pub fn stretch(&self, i: usize) -> f64 {
        self.stretch[i]
    }

    /// ln λ of point `i`.
    #[inline(always)]
    pub fn ln_stretch(&self, i: usize) -> f64 {
        self.ln_stretch[i]
    }
}

/// An incompressible strain-energy function evaluated for homogeneous test modes.
///
/// All stresses are nominal (first Piola-Kirchhoff, force per reference area) in Pa.
/// A parameter vector (or Jacobian buffer) of the wrong length gives NaN, never a
/// panic; where parameters enter from outside, [`StrainEnergy::check_params`] says
/// what is wrong with them.
pub trait StrainEnergy: Send + Sync {
    /// Registry name (`neo-hookean`, `yeoh`, `ogden3`, ...).
    fn name(&self) -> String;
    /// Parameter descriptions, in the order of the parameter vector.
    fn params(&self) -> &[ParamInfo];
    /// Nominal stress P(λ) in `mode`.
    fn nominal_stress(&self, p: &[f64], mode: Mode, lam: f64) -> f64;
    /// Tangent dP/dλ (Drucker stability requires it to be positive).
    fn tangent(&self, p: &[f64], mode: Mode, lam: f64) -> f64;
    /// The tangent of `mode` as a positive factor times a sum of powers of λ
    /// ([`powers`]), for the Drucker check to bound on whole stretch intervals; None
    /// where the model has no such form (the check then evaluates
    /// [`StrainEnergy::tangent`] at every stretch of its grid).
    fn tangent_powers(&self, _p: &[f64], _mode: Mode) -> Option<powers::TangentPowers> {
        None
    }
    /// Where the tangent is linear in the parameters, T = Σ p_k·B_k(λ) in `mode`
    /// (the polynomial models): the bases B_k, one per parameter, fixed by the model.
    /// The Drucker check turns them once into coefficients on fixed stretch cells
    /// (`fit/drucker.rs`), so that a check is a small product with the parameters.
    /// None (the default) where the tangent is not linear in the parameters.
    fn tangent_basis(&self, _mode: Mode) -> Option<&'static [powers::Laurent]> {
        None
    }
    /// True if the block evaluators ([`StrainEnergy::nominal_stresses`],
    /// [`StrainEnergy::stress_jacobians`]) read the points' ln λ
    /// ([`Points::ln_stretch`]): a fit problem takes the logarithms only then. The
    /// default, true, is always safe.
    fn reads_ln_stretch(&self) -> bool {
        true
    }
    /// The stress and tangent of `mode` at parameters `p` prepared for many
    /// stretches, the same numbers as [`StrainEnergy::nominal_stress`] and
    /// [`StrainEnergy::tangent`] without a dynamic call each (the simulator's
    /// right-hand side); None (the default) where the model has no prepared form.
    fn prepared(&self, _p: &[f64], _mode: Mode) -> Option<polynomial::Prepared> {
        None
    }
    /// ∂P/∂p written into `out` (length = number of parameters). No allocation.
    fn stress_jacobian(&self, p: &[f64], mode: Mode, lam: f64, out: &mut [f64]);
    /// Nominal stress at each of `pts` into `out` (one value a point): by default
    /// [`StrainEnergy::nominal_stress`] at every point; a model may override it to
    /// evaluate the points in vector lanes, giving the same bits as its own
    /// per-point method. No allocation.
    fn nominal_stresses(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate().take(pts.len()) {
            *o = self.nominal_stress(p, pts.mode(i), pts.stretch(i));
        }
    }
    /// ∂P/∂p at each of `pts`, row after row into `out` (`p.len()` values a point,
    /// point i's at `out[i·k..(i + 1)·k]`): by default
    /// [`StrainEnergy::stress_jacobian`] at every point; a model may override it
    /// as [`StrainEnergy::nominal_stresses`]. No allocation.
    fn stress_jacobians(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        let k = p.len().max(1);
        for (i, row) in out.chunks_exact_mut(k).enumerate().take(pts.len()) {
            self.stress_jacobian(p, pts.mode(i), pts.stretch(i), row);
        }
    }
    /// Small-strain shear modulus μ0 (Pa); Young's modulus is 3μ0.
    fn initial_shear_modulus(&self, p: &[f64]) -> f64;
    /// Deterministic, physically informed starting values of the nonlinear
    /// parameters (in parameter order, skipping linear ones). Empty for linear models.
    fn nonlinear_starts(&self, _max_i1_minus_3: f64) -> Vec<Vec<f64>> {
        Vec::new()
    }
    /// Bounds of every parameter given the data's largest I1 − 3 (the Gent limit
    /// must lie beyond the data). Defaults to [`ParamInfo`] bounds.
    fn bounds(&self, _max_i1_minus_3: f64) -> Vec<(f64, f64)> {
        self.params().iter().map(|p| (p.lower, p.upper)).collect()
    }
    /// The linear parameter whose value multiplies every ∂P/∂p_j of the nonlinear
    /// parameter j, if one does: P = Σ_l p_l·A_l(θ) with θ_j inside one A_l alone
    /// (Ogden's αᵢ in μᵢ's term, Gent's Jm in μ's), so ∂P/∂θ_j = p_l·∂A_l/∂θ_j.
    /// Variable projection then takes ∂P/∂θ at the solved coefficients from the one
    /// evaluation at unit ones that also gives A(θ). None (the default) where no
    /// single coefficient does, or for a linear parameter.
    fn coefficient_of(&self, _j: usize) -> Option<usize> {
        None
    }
    /// True if the stress is linear in every parameter (exact linear least squares).
    fn linear_in_params(&self) -> bool {
        self.params().iter().all(|p| p.linear)
    }
    /// Check a parameter vector before it is used: one finite value per parameter,
    /// in the order of [`StrainEnergy::params`].
    fn check_params(&self, p: &[f64]) -> Result<()> {
        let names: Vec<&str> = self.params().iter().map(|i| i.name.as_str()).collect();
        if p.len() != names.len() {
            return Err(Error::settings(format!(
                "{} takes {} parameters ({}), found {}",
                self.name(),
                names.len(),
                names.join(", "),
                p.len()
            )));
        }
        match names.iter().zip(p).find(|(_, v)| !v.is_finite()) {
            Some((name, v)) => Err(Error::settings(format!(
                "{} parameter {name} must be a finite number, found {v}",
                self.name()
            ))),
            None => Ok(()),
        }
    }
}

/// A model's stress and tangent at fixed parameters in one mode: by its prepared
/// form ([`StrainEnergy::prepared`]) where it has one, else by the dynamic calls,
/// the same numbers either way. The one place choosing between the two, for the
/// fit's predictions, the Drucker check and the simulator's plant. The model and
/// parameters are passed at each call (the plant owns both beside this), and must
/// be those it was made from.
#[derive(Debug, Clone)]
pub struct AtParams {
    mode: Mode,
    prepared: Option<polynomial::Prepared>,
}

impl AtParams {
    /// `model` at parameters `p` in `mode`, prepared where it can be.
    pub fn new(model: &dyn StrainEnergy, p: &[f64], mode: Mode) -> Self {
        AtParams {
            mode,
            prepared: model.prepared(p, mode),
        }
    }

    /// Nominal stress P(λ) (Pa): [`StrainEnergy::nominal_stress`].
    #[inline(always)]
    pub fn stress(&self, model: &dyn StrainEnergy, p: &[f64], lam: f64) -> f64 {
        match &self.prepared {
            Some(q) => q.stress(lam),
            None => model.nominal_stress(p, self.mode, lam),
        }
    }

    /// Tangent dP/dλ (Pa): [`StrainEnergy::tangent`].
    #[inline(always)]
    pub fn tangent(&self, model: &dyn StrainEnergy, p: &[f64], lam: f64) -> f64 {
        match &self.prepared {
            Some(q) => q.tangent(lam),
            None => model.tangent(p, self.mode, lam),
        }
    }
}

/// A model with [`StrainEnergy::coefficient_of`] hidden, everything else the
/// model's own: variable projection then evaluates it a second time at the solved
/// coefficients for ∂A/∂θ (the method for models without that information, and
/// the baseline the projection's test and criterion bench compare against).
pub struct WithoutCoefficients(pub Box<dyn StrainEnergy>);

impl StrainEnergy for WithoutCoefficients {
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
        self.0.tangent(p, mode, lam)
    }
    fn tangent_powers(&self, p: &[f64], mode: Mode) -> Option<powers::TangentPowers> {
        self.0.tangent_powers(p, mode)
    }
    fn tangent_basis(&self, mode: Mode) -> Option<&'static [powers::Laurent]> {
        self.0.tangent_basis(mode)
    }
    fn reads_ln_stretch(&self) -> bool {
        self.0.reads_ln_stretch()
    }
    fn prepared(&self, p: &[f64], mode: Mode) -> Option<polynomial::Prepared> {
        self.0.prepared(p, mode)
    }
    fn stress_jacobian(&self, p: &[f64], mode: Mode, lam: f64, out: &mut [f64]) {
        self.0.stress_jacobian(p, mode, lam, out)
    }
    fn nominal_stresses(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        self.0.nominal_stresses(p, pts, out)
    }
    fn stress_jacobians(&self, p: &[f64], pts: Points<'_>, out: &mut [f64]) {
        self.0.stress_jacobians(p, pts, out)
    }
    fn initial_shear_modulus(&self, p: &[f64]) -> f64 {
        self.0.initial_shear_modulus(p)
    }
    fn nonlinear_starts(&self, max_i1_minus_3: f64) -> Vec<Vec<f64>> {
        self.0.nonlinear_starts(max_i1_minus_3)
    }
    fn bounds(&self, max_i1_minus_3: f64) -> Vec<(f64, f64)> {
        self.0.bounds(max_i1_minus_3)
    }
    fn linear_in_params(&self) -> bool {
        self.0.linear_in_params()
    }
    fn check_params(&self, p: &[f64]) -> Result<()> {
        self.0.check_params(p)
    }
}

/// How Ogden's coefficients are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum OgdenForm {
    /// El Atrache Ceballos (2021) Eq. 2.9: W = Σ 2μi/αi² (λ1^αi + λ2^αi + λ3^αi − 3);
    /// μ0 = Σμi, the form of Abaqus and CalculiX (`abaqus`; `seed`, its old name, is
    /// still read).
    #[default]
    #[serde(alias = "seed")]
    Abaqus,
    /// Ogden (1972): W = Σ μi/αi (λ1^αi + λ2^αi + λ3^αi − 3); μ0 = ½Σμiαi.
    Original,
}

impl OgdenForm {
    /// What `--ogden-form seed` (the former name of [`OgdenForm::Abaqus`], still
    /// accepted) prints: the word "seed" is kept for random seeds (issue 35, §6).
    pub const FORMER_NAME_NOTE: &'static str = "note: Ogden form 'seed' is now called 'abaqus' (El Atrache Ceballos (2021) Eq. 2.9, the form Abaqus and CalculiX write); the old name still works but is deprecated: use --ogden-form abaqus";
}

impl std::fmt::Display for OgdenForm {
    /// The name the flag (`--ogden-form`) and the fit file use.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OgdenForm::Abaqus => "abaqus",
            OgdenForm::Original => "original",
        })
    }
}

/// A model as the user names it: plain data, turned into an evaluator by [`ModelSpec::build`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelSpec {
    /// Registry name.
    pub name: String,
    /// Ogden coefficient form (only for `ogdenN`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub form: Option<OgdenForm>,
}

/// Names accepted by `--model` (besides `auto`).
pub const MODEL_NAMES: [&str; 8] = [
    "neo-hookean",
    "mooney-rivlin",
    "yeoh",
    "gent",
    "ogden1",
    "ogden2",
    "ogden3",
    "ogden4",
];

impl ModelSpec {
    /// A spec from a registry name and an Ogden form (ignored for other models).
    pub fn new(name: &str, form: OgdenForm) -> Self {
        let form = name.starts_with("ogden").then_some(form);
        ModelSpec {
            name: name.to_string(),
            form,
        }
    }

    /// Build the evaluator. The registry: one line per model.
    pub fn build(&self) -> Result<Box<dyn StrainEnergy>> {
        let form = self.form.unwrap_or_default();
        Ok(match self.name.as_str() {
            "neo-hookean" => Box::new(polynomial::Polynomial::neo_hookean()),
            "mooney-rivlin" => Box::new(polynomial::Polynomial::mooney_rivlin()),
            "yeoh" => Box::new(polynomial::Polynomial::yeoh()),
            "gent" => Box::new(gent::Gent::new()),
            "ogden1" => Box::new(ogden::Ogden::new(1, form)),
            "ogden2" => Box::new(ogden::Ogden::new(2, form)),
            "ogden3" => Box::new(ogden::Ogden::new(3, form)),
            "ogden4" => Box::new(ogden::Ogden::new(4, form)),
            other => {
                return Err(Error::settings(format!("unknown model '{other}'"))
                    .with_hint(format!("use one of {} or auto", MODEL_NAMES.join(", "))))
            }
        })
    }
}
