//! The design manifest (TOML) → a checked [`Design`]. The format is documented in
//! `docs/rank.md`; every error names the manifest's line and column (or the
//! referenced file, whose own reader locates it) and says what to do.
//!
//! ```toml
//! name = "Silicone fillers for a thin-layer stack"
//! [actuator]
//! scene = "stack_silicone.toml"          # geometry, load, source, tolerances; material replaced
//! [drive]
//! voltage = "800 V"                      # or breakdown_fraction = 0.5 (of each candidate's Eb)
//! frequency = "100 Hz"                   # tan δ is given at this frequency; loss per cycle
//! step_span = "100 ms"                   # window of the step response (10–90 % time)
//! step_samples = 200
//! [[matrix]]
//! name = "Sylgard 184"
//! source = "El Atrache Ceballos (2021) Table 5.1"   # cited in every number's provenance
//! density = "1.03 g/cm3"
//! eps_r = 2.72
//! tan_delta = 0.0012
//! breakdown = "19 V/um"
//! hyperelastic = { model = "neo-hookean", parameters = { mu = "250 kPa" } }  # or { fit = ... }, { preset = ... }
//! viscous = { nv = "10 Pa s", arms = [ { k = "50 kPa", tau = "20 ms" } ] }   # optional: else the scene's
//! [[filler]]
//! name = "BaTiO3"
//! density = "6.02 g/cm3"
//! eps_r = 150
//! [[series]]
//! matrix = "Sylgard 184"
//! filler = "BaTiO3"
//! basis = "weight"                       # or volume
//! loadings = "0:0.6:7"                   # or a list [0, 0.1, "20 %"]
//! permittivity = { composite = "fits/x-composite.json", rule = "bruggeman" }  # or { rule = "maxwell-garnett" }
//! stiffening = "guth-gold"               # einstein | none
//! [[series.measured]]
//! loading = 0.2
//! tan_delta = 0.002
//! breakdown = "17 V/um"
//! hyperelastic = { fit = "fits/s20-neo-hookean.json" }
//! ```

use super::candidate::Stiffening;
use super::Provenance;
use crate::error::{Error, Location, Result};
use crate::fit::composite::Basis;
use crate::material::check::{
    check_hyperelastic, d, did_you_mean, Domain, BREAKDOWN, PERMITTIVITY,
};
use crate::material::dielectric::{MixingRule, Mixture};
use crate::material::file::{self, Arm, HyperelasticPart, Spread, Viscous};
use crate::material::hyperelastic::{ModelSpec, OgdenForm, MODEL_NAMES};
use crate::sim::scene::Scene;
use crate::sim::{budget, presets};
use crate::units::{parse_quantity, parse_uncertain, Dimension};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Plausible loss tangents.
pub const TAN_DELTA: Domain = d(
    "loss tangent",
    "",
    1e-7,
    10.0,
    true,
    "elastomers have tan δ of 1e-4–0.1; above 10 the material is a conductor",
);
/// Fewest samples of the step window (the 10–90 % time is read between them).
pub const MIN_STEP_SAMPLES: usize = 20;

/// A quantity written as a string with unit or as a bare SI number.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Text {
    Num(f64),
    Str(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    name: Option<String>,
    actuator: ActuatorSpec,
    drive: DriveSpec,
    #[serde(default)]
    matrix: Vec<MatrixSpec>,
    #[serde(default)]
    filler: Vec<FillerSpec>,
    #[serde(default)]
    series: Vec<SeriesSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ActuatorSpec {
    scene: Spanned<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DriveSpec {
    voltage: Option<Spanned<Text>>,
    breakdown_fraction: Option<Spanned<f64>>,
    frequency: Spanned<Text>,
    step_span: Spanned<Text>,
    step_samples: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MatrixSpec {
    name: Spanned<String>,
    source: Option<String>,
    density: Spanned<Text>,
    eps_r: Spanned<Text>,
    tan_delta: Spanned<Text>,
    breakdown: Spanned<toml::Value>,
    hyperelastic: Spanned<HyperSpec>,
    viscous: Option<Spanned<ViscousSpec>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HyperSpec {
    preset: Option<String>,
    fit: Option<String>,
    model: Option<String>,
    parameters: Option<BTreeMap<String, Spanned<Text>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ViscousSpec {
    preset: Option<String>,
    fit: Option<String>,
    nv: Option<Spanned<Text>>,
    arms: Option<Vec<Spanned<ArmSpec>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ArmSpec {
    k: Spanned<Text>,
    eta: Option<Spanned<Text>>,
    tau: Option<Spanned<Text>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FillerSpec {
    name: Spanned<String>,
    source: Option<String>,
    density: Spanned<Text>,
    eps_r: Spanned<Text>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Loadings {
    List(Vec<Text>),
    Range(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SeriesSpec {
    name: Option<Spanned<String>>,
    matrix: Spanned<String>,
    filler: Option<Spanned<String>>,
    basis: Option<Spanned<String>>,
    loadings: Option<Spanned<Loadings>>,
    permittivity: Option<Spanned<PermSpec>>,
    stiffening: Option<Spanned<String>>,
    #[serde(default)]
    measured: Vec<Spanned<MeasuredSpec>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PermSpec {
    rule: Option<Spanned<String>>,
    shape: Option<Spanned<f64>>,
    composite: Option<Spanned<String>>,
    frequency: Option<Spanned<Text>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeasuredSpec {
    loading: Spanned<Text>,
    source: Option<String>,
    eps_r: Option<Spanned<Text>>,
    tan_delta: Option<Spanned<Text>>,
    breakdown: Option<Spanned<toml::Value>>,
    hyperelastic: Option<Spanned<HyperSpec>>,
}

/// A value with where it comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct Stated<T> {
    /// The value (SI).
    pub value: T,
    /// Its standard error (of μ0 for a hyperelastic part, in Pa): from a fit file,
    /// or written in the manifest as `value ± σ`. None for a preset or a value
    /// written without ±, which the ranking's confidence takes as exact.
    pub std_error: Option<f64>,
    /// Stated (written in the manifest or the scene), fitted (a fit file) or
    /// predicted.
    pub provenance: Provenance,
    /// `manifest:line (note)` or the fit file.
    pub source: String,
    /// What a candidate using it is warned of (a breakdown fit that could not be
    /// scaled to the actuator, or was extrapolated).
    pub warnings: Vec<String>,
}

/// How each candidate is driven.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Level {
    /// A fixed voltage (V).
    Voltage(f64),
    /// A share of each candidate's breakdown voltage at rest, f·Eb·gap(λ0).
    BreakdownFraction(f64),
}

/// The drive of the ranking.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    /// Voltage or share of the breakdown voltage.
    pub level: Level,
    /// Drive frequency (Hz): tan δ is given at it; loss per cycle of a 0–V sine.
    pub frequency_hz: f64,
    /// Window of the step response (s).
    pub step_span_s: f64,
    /// Output samples of the step window.
    pub step_samples: usize,
}

/// A matrix elastomer.
#[derive(Debug, Clone)]
pub struct Matrix {
    /// Name.
    pub name: String,
    /// Density (kg/m³).
    pub density: f64,
    /// Relative permittivity.
    pub eps_r: Stated<f64>,
    /// Loss tangent at the drive frequency.
    pub tan_delta: Stated<f64>,
    /// Breakdown field (V/m).
    pub breakdown: Stated<f64>,
    /// Hyperelastic constants.
    pub hyperelastic: Stated<HyperelasticPart>,
    /// Viscous constants.
    pub viscous: Stated<Viscous>,
}

/// A filler.
#[derive(Debug, Clone)]
pub struct Filler {
    /// Name.
    pub name: String,
    /// Density (kg/m³).
    pub density: f64,
    /// Relative permittivity the stated mixing rules use (an effective value for a
    /// powder, not the bulk crystal's).
    pub eps_r: Stated<f64>,
}

/// Where a series' εr(loading) comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum PermittivityModel {
    /// A stated mixing rule with the matrix's and the filler's εr (predicted).
    Rule {
        /// The rule.
        rule: MixingRule,
        /// Yamada's shape factor n (3 = Maxwell Garnett).
        shape: f64,
    },
    /// A composite fit's rule: its εm, εf (and n) and phase densities (fitted).
    Composite {
        /// The rule with its constants.
        mixture: Mixture,
        /// Frequency of that fit (Hz).
        freq_hz: f64,
        /// The fit file.
        file: String,
        /// The standard errors and correlation of εm, εf (and n) it states.
        spread: Spread,
    },
}

/// A value written in the manifest with its standard uncertainty (`value ± σ`;
/// None when written without ±).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Uncertain {
    /// The value (SI).
    pub value: f64,
    /// One standard uncertainty (SI).
    pub std_error: Option<f64>,
}

/// Measured properties of one composite of a series.
#[derive(Debug, Clone)]
pub struct MeasuredPoint {
    /// Loading on the series' basis.
    pub loading: f64,
    /// `manifest:line (note)`.
    pub source: String,
    /// εr.
    pub eps_r: Option<Uncertain>,
    /// Loss tangent at the drive frequency.
    pub tan_delta: Option<Uncertain>,
    /// Breakdown field (V/m): stated, or from a breakdown fit scaled to the
    /// actuator.
    pub breakdown: Option<Stated<f64>>,
    /// Hyperelastic constants (fitted from a file or written in the manifest).
    pub hyperelastic: Option<Stated<HyperelasticPart>>,
}

/// One family of candidates: a matrix, optionally a filler at several loadings.
#[derive(Debug, Clone)]
pub struct Series {
    /// Name (default "matrix + filler").
    pub name: String,
    /// Index into [`Design::matrices`].
    pub matrix: usize,
    /// Index into [`Design::fillers`] (None: the matrix alone).
    pub filler: Option<usize>,
    /// Basis of the loadings.
    pub basis: Basis,
    /// Loadings (fractions on the basis, sorted, distinct).
    pub loadings: Vec<f64>,
    /// εr(loading) (None without a filler).
    pub permittivity: Option<PermittivityModel>,
    /// Stiffening of the matrix by the filler.
    pub stiffening: Stiffening,
    /// Measured composites, by loading.
    pub measured: Vec<MeasuredPoint>,
}

/// A checked design manifest.
#[derive(Clone)]
pub struct Design {
    /// Manifest path as given.
    pub path: PathBuf,
    /// Design name.
    pub name: String,
    /// SHA-256 over the manifest and every file it reads (the scene, the files the
    /// scene reads, and fit files): shards of one sweep carry it.
    pub sha256: String,
    /// The actuator scene (its material is replaced per candidate).
    pub scene: Scene,
    /// Its path.
    pub scene_path: PathBuf,
    /// The drive.
    pub drive: Drive,
    /// Matrices.
    pub matrices: Vec<Matrix>,
    /// Fillers.
    pub fillers: Vec<Filler>,
    /// Series.
    pub series: Vec<Series>,
}

/// 1-based line and column of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map(|i| i + 1).unwrap_or(0);
    (line, before[start..].chars().count() + 1)
}

struct Ctx<'a> {
    path: &'a Path,
    dir: &'a Path,
    text: &'a str,
    /// Files read (for the design hash), in reading order.
    files: std::cell::RefCell<Vec<PathBuf>>,
}

type Span = std::ops::Range<usize>;

impl Ctx<'_> {
    fn err(&self, span: &Span, msg: impl Into<String>) -> Error {
        let (l, c) = line_col(self.text, span.start);
        Error::input(Location::at(self.path, l, c), msg)
    }
    /// `manifest:line`, with the note when there is one.
    fn here(&self, span: &Span, note: &Option<String>) -> String {
        let line = line_col(self.text, span.start).0;
        match note {
            Some(n) => format!("{}:{line} ({n})", self.path.display()),
            None => format!("{}:{line}", self.path.display()),
        }
    }
    fn quantity(&self, q: &Spanned<Text>, dim: Dimension, key: &str) -> Result<f64> {
        let v = match q.get_ref() {
            Text::Num(v) => *v,
            Text::Str(s) => {
                parse_quantity(s, dim).map_err(|e| self.err(&q.span(), format!("{key}: {e}")))?
            }
        };
        match v.is_finite() {
            true => Ok(v),
            false => Err(self
                .err(&q.span(), format!("{key} must be a finite number"))
                .with_hint(format!("e.g. {key} = \"1 {}\"", dim.si()))),
        }
    }
    /// A value that may carry a standard uncertainty, `value ± σ`: finite, and
    /// within `dom` where given.
    fn uncertain(
        &self,
        q: &Spanned<Text>,
        dim: Dimension,
        dom: Option<&Domain>,
        key: &str,
    ) -> Result<Uncertain> {
        let hint = || {
            format!(
                "e.g. {key} = \"1.5 ± 0.1{}\" (value ± one standard uncertainty)",
                match dim {
                    Dimension::Number => String::new(),
                    d => format!(" {}", d.si()),
                }
            )
        };
        let u = match q.get_ref() {
            Text::Num(v) => Uncertain {
                value: *v,
                std_error: None,
            },
            Text::Str(s) => parse_uncertain(s, dim)
                .map(|x| Uncertain {
                    value: x.value,
                    std_error: x.tolerance,
                })
                .map_err(|e| self.err(&q.span(), format!("{key}: {e}")).with_hint(hint()))?,
        };
        if !u.value.is_finite() {
            return Err(self
                .err(&q.span(), format!("{key} must be a finite number"))
                .with_hint(hint()));
        }
        Ok(match dom {
            Some(dom) => Uncertain {
                value: self.checked(&q.span(), dom, key, u.value)?,
                ..u
            },
            None => u,
        })
    }
    fn checked(&self, span: &Span, dom: &Domain, key: &str, v: f64) -> Result<f64> {
        dom.check(key, v)
            .map_err(|x| self.err(span, x.msg).with_hint(x.hint))
    }
    /// A file named in the manifest, relative to it; recorded for the hash.
    fn file(&self, span: &Span, key: &str, f: &str) -> Result<PathBuf> {
        let p = self.dir.join(f);
        if !p.is_file() {
            return Err(self
                .err(span, format!("{key}: cannot read '{}'", p.display()))
                .with_hint("paths are relative to the design manifest"));
        }
        self.files.borrow_mut().push(p.clone());
        Ok(p)
    }
    fn unknown(&self, span: &Span, key: &str, found: &str, known: &[&str]) -> Error {
        let hint = match did_you_mean(found, known) {
            Some(m) => format!("did you mean '{m}'? known: {}", known.join(", ")),
            None => format!("known: {}", known.join(", ")),
        };
        self.err(span, format!("{key}: unknown '{found}'"))
            .with_hint(hint)
    }

    /// A breakdown field: stated (`"19 V/um"`, `"19 ± 1 V/um"`, a bare SI number)
    /// or `{ fit = "fits/x-breakdown.json" }`, a breakdown fit whose α (and σ)
    /// is carried to the actuator's film ([`Film`]; `BreakdownFit::strength`).
    /// What was scaled is the source's note; what could not be scaled or was
    /// extrapolated is also a warning of every candidate that uses it.
    fn breakdown(
        &self,
        q: &Spanned<toml::Value>,
        key: &str,
        note: &Option<String>,
        film: &Film,
    ) -> Result<Stated<f64>> {
        let span = q.span();
        let text = match q.get_ref() {
            toml::Value::String(s) => Some(Text::Str(s.clone())),
            toml::Value::Float(v) => Some(Text::Num(*v)),
            toml::Value::Integer(v) => Some(Text::Num(*v as f64)),
            _ => None,
        };
        if let Some(t) = text {
            let u = self.uncertain(
                &Spanned::new(span.clone(), t),
                Dimension::ElectricField,
                Some(&BREAKDOWN),
                key,
            )?;
            return Ok(Stated {
                value: u.value,
                std_error: u.std_error,
                provenance: Provenance::Stated,
                source: self.here(&span, note),
                warnings: Vec::new(),
            });
        }
        let hint = "breakdown = \"19 V/um\", \"19 ± 1 V/um\" or { fit = \"fits/x-breakdown.json\" } (written by dea-fit breakdown --out)";
        let f = match q.get_ref() {
            toml::Value::Table(t) if t.len() == 1 => match t.get("fit") {
                Some(toml::Value::String(f)) => f.clone(),
                _ => {
                    let k = t.keys().next().map_or("", String::as_str);
                    return Err(self
                        .err(
                            &span,
                            format!("{key}: '{k}' is not a key of a breakdown reference"),
                        )
                        .with_hint(hint));
                }
            },
            _ => {
                return Err(self
                    .err(
                        &span,
                        format!("{key}: expected a field with a unit or {{ fit = \"...\" }}"),
                    )
                    .with_hint(hint))
            }
        };
        let path = self.file(&span, &format!("{key}.fit"), &f)?;
        // the manifest's place first, then the fit file's own error
        let fit = file::read_breakdown(&path).map_err(|e| match e {
            Error::Input { loc, msg, hint } => {
                let (l, c) = line_col(self.text, span.start);
                Error::Input {
                    loc: Location::at(self.path, l, c),
                    msg: format!("{key}.fit = \"{f}\": {loc}: {msg}"),
                    hint,
                }
            }
            other => self.err(&span, format!("{key}.fit = \"{f}\": {other}")),
        })?;
        let s = fit.strength(
            Some(film.area_m2),
            Some(film.thickness_m),
            None,
            &path.display().to_string(),
        );
        let value = self.checked(&span, &BREAKDOWN, key, s.field)?;
        // "α × …" notes say what was scaled; the others what was not, or was
        // extrapolated (material::file::BreakdownFit::strength)
        let warnings = s
            .notes
            .iter()
            .filter(|n| !n.starts_with("α ×") && !n.starts_with("three-parameter"))
            .map(|n| format!("breakdown of {f}: {n}"))
            .collect();
        Ok(Stated {
            value,
            std_error: s.std_error,
            provenance: Provenance::Fitted,
            source: format!(
                "{} (Weibull α at {}: {})",
                s.source,
                film.describe,
                s.notes.join("; ")
            ),
            warnings,
        })
    }

    /// A hyperelastic part: a preset, a fit file (hyperelastic or identified) or a
    /// model with its parameters by name.
    fn hyperelastic(
        &self,
        h: &Spanned<HyperSpec>,
        key: &str,
        note: &Option<String>,
    ) -> Result<Stated<HyperelasticPart>> {
        let span = h.span();
        let s = h.get_ref();
        let given = [s.preset.is_some(), s.fit.is_some(), s.model.is_some()];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(self
                .err(&span, format!("{key} takes one of preset, fit, model"))
                .with_hint("e.g. { model = \"neo-hookean\", parameters = { mu = \"250 kPa\" } } or { fit = \"fits/x.json\" }"));
        }
        if s.parameters.is_some() && s.model.is_none() {
            return Err(self
                .err(&span, format!("{key}.parameters go with model"))
                .with_hint("drop parameters, or give model = \"...\" instead"));
        }
        if let Some(p) = &s.preset {
            return match p.as_str() {
                "vhb4910-yeoh" => Ok(Stated {
                    value: HyperelasticPart {
                        spec: ModelSpec::new("yeoh", OgdenForm::Abaqus),
                        params: presets::VHB4910_YEOH_PA.to_vec(),
                        ranges: None,
                    },
                    std_error: None,
                    provenance: Provenance::Fitted,
                    source: "preset vhb4910-yeoh (El Atrache Ceballos (2021) Table 3.2, Wissler & Mazza 2005)".into(),
                    warnings: Vec::new(),
                }),
                o => Err(self.unknown(&span, &format!("{key}.preset"), o, &["vhb4910-yeoh"])),
            };
        }
        if let Some(f) = &s.fit {
            let path = self.file(&span, &format!("{key}.fit"), f)?;
            let (value, spread) = file::read_hyperelastic_spread(&path)?;
            let model = value.evaluator()?;
            let grad = file::gradient(&value.params, |p| model.initial_shear_modulus(p));
            return Ok(Stated {
                std_error: spread.propagate(&grad),
                value,
                provenance: Provenance::Fitted,
                source: path.display().to_string(),
                warnings: Vec::new(),
            });
        }
        let m = s.model.as_deref().unwrap_or_default();
        if !MODEL_NAMES.contains(&m) {
            return Err(self.unknown(&span, &format!("{key}.model"), m, &MODEL_NAMES));
        }
        let spec = ModelSpec::new(m, OgdenForm::Abaqus);
        let model = spec.build()?;
        let given = s.parameters.as_ref();
        let names: Vec<&str> = model.params().iter().map(|p| p.name.as_str()).collect();
        if let Some(g) = given {
            if let Some(k) = g.keys().find(|k| !names.contains(&k.as_str())) {
                return Err(self.unknown(&g[k].span(), &format!("{key}.parameters"), k, &names));
            }
        }
        let mut params = Vec::new();
        let mut sigmas = Vec::new();
        for info in model.params() {
            let Some(q) = given.and_then(|g| g.get(&info.name)) else {
                return Err(self
                    .err(&span, format!("{key}.parameters.{} is missing", info.name))
                    .with_hint(file::expected_params(model.as_ref())));
            };
            let dim = match info.unit {
                "Pa" => Dimension::Stress,
                _ => Dimension::Number,
            };
            let u = self.uncertain(q, dim, None, &info.name)?;
            params.push(u.value);
            sigmas.push(u.std_error);
        }
        check_hyperelastic(model.as_ref(), &params, &format!("{key}.parameters"))
            .map_err(|v| self.err(&span, v.msg).with_hint(v.hint))?;
        // σ of μ0 from the parameters' σ, taken as independent (GUM eq. 10)
        let std_error = sigmas.iter().any(Option::is_some).then(|| {
            let grad = file::gradient(&params, |p| model.initial_shear_modulus(p));
            grad.iter()
                .zip(&sigmas)
                .map(|(g, s)| (g * s.unwrap_or(0.0)).powi(2))
                .sum::<f64>()
                .sqrt()
        });
        Ok(Stated {
            value: HyperelasticPart {
                spec,
                params,
                ranges: None,
            },
            std_error,
            provenance: Provenance::Stated,
            source: self.here(&span, note),
            warnings: Vec::new(),
        })
    }

    /// A viscous part: a preset, a fit file (relaxation or identified, with an
    /// optional nv), or arms and nv.
    fn viscous(
        &self,
        v: &Spanned<ViscousSpec>,
        key: &str,
        note: &Option<String>,
    ) -> Result<Stated<Viscous>> {
        let span = v.span();
        let s = v.get_ref();
        let kinds = [s.preset.is_some(), s.fit.is_some(), s.arms.is_some()];
        let n = kinds.iter().filter(|g| **g).count();
        if n > 1 || (n == 0 && s.nv.is_none()) || (s.preset.is_some() && s.nv.is_some()) {
            return Err(self
                .err(&span, format!("{key} takes one of preset, fit (with an optional nv), or arms and nv"))
                .with_hint("e.g. { preset = \"elatrache2021-table-4.2\" } or { nv = \"10 Pa s\", arms = [ { k = \"50 kPa\", tau = \"20 ms\" } ] }"));
        }
        let nv = match &s.nv {
            Some(q) => Some(self.checked(
                &q.span(),
                &crate::material::check::DASHPOT,
                &format!("{key}.nv"),
                self.quantity(q, Dimension::Viscosity, "nv")?,
            )?),
            None => None,
        };
        if let Some(p) = &s.preset {
            let names = presets::viscous_preset_names();
            return presets::viscous(p)
                .map(|value| Stated {
                    value,
                    std_error: None,
                    provenance: Provenance::Fitted,
                    source: format!(
                        "preset {}",
                        crate::material::viscoelastic::current_preset_name(p).0
                    ),
                    warnings: Vec::new(),
                })
                .ok_or_else(|| self.unknown(&span, &format!("{key}.preset"), p, &names));
        }
        if let Some(f) = &s.fit {
            let path = self.file(&span, &format!("{key}.fit"), f)?;
            let (arms, stated) = file::read_viscous(&path)?;
            if stated.is_some() && nv.is_some() {
                return Err(self
                    .err(
                        &span,
                        format!("{key}.nv conflicts with the nv of {key}.fit"),
                    )
                    .with_hint("an identified material states its dashpot: drop nv here"));
            }
            return Ok(Stated {
                value: Viscous {
                    nv_pa_s: stated.or(nv).unwrap_or(0.0),
                    arms,
                },
                std_error: None,
                provenance: Provenance::Fitted,
                source: path.display().to_string(),
                warnings: Vec::new(),
            });
        }
        let mut arms = Vec::new();
        for (i, a) in s.arms.iter().flatten().enumerate() {
            let k_key = format!("{key}.arms[{i}]");
            let at = a.get_ref();
            let k = self.checked(
                &at.k.span(),
                &crate::material::check::ARM_MODULUS,
                &format!("{k_key}.k"),
                self.quantity(&at.k, Dimension::Stress, "k")?,
            )?;
            let eta = match (&at.eta, &at.tau) {
                (Some(e), None) => self.quantity(e, Dimension::Viscosity, "eta")?,
                (None, Some(t)) => {
                    k * self.checked(
                        &t.span(),
                        &crate::material::check::ARM_TIME,
                        &format!("{k_key}.tau"),
                        self.quantity(t, Dimension::Time, "tau")?,
                    )?
                }
                _ => {
                    return Err(self
                        .err(&a.span(), format!("{k_key} takes eta or tau (one of them)"))
                        .with_hint("e.g. { k = \"50 kPa\", tau = \"20 ms\" }"))
                }
            };
            self.checked(
                &a.span(),
                &crate::material::check::ARM_TIME,
                &format!("{k_key}.tau"),
                eta / k,
            )?;
            arms.push(Arm {
                k_pa: k,
                eta_pa_s: eta,
            });
        }
        Ok(Stated {
            value: Viscous {
                nv_pa_s: nv.unwrap_or(0.0),
                arms,
            },
            std_error: None,
            provenance: Provenance::Stated,
            source: self.here(&span, note),
            warnings: Vec::new(),
        })
    }
}

/// Read and check a design manifest.
pub fn read(path: &Path) -> Result<Design> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &bytes)
}

/// Parse and check manifest bytes that came from `path` (relative files are read
/// beside it).
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Design> {
    let text = std::str::from_utf8(bytes)
        .map_err(|_| Error::input(Location::file(path), "the manifest is not UTF-8 text"))?;
    // `{ target = "…" }`: a step's fit file of the project above (issue 37)
    let resolved = crate::project::refs::resolve(text, path)?;
    let text: &str = &resolved;
    let dir = path.parent().unwrap_or(Path::new(""));
    let cx = Ctx {
        path,
        dir,
        text,
        files: Default::default(),
    };
    let spec: Spec = toml::from_str(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        let hint = match crate::material::check::unknown_name_hint(&msg) {
            Some(h) => format!("{h} (the design manifest format: docs/rank.md)"),
            None => "see the design manifest format in docs/rank.md".into(),
        };
        match e.span() {
            Some(s) => cx.err(&s, msg),
            None => Error::input(Location::file(path), msg),
        }
        .with_hint(hint)
    })?;

    // The actuator.
    let sc = &spec.actuator.scene;
    let scene_path = cx.file(&sc.span(), "actuator.scene", sc.get_ref())?;
    let scene = Scene::read(&scene_path)?;
    // the figures are of the nominal geometry: a tolerance would be dropped
    if let Some(t) = scene.tolerances.first() {
        return Err(Error::input(
            t.at.clone(),
            format!(
                "actuator.{}: rank does not take a tolerance of the geometry (its figures are of the nominal geometry: the tolerance would be dropped)",
                t.length
            ),
        )
        .with_hint("write the length alone in the design's scene (dea-fit identify takes the tolerance into its intervals)"));
    }
    // what the scene reads (its material's fit files) counts for the design hash
    cx.files.borrow_mut().extend(scene.files.iter().cloned());
    if scene.control.is_some() {
        return Err(cx
            .err(
                &sc.span(),
                "actuator.scene: a closed-loop scene cannot be driven by a step",
            )
            .with_hint(
                "give an open-loop scene (with [[input]]): its input is replaced by the drive",
            ));
    }

    // The drive.
    let dr = &spec.drive;
    let level = match (&dr.voltage, &dr.breakdown_fraction) {
        (Some(v), None) => Level::Voltage(cx.checked(
            &v.span(),
            &budget::MAX_VOLTAGE,
            "drive.voltage",
            cx.quantity(v, Dimension::Voltage, "voltage")?,
        )?),
        (None, Some(f)) => {
            let x = *f.get_ref();
            if !(x > 0.0 && x <= 1.0) {
                return Err(cx
                    .err(
                        &f.span(),
                        format!("drive.breakdown_fraction must be in (0, 1], found {x}"),
                    )
                    .with_hint(
                        "the drive is this share of each candidate's breakdown voltage at rest",
                    ));
            }
            Level::BreakdownFraction(x)
        }
        _ => {
            let at = dr.voltage.as_ref().map(|v| v.span()).unwrap_or(0..0);
            return Err(cx
                .err(&at, "[drive] takes one of voltage, breakdown_fraction")
                .with_hint("e.g. voltage = \"800 V\" or breakdown_fraction = 0.5"));
        }
    };
    let frequency_hz = cx.checked(
        &dr.frequency.span(),
        &budget::FREQUENCY,
        "drive.frequency",
        cx.quantity(&dr.frequency, Dimension::Frequency, "frequency")?,
    )?;
    let step_span_s = cx.checked(
        &dr.step_span.span(),
        &budget::SPAN,
        "drive.step_span",
        cx.quantity(&dr.step_span, Dimension::Time, "step_span")?,
    )?;
    let step_samples = match &dr.step_samples {
        None => 200,
        Some(n) => {
            let v = *n.get_ref();
            if v < MIN_STEP_SAMPLES as i64 || v as f64 > budget::SAMPLES.max {
                return Err(cx
                    .err(&n.span(), format!("drive.step_samples = {v}: expected {MIN_STEP_SAMPLES} … {}", budget::SAMPLES.max))
                    .with_hint("the 10–90 % time is read between samples: 200 resolve it to 0.5 % of the window"));
            }
            v as usize
        }
    };

    // The actuator's film, which a breakdown fit is scaled to.
    let film = Film::of(&scene, &scene_path);

    // Matrices.
    let mut matrices: Vec<Matrix> = Vec::new();
    for (i, m) in spec.matrix.iter().enumerate() {
        let key = format!("matrix[{i}]");
        let name = m.name.get_ref().trim().to_string();
        if name.is_empty() || matrices.iter().any(|o| o.name == name) {
            return Err(cx
                .err(
                    &m.name.span(),
                    format!("{key}.name: empty or repeated '{name}'"),
                )
                .with_hint("every matrix needs its own name"));
        }
        let density = cx.checked(
            &m.density.span(),
            &budget::DENSITY,
            &format!("{key}.density"),
            cx.quantity(&m.density, Dimension::Density, "density")?,
        )?;
        let eps = cx.uncertain(
            &m.eps_r,
            Dimension::Number,
            Some(&PERMITTIVITY),
            &format!("{key}.eps_r"),
        )?;
        let tan = cx.uncertain(
            &m.tan_delta,
            Dimension::Number,
            Some(&TAN_DELTA),
            &format!("{key}.tan_delta"),
        )?;
        let breakdown =
            cx.breakdown(&m.breakdown, &format!("{key}.breakdown"), &m.source, &film)?;
        let with = |u: Uncertain, s: &Span| Stated {
            value: u.value,
            std_error: u.std_error,
            provenance: Provenance::Stated,
            source: cx.here(s, &m.source),
            warnings: Vec::new(),
        };
        let viscous = match &m.viscous {
            Some(v) => cx.viscous(v, &format!("{key}.viscous"), &m.source)?,
            None => Stated {
                value: scene.material.viscous.clone(),
                std_error: None,
                provenance: Provenance::Stated,
                source: format!("{} [material] viscous", scene_path.display()),
                warnings: Vec::new(),
            },
        };
        matrices.push(Matrix {
            eps_r: with(eps, &m.eps_r.span()),
            tan_delta: with(tan, &m.tan_delta.span()),
            breakdown,
            hyperelastic: cx.hyperelastic(
                &m.hyperelastic,
                &format!("{key}.hyperelastic"),
                &m.source,
            )?,
            viscous,
            name,
            density,
        });
    }
    if matrices.is_empty() {
        return Err(
            Error::input(Location::file(path), "the manifest names no [[matrix]]").with_hint(
                "add a [[matrix]] table (name, density, eps_r, tan_delta, breakdown, hyperelastic)",
            ),
        );
    }

    // Fillers.
    let mut fillers: Vec<Filler> = Vec::new();
    for (i, f) in spec.filler.iter().enumerate() {
        let key = format!("filler[{i}]");
        let name = f.name.get_ref().trim().to_string();
        if name.is_empty() || fillers.iter().any(|o| o.name == name) {
            return Err(cx
                .err(
                    &f.name.span(),
                    format!("{key}.name: empty or repeated '{name}'"),
                )
                .with_hint("every filler needs its own name"));
        }
        fillers.push(Filler {
            density: cx.checked(
                &f.density.span(),
                &budget::DENSITY,
                &format!("{key}.density"),
                cx.quantity(&f.density, Dimension::Density, "density")?,
            )?,
            eps_r: {
                let u = cx.uncertain(
                    &f.eps_r,
                    Dimension::Number,
                    Some(&PERMITTIVITY),
                    &format!("{key}.eps_r"),
                )?;
                Stated {
                    value: u.value,
                    std_error: u.std_error,
                    provenance: Provenance::Stated,
                    source: cx.here(&f.eps_r.span(), &f.source),
                    warnings: Vec::new(),
                }
            },
            name,
        });
    }

    // Series.
    let mut series: Vec<Series> = Vec::new();
    for (i, s) in spec.series.iter().enumerate() {
        series.push(read_series(&cx, i, s, &matrices, &fillers, &film)?);
        let last = series.last().expect("pushed");
        if series[..i].iter().any(|o| o.name == last.name) {
            let at = s.name.as_ref().map(|n| n.span()).unwrap_or(s.matrix.span());
            return Err(cx
                .err(
                    &at,
                    format!("series[{i}]: a second series named '{}'", last.name),
                )
                .with_hint("series of the same matrix and filler need their own name = \"...\""));
        }
    }
    if series.is_empty() {
        return Err(
            Error::input(Location::file(path), "the manifest names no [[series]]").with_hint(
                "add a [[series]] table (matrix, filler, basis, loadings, permittivity)",
            ),
        );
    }

    // The design hash: the manifest and every file read, in order.
    let mut h = crate::io::sha256_hex(bytes);
    for f in cx.files.borrow().iter() {
        let b = std::fs::read(f).map_err(|e| Error::io(f, e))?;
        h = crate::io::sha256_hex(format!("{h}{}", crate::io::sha256_hex(&b)).as_bytes());
    }
    Ok(Design {
        path: path.to_path_buf(),
        name: spec.name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "design".into())
        }),
        sha256: h,
        scene,
        scene_path,
        drive: Drive {
            level,
            frequency_hz,
            step_span_s,
            step_samples,
        },
        matrices,
        fillers,
        series,
    })
}

/// A loading: a fraction (0.2) or a percentage ("20 %").
fn loading(cx: &Ctx, t: &Text, span: &Span, key: &str) -> Result<f64> {
    let v = match t {
        Text::Num(v) => *v,
        Text::Str(s) => parse_quantity(s, Dimension::Fraction)
            .map_err(|e| cx.err(span, format!("{key}: {e}")))?,
    };
    match (0.0..1.0).contains(&v) {
        true => Ok(v),
        false => Err(cx
            .err(
                span,
                format!("{key} = {v} is not a filler fraction in [0, 1)"),
            )
            .with_hint("write 20 % as 0.2 or \"20 %\"")),
    }
}

fn read_series(
    cx: &Ctx,
    i: usize,
    s: &SeriesSpec,
    matrices: &[Matrix],
    fillers: &[Filler],
    film: &Film,
) -> Result<Series> {
    let key = format!("series[{i}]");
    let matrix_names: Vec<&str> = matrices.iter().map(|m| m.name.as_str()).collect();
    let matrix = matrices
        .iter()
        .position(|m| m.name == *s.matrix.get_ref())
        .ok_or_else(|| {
            cx.unknown(
                &s.matrix.span(),
                &format!("{key}.matrix"),
                s.matrix.get_ref(),
                &matrix_names,
            )
        })?;
    let filler = match &s.filler {
        None => None,
        Some(f) => {
            let filler_names: Vec<&str> = fillers.iter().map(|m| m.name.as_str()).collect();
            Some(
                fillers
                    .iter()
                    .position(|x| x.name == *f.get_ref())
                    .ok_or_else(|| {
                        cx.unknown(
                            &f.span(),
                            &format!("{key}.filler"),
                            f.get_ref(),
                            &filler_names,
                        )
                    })?,
            )
        }
    };
    let name = match &s.name {
        Some(n) => n.get_ref().trim().to_string(),
        None => match filler {
            Some(f) => format!("{} + {}", matrices[matrix].name, fillers[f].name),
            None => matrices[matrix].name.clone(),
        },
    };
    let anchor = s.matrix.span();
    let Some(f) = filler else {
        // The matrix alone: one candidate, no filler keys.
        for (k, given) in [
            ("loadings", s.loadings.is_some()),
            ("permittivity", s.permittivity.is_some()),
            ("stiffening", s.stiffening.is_some()),
            ("measured", !s.measured.is_empty()),
        ] {
            if given {
                return Err(cx
                    .err(&anchor, format!("{key}.{k} needs a filler"))
                    .with_hint(
                    "a series without filler is the matrix alone: drop the key, or name a filler",
                ));
            }
        }
        return Ok(Series {
            name,
            matrix,
            filler: None,
            basis: Basis::Volume,
            loadings: vec![0.0],
            permittivity: None,
            stiffening: Stiffening::None,
            measured: Vec::new(),
        });
    };
    let basis = match &s.basis {
        Some(b) => match b.get_ref().as_str() {
            "weight" => Basis::Weight,
            "volume" => Basis::Volume,
            o => {
                return Err(cx.unknown(
                    &b.span(),
                    &format!("{key}.basis"),
                    o,
                    &["weight", "volume"],
                ))
            }
        },
        None => {
            return Err(cx
                .err(&anchor, format!("{key}.basis is missing"))
                .with_hint("basis = \"weight\" or \"volume\": the loadings are fractions on it"))
        }
    };
    let Some(l) = &s.loadings else {
        return Err(cx
            .err(&anchor, format!("{key}.loadings is missing"))
            .with_hint("e.g. loadings = \"0:0.4:9\" (start:stop:count) or [0, 0.1, 0.2]"));
    };
    let lk = format!("{key}.loadings");
    let mut loadings = match l.get_ref() {
        Loadings::List(v) => v
            .iter()
            .map(|t| loading(cx, t, &l.span(), &lk))
            .collect::<Result<Vec<_>>>()?,
        Loadings::Range(r) => super::sweep::range(r, Dimension::Fraction)
            .map_err(|e| cx.err(&l.span(), format!("{lk}: {e}")))?
            .into_iter()
            .map(|v| loading(cx, &Text::Num(v), &l.span(), &lk))
            .collect::<Result<Vec<_>>>()?,
    };
    loadings.sort_by(f64::total_cmp);
    loadings.dedup();
    if loadings.is_empty() {
        return Err(cx.err(&l.span(), format!("{lk} is empty")));
    }
    let stiffening = match &s.stiffening {
        None => Stiffening::GuthGold,
        Some(x) => Stiffening::parse(x.get_ref()).ok_or_else(|| {
            cx.unknown(
                &x.span(),
                &format!("{key}.stiffening"),
                x.get_ref(),
                &Stiffening::NAMES,
            )
        })?,
    };
    let Some(p) = &s.permittivity else {
        return Err(cx
            .err(&anchor, format!("{key}.permittivity is missing"))
            .with_hint("permittivity = { rule = \"maxwell-garnett\" } (stated) or { composite = \"fit.json\" } (a composite fit)"));
    };
    let ps = p.get_ref();
    let rule_names: Vec<&str> = MixingRule::ALL.iter().map(|r| r.name()).collect();
    let rule = match &ps.rule {
        None => None,
        Some(r) => Some(MixingRule::parse(r.get_ref()).ok_or_else(|| {
            cx.unknown(
                &r.span(),
                &format!("{key}.permittivity.rule"),
                r.get_ref(),
                &rule_names,
            )
        })?),
    };
    let permittivity = match &ps.composite {
        Some(c) => {
            if ps.shape.is_some() {
                return Err(cx
                    .err(
                        &p.span(),
                        format!("{key}.permittivity.shape goes with a stated rule"),
                    )
                    .with_hint("a composite fit states Yamada's n itself"));
            }
            let freq = match &ps.frequency {
                Some(q) => Some(cx.quantity(q, Dimension::Frequency, "frequency")?),
                None => None,
            };
            let file = cx.file(
                &c.span(),
                &format!("{key}.permittivity.composite"),
                c.get_ref(),
            )?;
            let (mixture, freq_hz, spread) = file::read_mixture(&file, rule, freq)?;
            let (m, fl) = (&matrices[matrix], &fillers[f]);
            for (what, theirs, ours) in [
                ("matrix", mixture.rho_matrix, m.density),
                ("filler", mixture.rho_filler, fl.density),
            ] {
                if (theirs - ours).abs() > 1e-3 * ours {
                    return Err(cx
                        .err(&c.span(), format!("{key}.permittivity.composite: the fit's {what} density {theirs} kg/m³ differs from the manifest's {ours} kg/m³"))
                        .with_hint("one composite, one pair of densities: correct the manifest or the composite series"));
                }
            }
            PermittivityModel::Composite {
                mixture,
                freq_hz,
                file: file.display().to_string(),
                spread,
            }
        }
        None => {
            if ps.frequency.is_some() {
                return Err(cx
                    .err(
                        &p.span(),
                        format!("{key}.permittivity.frequency goes with a composite fit"),
                    )
                    .with_hint(
                        "a stated rule uses the εr of the matrix and the filler as written",
                    ));
            }
            let Some(rule) = rule else {
                return Err(cx
                    .err(
                        &p.span(),
                        format!("{key}.permittivity needs rule or composite"),
                    )
                    .with_hint(format!("rule = one of {}", rule_names.join(", "))));
            };
            let shape = match (&ps.shape, rule.has_shape()) {
                (Some(n), true) if *n.get_ref() > 0.0 && n.get_ref().is_finite() => *n.get_ref(),
                (Some(n), true) => return Err(cx.err(&n.span(), "shape must be a positive number")),
                (None, true) => {
                    return Err(cx
                        .err(
                            &p.span(),
                            format!("{key}.permittivity: yamada needs shape = n"),
                        )
                        .with_hint("n = 3 is Maxwell Garnett; fitted series give n ≈ 3–10"))
                }
                (Some(n), false) => {
                    return Err(cx.err(
                        &n.span(),
                        format!("{key}.permittivity.shape goes with yamada only"),
                    ))
                }
                (None, false) => 3.0,
            };
            PermittivityModel::Rule { rule, shape }
        }
    };
    let mut measured: Vec<MeasuredPoint> = Vec::new();
    for (j, m) in s.measured.iter().enumerate() {
        let mk = format!("{key}.measured[{j}]");
        let x = m.get_ref();
        let at = loading(
            cx,
            x.loading.get_ref(),
            &x.loading.span(),
            &format!("{mk}.loading"),
        )?;
        if at == 0.0
            || measured
                .iter()
                .any(|o| super::candidate::same_loading(o.loading, at))
        {
            return Err(cx
                .err(&x.loading.span(), format!("{mk}.loading = {at}: the matrix or another measured point already holds it"))
                .with_hint("measured points are composites (loading > 0), one per loading; the matrix's values are in [[matrix]]"));
        }
        let eps_r = x
            .eps_r
            .as_ref()
            .map(|e| {
                cx.uncertain(
                    e,
                    Dimension::Number,
                    Some(&PERMITTIVITY),
                    &format!("{mk}.eps_r"),
                )
            })
            .transpose()?;
        let tan_delta = x
            .tan_delta
            .as_ref()
            .map(|e| {
                cx.uncertain(
                    e,
                    Dimension::Number,
                    Some(&TAN_DELTA),
                    &format!("{mk}.tan_delta"),
                )
            })
            .transpose()?;
        let breakdown = x
            .breakdown
            .as_ref()
            .map(|e| cx.breakdown(e, &format!("{mk}.breakdown"), &x.source, film))
            .transpose()?;
        let hyperelastic = match &x.hyperelastic {
            Some(h) => Some(cx.hyperelastic(h, &format!("{mk}.hyperelastic"), &x.source)?),
            None => None,
        };
        if eps_r.is_none() && tan_delta.is_none() && breakdown.is_none() && hyperelastic.is_none() {
            return Err(cx
                .err(&m.span(), format!("{mk} holds no measured value"))
                .with_hint("give eps_r, tan_delta, breakdown or hyperelastic"));
        }
        measured.push(MeasuredPoint {
            loading: at,
            source: cx.here(&m.span(), &x.source),
            eps_r,
            tan_delta,
            breakdown,
            hyperelastic,
        });
    }
    measured.sort_by(|a, b| a.loading.total_cmp(&b.loading));
    Ok(Series {
        name,
        matrix,
        filler: Some(f),
        basis,
        loadings,
        permittivity: Some(permittivity),
        stiffening,
        measured,
    })
}

/// The actuator's film as a breakdown fit sees it: the electrode area under
/// field (all of it: a film fails where its weakest part does, so the whole
/// active area counts) and the layer thickness; a scene states no prestretch.
#[derive(Debug, Clone)]
pub struct Film {
    /// Active electrode area (m²): [`super::figures::electrode_area`].
    pub area_m2: f64,
    /// Thickness of one dielectric layer (m).
    pub thickness_m: f64,
    /// Both in words, with the scene.
    pub describe: String,
}

impl Film {
    /// The film of `scene` (read from `path`).
    pub fn of(scene: &Scene, path: &Path) -> Film {
        let a = scene.actuator;
        let (area, how, h) = super::figures::electrode_area(&a);
        Film {
            area_m2: area,
            thickness_m: h,
            describe: format!(
                "the electrode area of {} ({how} = {} m², the whole film under field) and its {} µm layer",
                path.display(),
                crate::report::format::sig(area, 4),
                crate::report::format::sig(1e6 * h, 4)
            ),
        }
    }
}
