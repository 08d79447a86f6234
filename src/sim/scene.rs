//! Scene files (TOML) → validated [`Scene`]. The format is documented in
//! `docs/scenes.md`. Quantities are strings with a unit (`"2.25 mm"`, `"5 kV"`) or
//! bare SI numbers; keys that carry no unit table name the unit (`resistivity_ohm_m`).

use super::input::{Term, Waveform};
use super::integrate::Method;
use super::presets;
use crate::error::{Error, Location, Result};
use crate::fit::hyperelastic::HyperelasticFit;
use crate::material::hyperelastic::{ModelSpec, OgdenForm, StrainEnergy};
use crate::units::{parse_quantity, Dimension};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One Maxwell arm: spring k in series with dashpot η (τ = η/k), seed Eq. 3.16.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Arm {
    /// Spring modulus (Pa).
    pub k_pa: f64,
    /// Dashpot viscosity (Pa·s).
    pub eta_pa_s: f64,
}

/// Viscous part of the seed's generalised Kelvin-Maxwell model: Kelvin-Voigt dashpot
/// Nv (σ = Nv·dλ/dt, Eq. 3.14 read as strain rate) and Maxwell arms.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Viscous {
    /// Kelvin-Voigt dashpot (Pa·s).
    pub nv_pa_s: f64,
    /// Maxwell arms.
    pub arms: Vec<Arm>,
}

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

/// Material constants.
#[derive(Clone)]
pub struct Material {
    /// Hyperelastic model (registry name).
    pub model_name: String,
    /// Evaluator.
    pub model: Arc<dyn StrainEnergy>,
    /// Parameters (SI, model order).
    pub params: Vec<f64>,
    /// The fit the constants came from, if any (for range warnings).
    pub fit: Option<Arc<HyperelasticFit>>,
    /// Viscous constants.
    pub viscous: Viscous,
    /// Relative permittivity εr.
    pub eps_r: f64,
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
    /// Actuator.
    pub actuator: Actuator,
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
}

struct Ctx<'a> {
    file: &'a Path,
}

impl Ctx<'_> {
    fn err(&self, msg: impl Into<String>) -> Error {
        Error::input(Location::file(self.file), msg)
    }
    fn table<'t>(&self, t: &'t toml::Table, key: &str) -> Result<&'t toml::Table> {
        match t.get(key) {
            Some(toml::Value::Table(x)) => Ok(x),
            Some(_) => Err(self.err(format!("[{key}] must be a table"))),
            None => Err(self
                .err(format!("missing [{key}] section"))
                .with_hint("see docs/scenes.md for the scene format")),
        }
    }
    /// A quantity: a string with a unit, or a bare SI number.
    fn quantity(
        &self,
        t: &toml::Table,
        sec: &str,
        key: &str,
        dim: Dimension,
    ) -> Result<Option<f64>> {
        match t.get(key) {
            None => Ok(None),
            Some(toml::Value::Float(x)) => Ok(Some(*x)),
            Some(toml::Value::Integer(x)) => Ok(Some(*x as f64)),
            Some(toml::Value::String(s)) => parse_quantity(s, dim)
                .map(|q| Some(q.value))
                .map_err(|e| self.err(format!("{sec}.{key}: {e}"))),
            Some(v) => Err(self.err(format!(
                "{sec}.{key}: expected a quantity such as \"1 {}\", found {v}",
                dim.si()
            ))),
        }
    }
    fn need(&self, t: &toml::Table, sec: &str, key: &str, dim: Dimension) -> Result<f64> {
        self.quantity(t, sec, key, dim)?.ok_or_else(|| {
            self.err(format!("{sec}.{key} is missing"))
                .with_hint(format!(
                    "give it with a unit, e.g. {key} = \"1 {}\"",
                    dim.si()
                ))
        })
    }
    fn positive(&self, t: &toml::Table, sec: &str, key: &str, dim: Dimension) -> Result<f64> {
        let v = self.need(t, sec, key, dim)?;
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(format!("{sec}.{key} must be positive, found {v}")))
        }
    }
    fn number(&self, t: &toml::Table, sec: &str, key: &str) -> Result<Option<f64>> {
        match t.get(key) {
            None => Ok(None),
            Some(toml::Value::Float(x)) => Ok(Some(*x)),
            Some(toml::Value::Integer(x)) => Ok(Some(*x as f64)),
            Some(v) => Err(self.err(format!("{sec}.{key}: expected a number, found {v}"))),
        }
    }
    fn count(&self, t: &toml::Table, sec: &str, key: &str, min: i64) -> Result<usize> {
        match t.get(key) {
            Some(toml::Value::Integer(x)) if *x >= min => Ok(*x as usize),
            Some(v) => Err(self.err(format!(
                "{sec}.{key}: expected an integer ≥ {min}, found {v}"
            ))),
            None => Err(self.err(format!("{sec}.{key} is missing"))),
        }
    }
    fn string<'t>(&self, t: &'t toml::Table, sec: &str, key: &str) -> Result<Option<&'t str>> {
        match t.get(key) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.err(format!("{sec}.{key}: expected a string, found {v}"))),
        }
    }
    fn unknown_keys(&self, t: &toml::Table, sec: &str, known: &[&str]) -> Result<()> {
        for k in t.keys() {
            if !known.contains(&k.as_str()) {
                return Err(self
                    .err(format!("{sec}: unknown key '{k}'"))
                    .with_hint(format!("known keys: {}", known.join(", "))));
            }
        }
        Ok(())
    }
}

impl Scene {
    /// Read and validate a scene file.
    pub fn read(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Scene::parse(&text, path)
    }

    /// Parse and validate scene text; `path` names it in errors and anchors
    /// relative file references.
    pub fn parse(text: &str, path: &Path) -> Result<Scene> {
        let root: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let (line, col) = e
                .span()
                .map(|s| {
                    let before = &text[..s.start.min(text.len())];
                    let line = before.matches('\n').count() + 1;
                    let col = before.len() - before.rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
                    (line, col)
                })
                .unwrap_or((1, 1));
            Error::input(Location::at(path, line, col), e.message().to_string())
                .with_hint("the scene must be valid TOML; see docs/scenes.md")
        })?;
        let c = Ctx { file: path };
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        c.unknown_keys(
            &root,
            "scene",
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
        let actuator = read_actuator(&c, c.table(&root, "actuator")?)?;
        let (material, actuator_mass) = read_material(&c, c.table(&root, "material")?, &dir)?;
        let load = read_load(&c, root.get("load"), actuator_mass)?;
        let source = read_source(&c, root.get("source"))?;
        let time = read_time(&c, c.table(&root, "time")?)?;
        let control = match root.get("control") {
            None => None,
            Some(toml::Value::Table(t)) => Some(read_pid(&c, t, &dir)?),
            Some(_) => return Err(c.err("[control] must be a table")),
        };
        if control.is_some() && source == Source::Ideal {
            return Err(c
                .err("a closed loop needs a real source")
                .with_hint("give source.rise_time or source.resistance_ohm"));
        }
        let input = match (&control, root.get("input")) {
            (Some(_), None) => Waveform::default(),
            (_, v) => read_input(&c, v, &dir, "input", Dimension::Voltage)?,
        };
        Ok(Scene {
            name,
            actuator,
            material,
            load,
            source,
            input,
            control,
            time,
        })
    }
}

fn read_actuator(c: &Ctx, t: &toml::Table) -> Result<Actuator> {
    let s = "actuator";
    match c.string(t, s, "kind")? {
        Some("stack") => {
            c.unknown_keys(
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
            Ok(Actuator::Stack(StackGeometry {
                radius_m: c.positive(t, s, "radius", Dimension::Length)?,
                layer_m: c.positive(t, s, "layer_thickness", Dimension::Length)?,
                electrode_m: c
                    .quantity(t, s, "electrode_thickness", Dimension::Length)?
                    .unwrap_or(0.0)
                    .max(0.0),
                layers: c.count(t, s, "layers", 1)?,
                electrodes: match t.get("electrodes") {
                    None => 0,
                    Some(_) => c.count(t, s, "electrodes", 0)?,
                },
            }))
        }
        Some("helix") => {
            c.unknown_keys(
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
            let outer = c.positive(t, s, "outer_radius", Dimension::Length)?;
            let inner = c.positive(t, s, "inner_radius", Dimension::Length)?;
            if inner >= outer {
                return Err(c.err(format!(
                    "actuator.inner_radius ({inner} m) must be smaller than outer_radius ({outer} m)"
                )));
            }
            let lateral = match c.string(t, s, "lateral")? {
                None | Some("planar") => Lateral::Planar,
                Some("free") => Lateral::Free,
                Some(o) => {
                    return Err(c
                        .err(format!("actuator.lateral: unknown '{o}'"))
                        .with_hint("use planar (seed Eq. 4.18) or free"))
                }
            };
            Ok(Actuator::Helix(HelixGeometry {
                outer_m: outer,
                inner_m: inner,
                thickness_m: c.positive(t, s, "thickness", Dimension::Length)?,
                periods: c.count(t, s, "periods", 1)?,
                per_period: c.count(t, s, "per_period", 1)?,
                lateral,
            }))
        }
        Some(o) => Err(c
            .err(format!("actuator.kind: unknown '{o}'"))
            .with_hint("use stack or helix")),
        None => Err(c
            .err("actuator.kind is missing")
            .with_hint("use stack or helix")),
    }
}

fn read_material(c: &Ctx, t: &toml::Table, dir: &Path) -> Result<(Material, Option<f64>)> {
    let s = "material";
    c.unknown_keys(
        t,
        s,
        &[
            "hyperelastic",
            "viscous",
            "relative_permittivity",
            "density",
            "resistivity_ohm_m",
            "actuator_mass",
        ],
    )?;
    let h = match t.get("hyperelastic") {
        Some(toml::Value::Table(h)) => h,
        _ => {
            return Err(c
                .err("material.hyperelastic is missing")
                .with_hint("give { preset = \"vhb4910-yeoh\" }, { fit = \"fits/x.json\" } or { model = \"yeoh\", parameters = { C10 = \"69.3 kPa\", ... } }"))
        }
    };
    let hs = "material.hyperelastic";
    let (model_name, params, fit) = if let Some(p) = c.string(h, hs, "preset")? {
        match p {
            "vhb4910-yeoh" => ("yeoh".to_string(), presets::VHB4910_YEOH_PA.to_vec(), None),
            o => {
                return Err(c
                    .err(format!("{hs}.preset: unknown '{o}'"))
                    .with_hint("known: vhb4910-yeoh"))
            }
        }
    } else if let Some(f) = c.string(h, hs, "fit")? {
        let p: PathBuf = dir.join(f);
        let text = std::fs::read_to_string(&p).map_err(|e| Error::io(&p, e))?;
        let fit: HyperelasticFit = serde_json::from_str(&text).map_err(|e| {
            Error::input(
                Location::line(&p, e.line()),
                format!("not a hyperelastic fit file: {e}"),
            )
        })?;
        (fit.model.clone(), fit.values(), Some(Arc::new(fit)))
    } else if let Some(m) = c.string(h, hs, "model")? {
        let spec = ModelSpec::new(m, OgdenForm::Seed);
        let model = spec.build()?;
        let pt = match h.get("parameters") {
            Some(toml::Value::Table(x)) => x,
            _ => return Err(c.err(format!("{hs}.parameters is missing"))),
        };
        let mut vals = Vec::new();
        for info in model.params() {
            let dim = if info.unit == "Pa" {
                Dimension::Stress
            } else {
                Dimension::Time
            };
            let v = if info.unit == "Pa" {
                c.quantity(pt, hs, &info.name, dim)?
            } else {
                c.number(pt, hs, &info.name)?
            };
            vals.push(v.ok_or_else(|| c.err(format!("{hs}.parameters.{} is missing", info.name)))?);
        }
        (m.to_string(), vals, None)
    } else {
        return Err(c
            .err(format!("{hs} needs preset, fit or model"))
            .with_hint("e.g. hyperelastic = { preset = \"vhb4910-yeoh\" }"));
    };
    let model: Arc<dyn StrainEnergy> = Arc::from(
        ModelSpec {
            name: model_name.clone(),
            form: fit
                .as_ref()
                .and_then(|f: &Arc<HyperelasticFit>| f.form)
                .or(model_name.starts_with("ogden").then_some(OgdenForm::Seed)),
        }
        .build()?,
    );
    if model.initial_shear_modulus(&params) <= 0.0 {
        return Err(c.err("material.hyperelastic: the initial shear modulus is not positive"));
    }
    let viscous = match t.get("viscous") {
        None => presets::viscous("elastic").expect("preset exists"),
        Some(toml::Value::Table(v)) => {
            let vs = "material.viscous";
            if let Some(p) = c.string(v, vs, "preset")? {
                presets::viscous(p).ok_or_else(|| {
                    c.err(format!("{vs}.preset: unknown '{p}'"))
                        .with_hint(format!(
                            "known: {}",
                            presets::viscous_preset_names().join(", ")
                        ))
                })?
            } else {
                let nv = c
                    .quantity(v, vs, "nv", Dimension::Viscosity)?
                    .unwrap_or(0.0);
                let mut arms = Vec::new();
                if let Some(a) = v.get("arms") {
                    let list = a
                        .as_array()
                        .ok_or_else(|| c.err(format!("{vs}.arms must be an array of tables")))?;
                    for (i, a) in list.iter().enumerate() {
                        let at = a
                            .as_table()
                            .ok_or_else(|| c.err(format!("{vs}.arms[{i}] must be a table")))?;
                        let sec = format!("{vs}.arms[{i}]");
                        let k = c.positive(at, &sec, "k", Dimension::Stress)?;
                        let eta = match c.quantity(at, &sec, "eta", Dimension::Viscosity)? {
                            Some(e) => e,
                            None => k * c.positive(at, &sec, "tau", Dimension::Time)?,
                        };
                        if eta <= 0.0 {
                            return Err(c.err(format!("{sec}.eta must be positive")));
                        }
                        arms.push(Arm {
                            k_pa: k,
                            eta_pa_s: eta,
                        });
                    }
                }
                if nv < 0.0 {
                    return Err(c.err(format!("{vs}.nv must not be negative")));
                }
                Viscous { nv_pa_s: nv, arms }
            }
        }
        Some(_) => return Err(c.err("material.viscous must be a table")),
    };
    let eps_r = c
        .number(t, s, "relative_permittivity")?
        .ok_or_else(|| c.err("material.relative_permittivity is missing"))?;
    if eps_r < 1.0 {
        return Err(c.err(format!(
            "material.relative_permittivity must be ≥ 1, found {eps_r}"
        )));
    }
    let density = c.positive(t, s, "density", Dimension::Density)?;
    let resistivity = c.number(t, s, "resistivity_ohm_m")?;
    if resistivity.is_some_and(|r| r <= 0.0) {
        return Err(c.err("material.resistivity_ohm_m must be positive"));
    }
    let mass = c.quantity(t, s, "actuator_mass", Dimension::Mass)?;
    Ok((
        Material {
            model_name,
            model,
            params,
            fit,
            viscous,
            eps_r,
            density,
            resistivity,
        },
        mass,
    ))
}

fn read_load(c: &Ctx, v: Option<&toml::Value>, actuator_mass_kg: Option<f64>) -> Result<Load> {
    let empty = toml::Table::new();
    let t = match v {
        None => &empty,
        Some(toml::Value::Table(t)) => t,
        Some(_) => return Err(c.err("[load] must be a table")),
    };
    let s = "load";
    c.unknown_keys(
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
            return Err(c.err("load.weight needs gravity > 0"));
        }
        mass += w / gravity;
    }
    let fraction = c.number(t, s, "effective_mass_fraction")?.unwrap_or(0.5);
    if !(0.0..=1.0).contains(&fraction) || mass < 0.0 {
        return Err(c.err("load: mass must be ≥ 0 and effective_mass_fraction in [0, 1]"));
    }
    Ok(Load {
        mass_kg: mass,
        force_n: c.quantity(t, s, "force", Dimension::Force)?.unwrap_or(0.0),
        fraction,
        gravity,
        actuator_mass_kg,
    })
}

fn read_source(c: &Ctx, v: Option<&toml::Value>) -> Result<Source> {
    let t = match v {
        None => return Ok(Source::Ideal),
        Some(toml::Value::Table(t)) => t,
        Some(_) => return Err(c.err("[source] must be a table")),
    };
    c.unknown_keys(t, "source", &["rise_time", "resistance_ohm"])?;
    let rise = c.quantity(t, "source", "rise_time", Dimension::Time)?;
    let r = c.number(t, "source", "resistance_ohm")?;
    match (rise, r) {
        (Some(_), Some(_)) => Err(c.err("source: give rise_time or resistance_ohm, not both")),
        (Some(tau), None) if tau > 0.0 => Ok(Source::RiseTime { tau_s: tau }),
        (None, Some(ohm)) if ohm > 0.0 => Ok(Source::Resistance { ohm }),
        (None, None) => Ok(Source::Ideal),
        _ => Err(c.err("source: rise_time and resistance_ohm must be positive")),
    }
}

fn read_time(c: &Ctx, t: &toml::Table) -> Result<TimeSpec> {
    let s = "time";
    c.unknown_keys(
        t,
        s,
        &["span", "samples", "rtol", "atol", "integrator", "fidelity"],
    )?;
    let span = c.positive(t, s, "span", Dimension::Time)?;
    let n = match t.get("samples") {
        None => 1000,
        Some(_) => c.count(t, s, "samples", 1)?,
    };
    let rtol = c.number(t, s, "rtol")?.unwrap_or(1e-6);
    let atol = c.number(t, s, "atol")?.unwrap_or(rtol * 1e-3);
    if !(rtol > 0.0 && rtol < 0.1 && atol > 0.0) {
        return Err(c.err(format!(
            "time.rtol must be in (0, 0.1) and atol > 0, found {rtol}, {atol}"
        )));
    }
    let method = match c.string(t, s, "integrator")? {
        None | Some("auto") => None,
        Some(o) => match Method::parse(o) {
            Some(m) => Some(m),
            None => {
                return Err(c
                    .err(format!("time.integrator: unknown '{o}'"))
                    .with_hint("use auto, bdf, esdirk34, tr-bdf2, tsit45 or dp54"))
            }
        },
    };
    let fidelity = match c.string(t, s, "fidelity")? {
        None | Some("auto") => FidelityChoice::Auto,
        Some("dynamic") => FidelityChoice::Dynamic,
        Some("quasi-static") => FidelityChoice::QuasiStatic,
        Some(o) => {
            return Err(c
                .err(format!("time.fidelity: unknown '{o}'"))
                .with_hint("use auto, dynamic or quasi-static"))
        }
    };
    Ok(TimeSpec {
        span,
        samples: (1..=n).map(|i| span * i as f64 / n as f64).collect(),
        rtol,
        atol,
        method,
        fidelity,
    })
}

fn read_pid(c: &Ctx, t: &toml::Table, dir: &Path) -> Result<Pid> {
    let s = "control";
    c.unknown_keys(
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
        _ => return Err(c.err("control.kind must be \"pid\"")),
    }
    let g = |k: &str| -> Result<f64> {
        let v = c.number(t, s, k)?.unwrap_or(0.0);
        if v < 0.0 || !v.is_finite() {
            return Err(c.err(format!("control.{k} must be ≥ 0, found {v}")));
        }
        Ok(v)
    };
    Ok(Pid {
        kp: g("kp")?,
        ki: g("ki")?,
        kd: g("kd")?,
        tau_d: c
            .quantity(t, s, "derivative_filter", Dimension::Time)?
            .unwrap_or(1e-3)
            .max(1e-9),
        v_max: c.positive(t, s, "max_voltage", Dimension::Voltage)?,
        reference: read_input(
            c,
            t.get("reference"),
            dir,
            "control.reference",
            Dimension::Fraction,
        )?,
    })
}

fn read_input(
    c: &Ctx,
    v: Option<&toml::Value>,
    dir: &Path,
    sec: &str,
    dim: Dimension,
) -> Result<Waveform> {
    let list: Vec<&toml::Table> = match v {
        None => {
            return Err(c
                .err("missing [[input]]")
                .with_hint("e.g. [[input]] kind = \"step\", amplitude = \"5 kV\""))
        }
        Some(toml::Value::Table(t)) => vec![t],
        Some(toml::Value::Array(a)) => a
            .iter()
            .map(|x| {
                x.as_table()
                    .ok_or_else(|| c.err("[[input]] entries must be tables"))
            })
            .collect::<Result<_>>()?,
        Some(_) => return Err(c.err("[[input]] must be a table or array of tables")),
    };
    let mut terms = Vec::new();
    for (i, t) in list.into_iter().enumerate() {
        let s = format!("{sec}[{i}]");
        let s = s.as_str();
        let vq = |k: &str| c.quantity(t, s, k, dim);
        let tq = |k: &str| c.quantity(t, s, k, Dimension::Time);
        let term = match c.string(t, s, "kind")? {
            Some("step") => Term::Step {
                at: tq("at")?.unwrap_or(0.0),
                amplitude: c.need(t, s, "amplitude", dim)?,
            },
            Some("ramp") => {
                let (start, end) = (
                    c.need(t, s, "start", Dimension::Time)?,
                    c.need(t, s, "end", Dimension::Time)?,
                );
                if end <= start {
                    return Err(c.err(format!("{s}: end must be after start")));
                }
                Term::Ramp {
                    start,
                    end,
                    from: vq("from")?.unwrap_or(0.0),
                    to: c.need(t, s, "to", dim)?,
                }
            }
            Some("triangle") => Term::Triangle {
                start: tq("start")?.unwrap_or(0.0),
                amplitude: c.need(t, s, "amplitude", dim)?,
                frequency: c.positive(t, s, "frequency", Dimension::Frequency)?,
                cycles: c.number(t, s, "cycles")?.unwrap_or(1.0),
                offset: vq("offset")?.unwrap_or(0.0),
            },
            Some("sine") => Term::Sine {
                start: tq("start")?.unwrap_or(0.0),
                amplitude: c.need(t, s, "amplitude", dim)?,
                frequency: c.positive(t, s, "frequency", Dimension::Frequency)?,
                phase: c.number(t, s, "phase_rad")?.unwrap_or(0.0),
                offset: vq("offset")?.unwrap_or(0.0),
                cycles: c.number(t, s, "cycles")?,
            },
            Some("csv") => {
                let f = c
                    .string(t, s, "file")?
                    .ok_or_else(|| c.err(format!("{s}.file is missing")))?;
                Term::Pwl {
                    points: read_pwl(&dir.join(f))?,
                }
            }
            Some(o) => {
                return Err(c
                    .err(format!("{s}.kind: unknown '{o}'"))
                    .with_hint("use step, ramp, triangle, sine or csv"))
            }
            None => return Err(c.err(format!("{s}.kind is missing"))),
        };
        if term.kinks().iter().any(|k| !k.is_finite()) {
            return Err(c.err(format!("{s}: times must be finite")));
        }
        terms.push(term);
    }
    Ok(Waveform { terms })
}

/// Piecewise-linear input: a table with columns `time` and `voltage` (units in the
/// header, e.g. `time_s,voltage_kV` or `time [ms], voltage [V]`).
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
    for r in 0..table.rows.len() {
        let t = table.number(&table.rows[r], ct, "time")? * ft;
        let v = table.number(&table.rows[r], cv, "voltage")? * fv;
        if let Some(&(tp, _)) = pts.last() {
            if t <= tp {
                return Err(Error::input(
                    Location::at(path, table.rows[r].line, ct + 1),
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
