//! Scene files (TOML) → validated [`Scene`]. The format is documented in
//! `docs/scenes.md`. Quantities are strings with a unit (`"2.25 mm"`, `"5 kV"`) or
//! bare SI numbers; keys that carry no unit table name the unit (`resistivity_ohm_m`).

use super::budget;
use super::input::{Term, Waveform};
use super::integrate::Method;
use super::presets;
use crate::error::{Error, Location, Result};
use crate::material::breakdown::Strength;
use crate::material::check::{did_you_mean, Domain, Violation, ARM_TIME, MASS_FRACTION};
use crate::material::dielectric::MixingRule;
use crate::material::file::{
    self, expected_params, CompositePermittivity, FittedRanges, HyperelasticPart,
    IdentifiedMaterial, Viscous,
};
use crate::material::hyperelastic::{Mode, ModelSpec, OgdenForm, StrainEnergy, MODEL_NAMES};
use crate::material::viscoelastic::TimeTemperature;
use crate::units::{parse_quantity, parse_uncertain, Dimension};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Lateral kinematics of a helix element.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Lateral {
    /// Seed Eq. 4.18: mean radius fixed, the width spreads (planar compression).
    Planar,
    /// Free in-plane spreading (equibiaxial, like a stack layer).
    Free,
}

/// A multilayer stack (seed Chapter 3, Table 3.1).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct StackGeometry {
    /// Electrode radius r0 (m).
    pub radius_m: f64,
    /// Elastomer layer thickness zd0 (m).
    pub layer_m: f64,
    /// Electrode thickness ze0 (m).
    pub electrode_m: f64,
    /// Elastomer layers nd.
    pub layers: usize,
    /// Electrode layers ne.
    pub electrodes: usize,
}

/// A helical actuator (seed Chapter 4, Table 4.1).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HelixGeometry {
    /// Outer radius Ro0 (m).
    pub outer_m: f64,
    /// Inner radius Ri0 (m).
    pub inner_m: f64,
    /// Vertical element thickness z0 (m).
    pub thickness_m: f64,
    /// Periods Np.
    pub periods: usize,
    /// Elements per period Ne.
    pub per_period: usize,
    /// Lateral kinematics.
    pub lateral: Lateral,
}

/// The actuator.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Actuator {
    /// Multilayer stack.
    Stack(StackGeometry),
    /// Helix.
    Helix(HelixGeometry),
}

/// A length of the actuator's geometry, by its scene key.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Length {
    /// A stack's electrode radius r0.
    Radius,
    /// A stack's elastomer layer thickness zd0.
    LayerThickness,
    /// A stack's electrode thickness ze0.
    ElectrodeThickness,
    /// A helix's outer radius Ro0.
    OuterRadius,
    /// A helix's inner radius Ri0.
    InnerRadius,
    /// A helix's vertical element thickness z0.
    Thickness,
}

impl Length {
    /// The lengths of a stack's geometry.
    pub const STACK: [Length; 3] = [
        Length::Radius,
        Length::LayerThickness,
        Length::ElectrodeThickness,
    ];
    /// The lengths of a helix's geometry.
    pub const HELIX: [Length; 3] = [Length::OuterRadius, Length::InnerRadius, Length::Thickness];

    /// The key in `[actuator]`.
    pub fn key(self) -> &'static str {
        match self {
            Length::Radius => "radius",
            Length::LayerThickness => "layer_thickness",
            Length::ElectrodeThickness => "electrode_thickness",
            Length::OuterRadius => "outer_radius",
            Length::InnerRadius => "inner_radius",
            Length::Thickness => "thickness",
        }
    }
}

impl std::fmt::Display for Length {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}

/// The stated tolerance of a geometry length (`layer_thickness = "50 ± 1 um"`): one
/// standard deviation of the real length about the value the simulator runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Tolerance {
    /// Which length.
    pub length: Length,
    /// Its standard deviation σ (m), 0 ≤ σ ≤ the length.
    pub sigma_m: f64,
    /// Where the scene states it (for a reader that does not carry it, and refuses
    /// it there: `dea-fit rank`).
    #[serde(skip)]
    pub at: Location,
}

impl Actuator {
    /// The lengths of this actuator's geometry ([`Length::STACK`] or [`Length::HELIX`]).
    pub fn lengths(&self) -> [Length; 3] {
        match self {
            Actuator::Stack(_) => Length::STACK,
            Actuator::Helix(_) => Length::HELIX,
        }
    }

    /// A length's field of this actuator's geometry (None: the other kind's).
    fn length_mut(&mut self, l: Length) -> Option<&mut f64> {
        match (self, l) {
            (Actuator::Stack(s), Length::Radius) => Some(&mut s.radius_m),
            (Actuator::Stack(s), Length::LayerThickness) => Some(&mut s.layer_m),
            (Actuator::Stack(s), Length::ElectrodeThickness) => Some(&mut s.electrode_m),
            (Actuator::Helix(h), Length::OuterRadius) => Some(&mut h.outer_m),
            (Actuator::Helix(h), Length::InnerRadius) => Some(&mut h.inner_m),
            (Actuator::Helix(h), Length::Thickness) => Some(&mut h.thickness_m),
            _ => None,
        }
    }

    /// The value of a length (m); None for a length of the other kind.
    pub fn length(&self, l: Length) -> Option<f64> {
        let mut a = *self;
        a.length_mut(l).map(|v| *v)
    }

    /// This geometry with the length `l` at `value` (m); None for a length of the
    /// other kind.
    pub fn with_length(&self, l: Length, value: f64) -> Option<Actuator> {
        let mut a = *self;
        *a.length_mut(l)? = value;
        Some(a)
    }
}

/// Material constants.
#[derive(Clone)]
pub struct Material {
    /// Hyperelastic model (registry name and Ogden form).
    pub spec: ModelSpec,
    /// Evaluator.
    pub model: Arc<dyn StrainEnergy>,
    /// Parameters (SI, model order).
    pub params: Vec<f64>,
    /// The fitted stretch ranges of the file the constants came from, if any (for
    /// range warnings; None for presets and inline constants).
    pub fit: Option<Arc<FittedRanges>>,
    /// Viscous constants.
    pub viscous: Viscous,
    /// Relative permittivity εr.
    pub eps_r: f64,
    /// Where εr comes from when it is a composite's mixing rule (εr = εr(w) of the
    /// filler mass fraction w); None when εr is given as a number.
    pub composite: Option<CompositePermittivity>,
    /// Density (kg/m³).
    pub density: f64,
    /// Volume resistivity (Ω·m); None = no leakage.
    pub resistivity: Option<f64>,
}

/// Mechanical load.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Load {
    /// Hanging mass (kg).
    pub mass_kg: f64,
    /// Constant massless tensile force (N).
    pub force_n: f64,
    /// Effective-mass fraction f of the actuator's own mass (seed Eq. 3.10: ½).
    pub fraction: f64,
    /// Gravity (m/s²); acts on the hanging mass and on f·m_actuator (Eq. 3.9–3.10).
    pub gravity: f64,
    /// Actuator mass (kg) if given explicitly (else density × volume).
    pub actuator_mass_kg: Option<f64>,
}

/// The voltage source between the input signal and the actuator.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Source {
    /// The terminal voltage is the input.
    Ideal,
    /// First-order lag with this time constant (s) (slew of a real supply).
    RiseTime {
        /// Time constant (s).
        tau_s: f64,
    },
    /// Ideal source behind an output resistance (Ω).
    Resistance {
        /// Output resistance (Ω).
        ohm: f64,
    },
}

/// Model fidelity requested by the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FidelityChoice {
    /// Let the simulator choose (see `sim::fidelity`).
    Auto,
    /// Full model with inertia and every arm.
    Dynamic,
    /// No inertia (without a dashpot: not through a jump of an ideal source).
    QuasiStatic,
}

/// PID on the contraction estimated from the capacitance (seed §3.6, Eq. 3.29):
/// u = Kp·e + Ki·∫e dt + Kd·de/dt, e = reference − ŷ, ŷ = 1 − sqrt(C(λ0)/C) (the
/// stack's self-sensing law C ∝ λ⁻², Eq. 3.22), the derivative through a first-order
/// filter, the output clamped to [0, V_max] with conditional-integration anti-windup.
#[derive(Debug, Clone, PartialEq)]
pub struct Pid {
    /// Proportional gain (V per unit contraction).
    pub kp: f64,
    /// Integral gain (V/s per unit contraction).
    pub ki: f64,
    /// Derivative gain (V·s per unit contraction).
    pub kd: f64,
    /// Derivative filter time constant (s).
    pub tau_d: f64,
    /// Output limit (V).
    pub v_max: f64,
    /// Reference contraction (fraction of the rest length).
    pub reference: Waveform,
}

/// Time span, samples and tolerances.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSpec {
    /// End time (s); the run starts at 0.
    pub span: f64,
    /// Output sample times (s), sorted, in (0, span].
    pub samples: Vec<f64>,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance relative to each state's scale.
    pub atol: f64,
    /// Integrator (None = auto).
    pub method: Option<Method>,
    /// Fidelity.
    pub fidelity: FidelityChoice,
}

/// A validated scene: a pure description, `Send + Sync`, cheap to clone and to
/// re-run with other material constants (`scene.material.params`).
#[derive(Clone)]
pub struct Scene {
    /// Scene name (file stem unless given).
    pub name: String,
    /// Actuator (the nominal geometry, which the simulator runs).
    pub actuator: Actuator,
    /// The stated tolerances of the geometry's lengths, in the order of
    /// [`Actuator::lengths`] (`layer_thickness = "50 ± 1 um"`); empty when the scene
    /// states none. `dea-fit identify` carries them into its intervals
    /// ([`crate::identify::geometry`]).
    pub tolerances: Vec<Tolerance>,
    /// Material.
    pub material: Material,
    /// Load.
    pub load: Load,
    /// Voltage source.
    pub source: Source,
    /// Input voltage (V); unused when `control` is set.
    pub input: Waveform,
    /// Closed loop (seed Eq. 3.29), replacing the input.
    pub control: Option<Pid>,
    /// Time and tolerances.
    pub time: TimeSpec,
    /// Every file the scene read besides itself (fit files, identified and
    /// composite files, tables), in the order read: what a hash of its inputs
    /// must cover (the design hash of `dea-fit rank`).
    pub files: Vec<PathBuf>,
    /// The film's breakdown strength (`material.breakdown`), stated or from a
    /// breakdown fit scaled to the film under field ([`Actuator::film_area`]); None:
    /// the scene states none and no field is checked.
    pub breakdown: Option<Strength>,
    /// What the material files the scene takes constants from say against them
    /// (constants they call not identifiable, a blocking status), one sentence per
    /// file ([`file::doubts`]), and a `material.temperature` outside the measured
    /// temperatures of its DMA fit: said whenever the scene runs
    /// ([`Scene::material_warnings`]).
    pub doubts: Vec<String>,
}

/// The reader's context: the file, its text, and the byte offset of every key and
/// array element by key path (`material.viscous.arms[1].k`), from toml's spanned
/// parser, so that every error points at the offending key's line and column.
struct Ctx<'a> {
    file: &'a Path,
    text: &'a str,
    spans: HashMap<String, usize>,
    /// The files referenced so far ([`Scene::files`]).
    files: std::cell::RefCell<Vec<PathBuf>>,
    /// What the material files read so far say against their constants
    /// ([`Scene::doubts`]).
    doubts: std::cell::RefCell<Vec<String>>,
}

fn collect_spans(prefix: &str, t: &toml::de::DeTable, out: &mut HashMap<String, usize>) {
    for (k, v) in t.iter() {
        let path = match prefix {
            "" => k.get_ref().to_string(),
            p => format!("{p}.{}", k.get_ref()),
        };
        out.insert(path.clone(), k.span().start);
        collect_value(&path, v, out);
    }
}

fn collect_value(
    path: &str,
    v: &toml::Spanned<toml::de::DeValue>,
    out: &mut HashMap<String, usize>,
) {
    match v.get_ref() {
        toml::de::DeValue::Table(t) => collect_spans(path, t, out),
        toml::de::DeValue::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                let p = format!("{path}[{i}]");
                out.insert(p.clone(), x.span().start);
                collect_value(&p, x, out);
            }
        }
        _ => {}
    }
}

/// 1-based line and column (in characters) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map(|i| i + 1).unwrap_or(0);
    (line, before[start..].chars().count() + 1)
}

impl Ctx<'_> {
    /// Where `key` is: the key itself, else its closest enclosing table, else the file.
    fn loc(&self, key: &str) -> Location {
        let mut p = key.to_string();
        loop {
            for q in [p.clone(), p.replace("[0]", "")] {
                if let Some(&o) = self.spans.get(&q) {
                    let (l, c) = line_col(self.text, o);
                    return Location::at(self.file, l, c);
                }
            }
            match p.rfind(['.', '[']) {
                Some(i) => p.truncate(i),
                None => return Location::file(self.file),
            }
        }
    }
    /// An error at `key`, its message starting with the key path.
    fn err(&self, key: &str, msg: impl std::fmt::Display) -> Error {
        Error::input(self.loc(key), format!("{key}: {msg}"))
    }
    fn violation(&self, v: Violation) -> Error {
        self.err(&v.key, v.msg).with_hint(v.hint)
    }
    fn table<'t>(&self, t: &'t toml::Table, key: &str) -> Result<&'t toml::Table> {
        match t.get(key) {
            Some(toml::Value::Table(x)) => Ok(x),
            Some(_) => Err(self.err(key, "must be a table")),
            None => Err(self
                .err(key, format!("missing [{key}] section"))
                .with_hint("see docs/scenes.md for the scene format")),
        }
    }
    fn opt_table<'t>(&self, t: &'t toml::Table, key: &str) -> Result<Option<&'t toml::Table>> {
        match t.get(key) {
            None => Ok(None),
            Some(_) => self.table(t, key).map(Some),
        }
    }
    /// A quantity: a string with a unit, or a bare SI number; always finite.
    fn quantity(
        &self,
        t: &toml::Table,
        sec: &str,
        key: &str,
        dim: Dimension,
    ) -> Result<Option<f64>> {
        let k = format!("{sec}.{key}");
        let v = match t.get(key) {
            None => return Ok(None),
            Some(toml::Value::Float(x)) => *x,
            Some(toml::Value::Integer(x)) => *x as f64,
            Some(toml::Value::String(s)) => parse_quantity(s, dim).map_err(|e| self.err(&k, e))?,
            Some(v) => {
                return Err(self.err(
                    &k,
                    format!("expected a quantity such as \"1 {}\", found {v}", dim.si()),
                ))
            }
        };
        match v.is_finite() {
            true => Ok(Some(v)),
            false => Err(self
                .err(&k, format!("must be a finite number, found {v}"))
                .with_hint(format!(
                    "give it with a unit, e.g. {key} = \"1 {}\"",
                    dim.si()
                ))),
        }
    }
    fn need(&self, t: &toml::Table, sec: &str, key: &str, dim: Dimension) -> Result<f64> {
        self.quantity(t, sec, key, dim)?.ok_or_else(|| {
            self.err(&format!("{sec}.{key}"), "is missing")
                .with_hint(format!(
                    "give it with a unit, e.g. {key} = \"1 {}\"",
                    dim.si()
                ))
        })
    }
    /// A length of `[actuator]`: a quantity, or a string with its tolerance
    /// (`"50 ± 1 um"`, the reader of every `±` in the project,
    /// [`parse_uncertain`]), the tolerance pushed to `tol`. The σ is one standard
    /// deviation and at most the length (a larger one says the length is unknown,
    /// and a length is positive); a negative, non-finite or larger σ is refused at
    /// the key.
    fn length(&self, t: &toml::Table, l: Length, tol: &mut Vec<Tolerance>) -> Result<Option<f64>> {
        let (key, k) = (l.key(), format!("actuator.{}", l.key()));
        let Some(toml::Value::String(s)) = t.get(key) else {
            return self.quantity(t, "actuator", key, Dimension::Length);
        };
        let hint = || {
            format!("give the length, or the length with one standard deviation of it in [0, the length], e.g. {key} = \"50 ± 1 um\"")
        };
        let q =
            parse_uncertain(s, Dimension::Length).map_err(|e| self.err(&k, e).with_hint(hint()))?;
        if !q.value.is_finite() {
            return Err(self
                .err(&k, format!("must be a finite length, found {}", q.value))
                .with_hint(hint()));
        }
        if let Some(sigma) = q.tolerance {
            if !(sigma.is_finite() && (0.0..=q.value).contains(&sigma)) {
                return Err(self
                    .err(
                        &k,
                        format!(
                            "the tolerance {} of '{s}' must be a finite standard deviation from 0 to the length ({})",
                            crate::report::format::si(sigma, "m"),
                            crate::report::format::si(q.value, "m"),
                        ),
                    )
                    .with_hint(hint()));
            }
            tol.push(Tolerance {
                length: l,
                sigma_m: sigma,
                at: self.loc(&k),
            });
        }
        Ok(Some(q.value))
    }
    fn need_length(&self, t: &toml::Table, l: Length, tol: &mut Vec<Tolerance>) -> Result<f64> {
        self.length(t, l, tol)?.ok_or_else(|| {
            self.err(&format!("actuator.{}", l.key()), "is missing")
                .with_hint(format!("give it with a unit, e.g. {} = \"1 m\"", l.key()))
        })
    }
    /// A plain (dimensionless or unit-in-the-name) number; always finite.
    fn number(&self, t: &toml::Table, sec: &str, key: &str) -> Result<Option<f64>> {
        let k = format!("{sec}.{key}");
        let v = match t.get(key) {
            None => return Ok(None),
            Some(toml::Value::Float(x)) => *x,
            Some(toml::Value::Integer(x)) => *x as f64,
            Some(v) => return Err(self.err(&k, format!("expected a number, found {v}"))),
        };
        match v.is_finite() {
            true => Ok(Some(v)),
            false => Err(self.err(&k, format!("must be a finite number, found {v}"))),
        }
    }
    /// An integer count inside `dom` (checked before anything is sized by it).
    fn count(&self, t: &toml::Table, sec: &str, key: &str, dom: &Domain) -> Result<Option<usize>> {
        let k = format!("{sec}.{key}");
        match t.get(key) {
            None => Ok(None),
            Some(toml::Value::Integer(x)) => dom
                .check(&k, *x as f64)
                .map(|_| Some(*x as usize))
                .map_err(|v| self.violation(v)),
            Some(v) => Err(self.err(&k, format!("expected an integer, found {v}"))),
        }
    }
    fn need_count(&self, t: &toml::Table, sec: &str, key: &str, dom: &Domain) -> Result<usize> {
        self.count(t, sec, key, dom)?
            .ok_or_else(|| self.err(&format!("{sec}.{key}"), "is missing"))
    }
    fn string<'t>(&self, t: &'t toml::Table, sec: &str, key: &str) -> Result<Option<&'t str>> {
        match t.get(key) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.err(
                &format!("{sec}.{key}"),
                format!("expected a string, found {v}"),
            )),
        }
    }
    /// Refuse keys outside `known`, with the list and a near miss.
    fn known(&self, t: &toml::Table, sec: &str, known: &[&str]) -> Result<()> {
        for k in t.keys() {
            if !known.contains(&k.as_str()) {
                let hint = match did_you_mean(k, known) {
                    Some(m) => format!("did you mean '{m}'? known keys: {}", known.join(", ")),
                    None => format!("known keys: {}", known.join(", ")),
                };
                let path = match sec {
                    "" => k.clone(),
                    s => format!("{s}.{k}"),
                };
                return Err(self.err(&path, "unknown key").with_hint(hint));
            }
        }
        Ok(())
    }
    /// Refuse more than one of `keys` (alternatives that would silently override
    /// each other).
    fn one_of(&self, t: &toml::Table, sec: &str, keys: &[&str]) -> Result<()> {
        let given: Vec<&str> = keys
            .iter()
            .copied()
            .filter(|k| t.contains_key(*k))
            .collect();
        if given.len() > 1 {
            return Err(self
                .err(
                    &format!("{sec}.{}", given[1]),
                    format!("conflicts with {sec}.{}", given[0]),
                )
                .with_hint(format!("give one of {}", keys.join(", "))));
        }
        Ok(())
    }
    /// A name from a fixed list, with a near miss in the hint.
    fn unknown_name(&self, key: &str, found: &str, known: &[&str]) -> Error {
        let hint = match did_you_mean(found, known) {
            Some(m) => format!("did you mean '{m}'? known: {}", known.join(", ")),
            None => format!("known: {}", known.join(", ")),
        };
        self.err(key, format!("unknown '{found}'")).with_hint(hint)
    }
    /// A file named by `key`, relative to the scene; read errors name the key.
    fn file_ref(&self, dir: &Path, key: &str, f: &str) -> Result<PathBuf> {
        let p = dir.join(f);
        match p.is_file() {
            true => {
                self.files.borrow_mut().push(p.clone());
                Ok(p)
            }
            false => Err(self
                .err(key, format!("cannot read '{}'", p.display()))
                .with_hint("the path is relative to the scene file")),
        }
    }
}

impl Ctx<'_> {
    /// Note what the material file `path` says against the constants of `parts` the
    /// scene takes from it ([`file::doubts`]).
    fn doubt(&self, path: &Path, parts: &[&str]) -> Result<()> {
        if let Some(d) = file::doubts(path, parts)? {
            self.doubts.borrow_mut().push(d.sentence(
                "the scene uses them as the file states them, and what depends on them is not determined by data",
            ));
        }
        Ok(())
    }
}

impl Scene {
    /// What a run of the scene says about its material (`simulate` and `static`
    /// alike): a stretch of the run (its smallest and largest, in the plant's
    /// `mode`) outside the range the hyperelastic constants were fitted or
    /// identified over ([`FittedRanges::range_warning`]), and what the material files
    /// say against the constants the scene takes from them ([`Scene::doubts`]).
    pub fn material_warnings(&self, mode: Mode, stretch: (f64, f64)) -> Vec<String> {
        let mut warnings = Vec::new();
        if let Some(fit) = &self.material.fit {
            for lam in [stretch.0, stretch.1] {
                if let Some(wr) = fit.range_warning(mode, lam) {
                    warnings.push(wr);
                }
            }
            warnings.dedup();
        }
        warnings.extend(self.doubts.iter().cloned());
        warnings
    }

    /// Read and validate a scene file.
    pub fn read(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Scene::parse(&text, path)
    }

    /// Parse and validate scene text; `path` names it in errors and anchors
    /// relative file references. Every quantity is checked against the simulator's
    /// table of plausible ranges (`sim::budget`), located at its key.
    pub fn parse(text: &str, path: &Path) -> Result<Scene> {
        // `{ target = "…" }`: a step's fit file of the project above (issue 37)
        let resolved = crate::project::refs::resolve(text, path)?;
        let text: &str = &resolved;
        let root: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let (line, col) = e.span().map(|s| line_col(text, s.start)).unwrap_or((1, 1));
            Error::input(Location::at(path, line, col), e.message().to_string())
                .with_hint("the scene must be valid TOML; see docs/scenes.md")
        })?;
        let mut spans = HashMap::new();
        if let Ok(t) = toml::de::DeTable::parse(text) {
            collect_spans("", t.get_ref(), &mut spans);
        }
        let c = Ctx {
            file: path,
            text,
            spans,
            files: Default::default(),
            doubts: Default::default(),
        };
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        c.known(
            &root,
            "",
            &[
                "name", "actuator", "material", "load", "source", "input", "control", "time",
            ],
        )?;
        let name = c
            .string(&root, "scene", "name")?
            .map(str::to_string)
            .unwrap_or_else(|| {
                path.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "scene".into())
            });
        let (actuator, tolerances) = read_actuator(&c, c.table(&root, "actuator")?)?;
        let material_table = c.table(&root, "material")?;
        let (material, actuator_mass) = read_material(&c, material_table, &dir)?;
        let breakdown = read_breakdown(&c, material_table, &dir, &actuator)?;
        let load = read_load(&c, c.opt_table(&root, "load")?, actuator_mass)?;
        let source = read_source(&c, c.opt_table(&root, "source")?)?;
        let time = read_time(&c, c.table(&root, "time")?)?;
        let control = match c.opt_table(&root, "control")? {
            None => None,
            Some(t) => Some(read_pid(&c, t, &dir)?),
        };
        if control.is_some() && source == Source::Ideal {
            return Err(c
                .err("control", "a closed loop needs a real source")
                .with_hint("give source.rise_time or source.resistance_ohm"));
        }
        let input = match (&control, root.get("input")) {
            (Some(_), None) => Waveform::default(),
            (Some(_), Some(_)) => {
                return Err(c
                    .err(
                        "input",
                        "conflicts with [control]: a closed loop sets the voltage",
                    )
                    .with_hint("drop [[input]] or [control]"))
            }
            (None, v) => read_input(&c, v, &dir, "input", Dimension::Voltage)?,
        };
        let scene = Scene {
            name,
            actuator,
            tolerances,
            material,
            load,
            source,
            input,
            control,
            time,
            files: c.files.take(),
            breakdown,
            doubts: c.doubts.take(),
        };
        budget::validate(&scene).map_err(|v| c.violation(v))?;
        budget::rest_state(&scene).map_err(|v| c.violation(v))?;
        Ok(scene)
    }
}

/// `[actuator]`: a stack or a helix, and the tolerances its lengths state
/// ([`Ctx::length`]).
fn read_actuator(c: &Ctx, t: &toml::Table) -> Result<(Actuator, Vec<Tolerance>)> {
    let s = "actuator";
    let mut tol = Vec::new();
    let actuator = match c.string(t, s, "kind")? {
        Some("stack") => {
            c.known(
                t,
                s,
                &[
                    "kind",
                    "radius",
                    "layer_thickness",
                    "electrode_thickness",
                    "layers",
                    "electrodes",
                ],
            )?;
            let [r, l, e] = Length::STACK;
            Actuator::Stack(StackGeometry {
                radius_m: c.need_length(t, r, &mut tol)?,
                layer_m: c.need_length(t, l, &mut tol)?,
                electrode_m: c.length(t, e, &mut tol)?.unwrap_or(0.0),
                layers: c.need_count(t, s, "layers", &budget::COUNT)?,
                electrodes: c
                    .count(t, s, "electrodes", &budget::ELECTRODE_COUNT)?
                    .unwrap_or(0),
            })
        }
        Some("helix") => {
            c.known(
                t,
                s,
                &[
                    "kind",
                    "outer_radius",
                    "inner_radius",
                    "thickness",
                    "periods",
                    "per_period",
                    "lateral",
                ],
            )?;
            let lateral = match c.string(t, s, "lateral")? {
                None | Some("planar") => Lateral::Planar,
                Some("free") => Lateral::Free,
                Some(o) => {
                    return Err(c
                        .unknown_name("actuator.lateral", o, &["planar", "free"])
                        .with_hint("use planar (El Atrache Ceballos (2021) Eq. 4.18) or free"))
                }
            };
            let [o, i, z] = Length::HELIX;
            Actuator::Helix(HelixGeometry {
                outer_m: c.need_length(t, o, &mut tol)?,
                inner_m: c.need_length(t, i, &mut tol)?,
                thickness_m: c.need_length(t, z, &mut tol)?,
                periods: c.need_count(t, s, "periods", &budget::COUNT)?,
                per_period: c.need_count(t, s, "per_period", &budget::COUNT)?,
                lateral,
            })
        }
        Some(o) => return Err(c.unknown_name("actuator.kind", o, &["stack", "helix"])),
        None => {
            return Err(c
                .err("actuator.kind", "is missing")
                .with_hint("use stack or helix"))
        }
    };
    Ok((actuator, tol))
}

/// The hyperelastic part: a preset, a material file (a hyperelastic fit or an
/// identified material, `material::file`) or a model with inline parameters.
fn read_hyperelastic(c: &Ctx, h: &toml::Table, dir: &Path) -> Result<HyperelasticPart> {
    let hs = "material.hyperelastic";
    c.known(h, hs, &["preset", "fit", "model", "parameters"])?;
    c.one_of(h, hs, &["preset", "fit", "model"])?;
    if let Some(p) = c.string(h, hs, "preset")? {
        c.one_of(h, hs, &["preset", "parameters"])?;
        return match p {
            "vhb4910-yeoh" => Ok(HyperelasticPart {
                spec: ModelSpec::new("yeoh", OgdenForm::Abaqus),
                params: presets::VHB4910_YEOH_PA.to_vec(),
                ranges: None,
            }),
            o => Err(c.unknown_name(&format!("{hs}.preset"), o, &["vhb4910-yeoh"])),
        };
    }
    if let Some(f) = c.string(h, hs, "fit")? {
        c.one_of(h, hs, &["fit", "parameters"])?;
        let path = c.file_ref(dir, &format!("{hs}.fit"), f)?;
        let part = file::read_hyperelastic(&path)?;
        c.doubt(&path, &["hyperelastic"])?;
        return Ok(part);
    }
    let Some(m) = c.string(h, hs, "model")? else {
        return Err(c
            .err(hs, "needs preset, fit or model")
            .with_hint("e.g. hyperelastic = { preset = \"vhb4910-yeoh\" }"));
    };
    if !MODEL_NAMES.contains(&m) {
        return Err(c.unknown_name(&format!("{hs}.model"), m, &MODEL_NAMES));
    }
    let model = ModelSpec::new(m, OgdenForm::Abaqus).build()?;
    let ps = format!("{hs}.parameters");
    let pt = match h.get("parameters") {
        Some(toml::Value::Table(x)) => x,
        Some(_) => return Err(c.err(&ps, "must be a table of name = value")),
        None => {
            return Err(c
                .err(&ps, "is missing")
                .with_hint(expected_params(model.as_ref())))
        }
    };
    let names: Vec<&str> = model.params().iter().map(|p| p.name.as_str()).collect();
    c.known(pt, &ps, &names)?;
    let mut vals = Vec::new();
    for info in model.params() {
        let v = match info.unit {
            "Pa" => c.quantity(pt, &ps, &info.name, Dimension::Stress)?,
            _ => c.number(pt, &ps, &info.name)?,
        };
        vals.push(v.ok_or_else(|| {
            c.err(&format!("{ps}.{}", info.name), "is missing")
                .with_hint(expected_params(model.as_ref()))
        })?);
    }
    Ok(HyperelasticPart {
        spec: ModelSpec::new(m, OgdenForm::Abaqus),
        params: vals,
        ranges: None,
    })
}

/// `material.viscous`, and the time–temperature shift of a DMA fit given as its
/// `fit` (None otherwise).
fn read_viscous(
    c: &Ctx,
    v: Option<&toml::Table>,
    dir: &Path,
) -> Result<(Viscous, Option<TimeTemperature>)> {
    let vs = "material.viscous";
    let Some(v) = v else {
        return Ok((presets::viscous("elastic").expect("preset exists"), None));
    };
    c.known(v, vs, &["preset", "fit", "nv", "arms"])?;
    c.one_of(v, vs, &["preset", "fit", "arms"])?;
    if let Some(p) = c.string(v, vs, "preset")? {
        c.one_of(v, vs, &["preset", "nv"])?;
        let names = presets::viscous_preset_names();
        return presets::viscous(p)
            .map(|v| (v, None))
            .ok_or_else(|| c.unknown_name(&format!("{vs}.preset"), p, &names));
    }
    let nv = c.quantity(v, vs, "nv", Dimension::Viscosity)?;
    if let Some(f) = c.string(v, vs, "fit")? {
        let path = c.file_ref(dir, &format!("{vs}.fit"), f)?;
        let (arms, stated, shift) = file::read_viscous_shift(&path)?;
        c.doubt(&path, &["viscous"])?;
        if stated.is_some() && nv.is_some() {
            return Err(c
                .err(
                    &format!("{vs}.nv"),
                    format!("conflicts with the nv of {vs}.fit"),
                )
                .with_hint("an identified material states its dashpot: drop nv here"));
        }
        return Ok((
            Viscous {
                nv_pa_s: stated.or(nv).unwrap_or(0.0),
                arms,
            },
            shift,
        ));
    }
    let mut arms = Vec::new();
    if let Some(a) = v.get("arms") {
        let list = a
            .as_array()
            .ok_or_else(|| c.err(&format!("{vs}.arms"), "must be an array of tables"))?;
        for (i, a) in list.iter().enumerate() {
            let sec = format!("{vs}.arms[{i}]");
            let at = a.as_table().ok_or_else(|| c.err(&sec, "must be a table"))?;
            c.known(at, &sec, &["k", "eta", "tau"])?;
            c.one_of(at, &sec, &["eta", "tau"])?;
            let k = c.need(at, &sec, "k", Dimension::Stress)?;
            let eta = match c.quantity(at, &sec, "eta", Dimension::Viscosity)? {
                Some(e) => e,
                None => k * c.need(at, &sec, "tau", Dimension::Time)?,
            };
            arms.push(file::Arm {
                k_pa: k,
                eta_pa_s: eta,
            });
        }
    }
    Ok((
        Viscous {
            nv_pa_s: nv.unwrap_or(0.0),
            arms,
        },
        None,
    ))
}

/// `material.temperature` (`"40 C"`, `"-5 C"`, `"313.15 K"`): the viscous part at
/// that temperature, by the time–temperature shift of its DMA fit
/// ([`TimeTemperature`]: every Maxwell arm's τⱼ times aT(T), its kⱼ times bT(T));
/// the hyperelastic part and a stated Kelvin–Voigt dashpot are as given. An arm
/// faster than 1 ns at T is folded into the dashpot, said as a warning. Outside
/// the fit's measured temperatures: a warning ([`Scene::doubts`]); at or below the
/// WLF singularity, or with a viscous part that has no shift: a located error.
fn at_temperature(
    c: &Ctx,
    t: &toml::Table,
    viscous: Viscous,
    shift: Option<&TimeTemperature>,
) -> Result<Viscous> {
    let key = "material.temperature";
    let Some(text) = c.string(t, "material", "temperature")? else {
        return Ok(viscous);
    };
    let k = crate::dma::temperature::parse(text).map_err(|e| {
        c.err(key, e)
            .with_hint("e.g. temperature = \"40 C\" or \"313.15 K\"")
    })?;
    let shift = shift.ok_or_else(|| {
        c.err(
            key,
            "the material has no time–temperature shift: only a DMA fit's viscous part can be taken to another temperature",
        )
        .with_hint("give material.viscous = { fit = \"fits/x-dma.json\" } from dea-fit dma with isotherms (a shift law or free shifts), or drop temperature")
    })?;
    let at = shift.at(k).map_err(|e| {
        c.err(key, e).with_hint(format!(
            "give a temperature above {} or fit another law (dea-fit dma --shift arrhenius|free)",
            crate::dma::temperature::celsius(
                shift.reference_k - shift.law.and_then(|l| l.c2).unwrap_or(0.0)
            )
        ))
    })?;
    if let Some(w) = &at.warning {
        c.doubts
            .borrow_mut()
            .push(format!("{} {key}: {w}", c.loc(key)));
    }
    // an arm faster than the simulator's plausible times (ARM_TIME, 1 ns) at T is
    // its own low-rate limit, a dashpot η = k·τ (stress k·τ·dλ/dt for rates ≪ 1/τ,
    // E″ = ωη, E′ → 0): folded into Nv; one slower than ARM_TIME's 30 000 years is
    // refused
    let (mut nv, mut arms, mut folded) = (viscous.nv_pa_s, Vec::new(), 0);
    for a in viscous.arms.iter().map(|a| at.arm(a)) {
        let tau = a.eta_pa_s / a.k_pa;
        if tau < ARM_TIME.min {
            nv += a.eta_pa_s;
            folded += 1;
        } else if tau > ARM_TIME.max {
            return Err(c
                .err(
                    key,
                    format!(
                        "at {text} an arm's relaxation time is {tau:.3e} s (aT = 10^{:.2}), beyond the {} s the simulator takes: the material is glassy there",
                        at.log10_at, ARM_TIME.max
                    ),
                )
                .with_hint("simulate at a higher temperature"));
        } else {
            arms.push(a);
        }
    }
    if folded > 0 {
        c.doubts.borrow_mut().push(format!(
            "{} {key}: at {text} {folded} of the DMA fit's arms relax faster than {:e} s (aT = 10^{:.3}): each is taken as its low-rate limit, a dashpot k*tau, added to Nv (now {nv:.4e} Pa s)",
            c.loc(key),
            ARM_TIME.min,
            at.log10_at
        ));
    }
    Ok(Viscous { nv_pa_s: nv, arms })
}

/// The material file of `material.identified`, after refusing the scene keys it
/// fills (hyperelastic always, viscous and relative_permittivity when it holds them).
fn read_identified(c: &Ctx, t: &toml::Table, dir: &Path) -> Result<Option<IdentifiedMaterial>> {
    let Some(f) = c.string(t, "material", "identified")? else {
        return Ok(None);
    };
    let path = c.file_ref(dir, "material.identified", f)?;
    let m = IdentifiedMaterial::read(&path)?;
    c.doubt(&path, &["hyperelastic", "viscous", "dielectric"])?;
    for (key, filled) in [
        ("hyperelastic", true),
        ("viscous", m.viscous.is_some()),
        ("relative_permittivity", m.eps_r.is_some()),
    ] {
        if filled && t.contains_key(key) {
            return Err(c
                .err(
                    &format!("material.{key}"),
                    "conflicts with material.identified, whose file gives it",
                )
                .with_hint(format!(
                    "drop material.{key}, or take only some parts of the file: hyperelastic = {{ fit = \"{f}\" }}"
                )));
        }
    }
    Ok(Some(m))
}

/// `material.relative_permittivity`: a number, or a composite's mixing rule at a
/// filler mass fraction (`{ composite = "x.json", mass_fraction = "20 %", rule =
/// "bruggeman", frequency = "100 Hz" }`; rule and frequency optional: the rule the
/// fit ranks first, at its lowest frequency).
fn read_permittivity(
    c: &Ctx,
    t: &toml::Table,
    dir: &Path,
) -> Result<(f64, Option<CompositePermittivity>)> {
    let key = "material.relative_permittivity";
    let Some(toml::Value::Table(p)) = t.get("relative_permittivity") else {
        let e = c.number(t, "material", "relative_permittivity")?.ok_or_else(|| {
            c.err(key, "is missing").with_hint(
                "e.g. relative_permittivity = 4.7, or { composite = \"fits/x.json\", mass_fraction = \"20 %\" }",
            )
        })?;
        return Ok((e, None));
    };
    c.known(p, key, &["composite", "rule", "frequency", "mass_fraction"])?;
    let f = c.string(p, key, "composite")?.ok_or_else(|| {
        c.err(&format!("{key}.composite"), "is missing")
            .with_hint("the composite fit (dea-fit composite --out) whose mixing rule gives εr")
    })?;
    let rule = match c.string(p, key, "rule")? {
        None => None,
        Some(r) => Some(MixingRule::parse(r).ok_or_else(|| {
            let names: Vec<&str> = MixingRule::ALL.iter().map(|m| m.name()).collect();
            c.unknown_name(&format!("{key}.rule"), r, &names)
        })?),
    };
    let freq = c.quantity(p, key, "frequency", Dimension::Frequency)?;
    let w = c.need(p, key, "mass_fraction", Dimension::Fraction)?;
    MASS_FRACTION
        .check(&format!("{key}.mass_fraction"), w)
        .map_err(|v| c.violation(v))?;
    let path = c.file_ref(dir, &format!("{key}.composite"), f)?;
    let (mixture, freq_hz, _) = file::read_mixture(&path, rule, freq)?;
    let comp = CompositePermittivity {
        mixture,
        freq_hz,
        mass_fraction: w,
    };
    Ok((comp.eps_r(), Some(comp)))
}

/// `material.breakdown`: a stated field (`"25 V/um"`, `"25 ± 2 V/um"`, or a bare
/// number in V/m), or a breakdown fit (`{ fit = "fits/x-breakdown.json" }`, relative
/// to the scene, with the film's `prestretch` when the fit has that covariate)
/// carried by [`crate::material::file::BreakdownFit::strength`] to the film under
/// field ([`Actuator::film_area`]) and to its thickness as built (the gap h(1)).
fn read_breakdown(
    c: &Ctx,
    t: &toml::Table,
    dir: &Path,
    actuator: &Actuator,
) -> Result<Option<Strength>> {
    let key = "material.breakdown";
    let hint = "e.g. breakdown = \"25 ± 2 V/um\" (value ± one standard uncertainty), or { fit = \"fits/x-breakdown.json\" } from dea-fit breakdown --out";
    let plausible = |k: &str, v: f64| {
        crate::material::check::BREAKDOWN
            .check(k, v)
            .map_err(|v| c.violation(v))
    };
    let source = || format!("{} {key}", c.loc(key));
    match t.get("breakdown") {
        None => Ok(None),
        Some(toml::Value::String(s)) => {
            let q = parse_uncertain(s, Dimension::ElectricField)
                .map_err(|e| c.err(key, e).with_hint(hint))?;
            plausible(key, q.value)?;
            Ok(Some(Strength::stated(q.value, q.tolerance, source())))
        }
        Some(toml::Value::Float(_) | toml::Value::Integer(_)) => {
            let v = c.number(t, "material", "breakdown")?.unwrap_or(f64::NAN);
            plausible(key, v)?;
            Ok(Some(Strength::stated(v, None, source())))
        }
        Some(toml::Value::Table(b)) => {
            c.known(b, key, &["fit", "prestretch"])?;
            let f = c
                .string(b, key, "fit")?
                .ok_or_else(|| c.err(&format!("{key}.fit"), "is missing").with_hint(hint))?;
            let prestretch = c.number(b, key, "prestretch")?;
            if let Some(p) = prestretch {
                if !(1.0..=100.0).contains(&p) {
                    return Err(c
                        .err(
                            &format!("{key}.prestretch"),
                            format!("must be a stretch from 1 to 100, found {p}"),
                        )
                        .with_hint("the in-plane prestretch λp of the film as made (1: none)"));
                }
            }
            let path = c.file_ref(dir, &format!("{key}.fit"), f)?;
            let fit = file::read_breakdown(&path)?;
            let s = fit.strength(
                Some(actuator.film_area()),
                Some(actuator.gap(1.0)),
                prestretch,
                &path.display().to_string(),
            );
            plausible(key, s.field)?;
            Ok(Some(s))
        }
        Some(v) => Err(c
            .err(
                key,
                format!("expected a field such as \"25 V/um\" or {{ fit = ... }}, found {v}"),
            )
            .with_hint(hint)),
    }
}

fn read_material(c: &Ctx, t: &toml::Table, dir: &Path) -> Result<(Material, Option<f64>)> {
    let s = "material";
    c.known(
        t,
        s,
        &[
            "identified",
            "hyperelastic",
            "viscous",
            "relative_permittivity",
            "density",
            "resistivity_ohm_m",
            "actuator_mass",
            "breakdown",
            "temperature",
        ],
    )?;
    let identified = read_identified(c, t, dir)?;
    let (hyper, viscous, eps_r) = match identified {
        Some(m) => (m.hyperelastic, m.viscous, m.eps_r.map(|e| (e, m.composite))),
        None => {
            let h = match t.get("hyperelastic") {
                Some(toml::Value::Table(h)) => h,
                _ => {
                    return Err(c
                        .err("material.hyperelastic", "is missing or not a table")
                        .with_hint("give { preset = \"vhb4910-yeoh\" }, { fit = \"fits/x.json\" } or { model = \"yeoh\", parameters = { C10 = \"69.3 kPa\", ... } }, or material.identified = \"fits/x.json\""))
                }
            };
            (read_hyperelastic(c, h, dir)?, None, None)
        }
    };
    let (viscous, shift) = match viscous {
        Some(v) => (v, None),
        None => read_viscous(c, c.opt_table(t, "viscous")?, dir)?,
    };
    let viscous = at_temperature(c, t, viscous, shift.as_ref())?;
    let (eps_r, composite) = match eps_r {
        Some(e) => e,
        None => read_permittivity(c, t, dir)?,
    };
    let model: Arc<dyn StrainEnergy> = Arc::from(hyper.spec.build()?);
    let density = c.need(t, s, "density", Dimension::Density)?;
    let resistivity = c.number(t, s, "resistivity_ohm_m")?;
    let mass = c.quantity(t, s, "actuator_mass", Dimension::Mass)?;
    Ok((
        Material {
            spec: hyper.spec,
            model,
            params: hyper.params,
            fit: hyper.ranges.map(Arc::new),
            viscous,
            eps_r,
            composite,
            density,
            resistivity,
        },
        mass,
    ))
}

fn read_load(c: &Ctx, t: Option<&toml::Table>, actuator_mass_kg: Option<f64>) -> Result<Load> {
    let empty = toml::Table::new();
    let t = t.unwrap_or(&empty);
    let s = "load";
    c.known(
        t,
        s,
        &[
            "mass",
            "weight",
            "force",
            "effective_mass_fraction",
            "gravity",
        ],
    )?;
    let gravity = c.number(t, s, "gravity")?.unwrap_or(9.81);
    let mut mass = c.quantity(t, s, "mass", Dimension::Mass)?.unwrap_or(0.0);
    if let Some(w) = c.quantity(t, s, "weight", Dimension::Force)? {
        if gravity <= 0.0 {
            return Err(c
                .err("load.weight", "needs gravity > 0")
                .with_hint("give the hanging mass instead"));
        }
        budget::FORCE
            .check("load.weight", w)
            .map_err(|v| c.violation(v))?;
        mass += w / gravity;
    }
    Ok(Load {
        mass_kg: mass,
        force_n: c.quantity(t, s, "force", Dimension::Force)?.unwrap_or(0.0),
        fraction: c.number(t, s, "effective_mass_fraction")?.unwrap_or(0.5),
        gravity,
        actuator_mass_kg,
    })
}

fn read_source(c: &Ctx, t: Option<&toml::Table>) -> Result<Source> {
    let Some(t) = t else {
        return Ok(Source::Ideal);
    };
    c.known(t, "source", &["rise_time", "resistance_ohm"])?;
    c.one_of(t, "source", &["rise_time", "resistance_ohm"])?;
    let rise = c.quantity(t, "source", "rise_time", Dimension::Time)?;
    let r = c.number(t, "source", "resistance_ohm")?;
    Ok(match (rise, r) {
        (Some(tau), _) => Source::RiseTime { tau_s: tau },
        (None, Some(ohm)) => Source::Resistance { ohm },
        (None, None) => Source::Ideal,
    })
}

fn read_time(c: &Ctx, t: &toml::Table) -> Result<TimeSpec> {
    let s = "time";
    c.known(
        t,
        s,
        &[
            "span",
            "samples",
            "sample_times",
            "rtol",
            "atol",
            "integrator",
            "fidelity",
        ],
    )?;
    c.one_of(t, s, &["samples", "sample_times"])?;
    let span = c.need(t, s, "span", Dimension::Time)?;
    budget::SPAN
        .check("time.span", span)
        .map_err(|v| c.violation(v))?;
    let samples = match t.get("sample_times") {
        Some(list) => read_sample_times(c, list, span)?,
        None => {
            // checked before the sample times are allocated
            let n = c.count(t, s, "samples", &budget::SAMPLES)?.unwrap_or(1000);
            (1..=n).map(|i| span * i as f64 / n as f64).collect()
        }
    };
    let rtol = c.number(t, s, "rtol")?.unwrap_or(1e-6);
    let atol = c.number(t, s, "atol")?.unwrap_or(rtol * 1e-3);
    let method = match c.string(t, s, "integrator")? {
        None | Some("auto") => None,
        Some(o) => match Method::parse(o) {
            Some(m) => Some(m),
            None => {
                let names: Vec<&str> = std::iter::once("auto")
                    .chain(Method::ALL.map(Method::name))
                    .collect();
                return Err(c.unknown_name("time.integrator", o, &names));
            }
        },
    };
    let fidelity = match c.string(t, s, "fidelity")? {
        None | Some("auto") => FidelityChoice::Auto,
        Some("dynamic") => FidelityChoice::Dynamic,
        Some("quasi-static") => FidelityChoice::QuasiStatic,
        Some(o) => {
            return Err(c.unknown_name("time.fidelity", o, &["auto", "dynamic", "quasi-static"]))
        }
    };
    Ok(TimeSpec {
        span,
        samples,
        rtol,
        atol,
        method,
        fidelity,
    })
}

/// `time.sample_times`: explicit output times, numbers in s or strings with a unit,
/// strictly increasing, in (0, span], at most the sample-count limit.
fn read_sample_times(c: &Ctx, list: &toml::Value, span: f64) -> Result<Vec<f64>> {
    let key = "time.sample_times";
    let items = list.as_array().ok_or_else(|| {
        c.err(key, "must be a list of times")
            .with_hint("e.g. sample_times = [0.1, 0.25, \"0.5 s\", \"800 ms\"]")
    })?;
    budget::SAMPLES
        .check(key, items.len() as f64)
        .map_err(|v| c.violation(v))?;
    let mut out: Vec<f64> = Vec::with_capacity(items.len());
    for (i, x) in items.iter().enumerate() {
        let k = format!("{key}[{i}]");
        let v = match x {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(n) => *n as f64,
            toml::Value::String(q) => {
                parse_quantity(q, Dimension::Time).map_err(|e| c.err(&k, e))?
            }
            o => return Err(c.err(&k, format!("expected a time such as \"0.5 s\", found {o}"))),
        };
        let prev = out.last().copied().unwrap_or(0.0);
        if !(v.is_finite() && v > prev && v <= span) {
            let why = match (v.is_finite(), v <= span) {
                (false, _) => "must be a finite time".to_string(),
                (true, false) => format!("{v} s is after the end of the span ({span} s)"),
                (true, true) if i == 0 => {
                    format!("{v} s must be after 0 (the run's start is always sampled)")
                }
                _ => format!("{v} s is not after the previous time {prev} s"),
            };
            return Err(c
                .err(&k, why)
                .with_hint("sample times increase strictly within (0, time.span]"));
        }
        out.push(v);
    }
    Ok(out)
}

fn read_pid(c: &Ctx, t: &toml::Table, dir: &Path) -> Result<Pid> {
    let s = "control";
    c.known(
        t,
        s,
        &[
            "kind",
            "kp",
            "ki",
            "kd",
            "derivative_filter",
            "max_voltage",
            "reference",
        ],
    )?;
    match c.string(t, s, "kind")? {
        Some("pid") => {}
        Some(o) => return Err(c.unknown_name("control.kind", o, &["pid"])),
        None => {
            return Err(c
                .err("control.kind", "is missing")
                .with_hint("kind = \"pid\""))
        }
    }
    Ok(Pid {
        kp: c.number(t, s, "kp")?.unwrap_or(0.0),
        ki: c.number(t, s, "ki")?.unwrap_or(0.0),
        kd: c.number(t, s, "kd")?.unwrap_or(0.0),
        tau_d: c
            .quantity(t, s, "derivative_filter", Dimension::Time)?
            .unwrap_or(1e-3),
        v_max: c.need(t, s, "max_voltage", Dimension::Voltage)?,
        reference: read_input(
            c,
            t.get("reference"),
            dir,
            "control.reference",
            Dimension::Fraction,
        )?,
    })
}

/// Keys of each input kind.
const INPUT_KEYS: [(&str, &[&str]); 5] = [
    ("step", &["kind", "at", "amplitude"]),
    ("ramp", &["kind", "start", "end", "from", "to"]),
    (
        "triangle",
        &[
            "kind",
            "start",
            "amplitude",
            "frequency",
            "cycles",
            "offset",
        ],
    ),
    (
        "sine",
        &[
            "kind",
            "start",
            "amplitude",
            "frequency",
            "phase_rad",
            "offset",
            "cycles",
        ],
    ),
    ("csv", &["kind", "file", "smooth"]),
];

fn read_input(
    c: &Ctx,
    v: Option<&toml::Value>,
    dir: &Path,
    sec: &str,
    dim: Dimension,
) -> Result<Waveform> {
    let list: Vec<(String, &toml::Table)> = match v {
        None => {
            return Err(c
                .err(sec, "is missing")
                .with_hint("e.g. [[input]] kind = \"step\", amplitude = \"5 kV\""))
        }
        Some(toml::Value::Table(t)) => vec![(sec.to_string(), t)],
        Some(toml::Value::Array(a)) => a
            .iter()
            .enumerate()
            .map(|(i, x)| {
                let s = format!("{sec}[{i}]");
                x.as_table()
                    .map(|t| (s.clone(), t))
                    .ok_or_else(|| c.err(&s, "must be a table"))
            })
            .collect::<Result<_>>()?,
        Some(_) => return Err(c.err(sec, "must be a table or an array of tables")),
    };
    let kinds: Vec<&str> = INPUT_KEYS.iter().map(|k| k.0).collect();
    let mut terms = Vec::new();
    for (s, t) in &list {
        let s = s.as_str();
        let kind = match c.string(t, s, "kind")? {
            Some(k) => k,
            None => {
                return Err(c
                    .err(&format!("{s}.kind"), "is missing")
                    .with_hint(format!("use one of {}", kinds.join(", "))))
            }
        };
        let Some((_, keys)) = INPUT_KEYS.iter().find(|k| k.0 == kind) else {
            return Err(c.unknown_name(&format!("{s}.kind"), kind, &kinds));
        };
        c.known(t, s, keys)?;
        let vq = |k: &str| c.quantity(t, s, k, dim);
        let tq = |k: &str| c.quantity(t, s, k, Dimension::Time);
        let term = match kind {
            "step" => Term::Step {
                at: tq("at")?.unwrap_or(0.0),
                amplitude: c.need(t, s, "amplitude", dim)?,
            },
            "ramp" => Term::Ramp {
                start: c.need(t, s, "start", Dimension::Time)?,
                end: c.need(t, s, "end", Dimension::Time)?,
                from: vq("from")?.unwrap_or(0.0),
                to: c.need(t, s, "to", dim)?,
            },
            "triangle" => Term::Triangle {
                start: tq("start")?.unwrap_or(0.0),
                amplitude: c.need(t, s, "amplitude", dim)?,
                frequency: c.need(t, s, "frequency", Dimension::Frequency)?,
                cycles: c.number(t, s, "cycles")?.unwrap_or(1.0),
                offset: vq("offset")?.unwrap_or(0.0),
            },
            "sine" => Term::Sine {
                start: tq("start")?.unwrap_or(0.0),
                amplitude: c.need(t, s, "amplitude", dim)?,
                frequency: c.need(t, s, "frequency", Dimension::Frequency)?,
                phase: c.number(t, s, "phase_rad")?.unwrap_or(0.0),
                offset: vq("offset")?.unwrap_or(0.0),
                cycles: c.number(t, s, "cycles")?,
            },
            _ => {
                let key = format!("{s}.file");
                let f = c
                    .string(t, s, "file")?
                    .ok_or_else(|| c.err(&key, "is missing").with_hint("file = \"v.csv\""))?;
                let points = read_pwl(&c.file_ref(dir, &key, f)?)?;
                match t.get("smooth") {
                    None | Some(toml::Value::Boolean(false)) => Term::Pwl { points },
                    // a measured signal: smooth between its real corners
                    Some(toml::Value::Boolean(true)) => {
                        let (ts, vs): (Vec<f64>, Vec<f64>) = points.into_iter().unzip();
                        Term::Measured(std::sync::Arc::new(
                            super::input::Measured::fit(&ts, &vs).map_err(|e| c.err(&key, e))?,
                        ))
                    }
                    Some(o) => {
                        return Err(c
                            .err(&format!("{s}.smooth"), format!("expected true or false, found {o}"))
                            .with_hint("smooth = true reads a measured voltage as one smooth input with its real corners"))
                    }
                }
            }
        };
        terms.push(term);
    }
    Ok(Waveform { terms })
}

/// Piecewise-linear input: a table with columns `time` and `voltage` (units in the
/// header, e.g. `time_s,voltage_kV` or `time [ms], voltage [V]`). Every point is
/// checked at its line against the time and voltage ranges of `sim::budget`.
fn read_pwl(path: &Path) -> Result<Vec<(f64, f64)>> {
    let table = crate::io::table::Table::read(path)?;
    let find = |what: &str, dim: Dimension| -> Result<(usize, f64)> {
        for (i, h) in table.header.iter().enumerate() {
            let l = h.to_ascii_lowercase();
            if l.starts_with(what) {
                let unit = h[what.len()..].trim_matches(|c: char| {
                    c == '_' || c == ' ' || c == '[' || c == ']' || c == '(' || c == ')'
                });
                let f = if unit.is_empty() {
                    Some(1.0)
                } else {
                    dim.factor(unit)
                };
                return f.map(|f| (i, f)).ok_or_else(|| {
                    Error::input(
                        Location::line(path, table.header_line),
                        format!("column '{h}': unknown unit '{unit}'"),
                    )
                    .with_hint(format!("use one of {}", dim.accepted()))
                });
            }
        }
        Err(Error::input(
            Location::line(path, table.header_line),
            format!("no '{what}' column"),
        )
        .with_hint("the header needs time_s and voltage_V (or other units)"))
    };
    let (ct, ft) = find("time", Dimension::Time)?;
    let (cv, fv) = find("voltage", Dimension::Voltage)?;
    let mut pts: Vec<(f64, f64)> = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let t = table.number(row, ct, "time")? * ft;
        let v = table.number(row, cv, "voltage")? * fv;
        for (col, dom, x) in [(ct, &budget::INSTANT, t), (cv, &budget::VOLTAGE, v)] {
            dom.check(&table.header[col], x).map_err(|e| {
                Error::input(Location::at(path, row.line(), col + 1), e.msg).with_hint(e.hint)
            })?;
        }
        if let Some(&(tp, _)) = pts.last() {
            if t <= tp {
                return Err(Error::input(
                    Location::at(path, row.line(), ct + 1),
                    format!("time {t} s is not after the previous {tp} s"),
                )
                .with_hint("times must increase strictly"));
            }
        }
        pts.push((t, v));
    }
    if pts.len() < 2 {
        return Err(Error::input(
            Location::file(path),
            "a piecewise-linear input needs at least 2 points",
        ));
    }
    Ok(pts)
}
