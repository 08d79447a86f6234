//! Plausibility checks of material constants, shared by the readers of scenes and
//! material files and by the simulator's own guards (`sim::budget`): a plausible
//! range per quantity with its reason ([`Domain`]), the check of a hyperelastic
//! model's parameters, and the near-miss suggestion of the readers' hints.

use crate::material::hyperelastic::StrainEnergy;

/// A plausible range of a physical quantity (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    /// What the quantity is (for messages).
    pub what: &'static str,
    /// SI unit.
    pub unit: &'static str,
    /// Smallest plausible value.
    pub min: f64,
    /// Largest plausible value.
    pub max: f64,
    /// Whether exactly 0 is allowed too (an absent part: no electrode, no load).
    pub zero: bool,
    /// Why these bounds.
    pub reason: &'static str,
}

pub(crate) const fn d(
    what: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    zero: bool,
    reason: &'static str,
) -> Domain {
    Domain {
        what,
        unit,
        min,
        max,
        zero,
        reason,
    }
}

/// Plausible breakdown fields: elastomers break down at 10–300 V/µm.
pub const BREAKDOWN: Domain = d(
    "breakdown field",
    "V/m",
    1e5,
    2e9,
    false,
    "elastomers break down at 10–300 V/µm (1e7–3e8 V/m); write it with a unit, e.g. \"80 V/um\"",
);
/// Relative permittivity εr.
pub const PERMITTIVITY: Domain = d(
    "relative permittivity",
    "",
    1.0,
    1e5,
    false,
    "vacuum has εr = 1, elastomers 2–10, ceramic-filled composites up to ≈ 1e4",
);
/// Filler mass fraction w of a composite (εr from a mixing rule), in [0, 1).
pub const MASS_FRACTION: Domain = d(
    "filler mass fraction",
    "",
    0.0,
    0.999,
    true,
    "0 is the pure matrix; a mass fraction is below 1, and beyond 99.9 % filler the composite is a powder, not an elastomer",
);
/// Hyperelastic stress coefficients (C10, μi, …; may be negative).
pub const MODULUS: Domain = d(
    "stress coefficient",
    "Pa",
    -1e10,
    1e10,
    true,
    "elastomers have moduli of 1 kPa–100 MPa; 10 GPa is a metal",
);
/// Small-strain shear modulus μ0 of the hyperelastic model.
pub const SHEAR_MODULUS: Domain = d(
    "initial shear modulus",
    "Pa",
    1.0,
    1e10,
    false,
    "a solid resists shear (μ0 > 0); gels have ≈ 100 Pa, elastomers 10 kPa–10 MPa",
);
/// |αi| of an Ogden term.
pub const OGDEN_EXPONENT: Domain = d(
    "Ogden exponent magnitude",
    "",
    1e-2,
    20.0,
    false,
    "a term with α ≈ 0 stores no energy; the fitter bounds the magnitude of α by 20",
);
/// Kelvin-Voigt dashpot Nv.
pub const DASHPOT: Domain = d(
    "dashpot viscosity",
    "Pa·s",
    1e-9,
    1e12,
    true,
    "0 for none; Table 4.2: 1875 Pa·s",
);
/// Maxwell arm modulus kj.
pub const ARM_MODULUS: Domain = d(
    "arm modulus",
    "Pa",
    1e-3,
    1e10,
    false,
    "relaxation moduli of elastomers are 1 kPa–100 MPa",
);
/// Maxwell arm relaxation time τj = ηj/kj.
pub const ARM_TIME: Domain = d(
    "relaxation time",
    "s",
    1e-9,
    1e12,
    false,
    "1 ns to 30 000 years",
);

/// A value outside its domain: the scene key, what is wrong, what to do.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    /// Key path in the scene format (`material.relative_permittivity`, `input[0].cycles`).
    pub key: String,
    /// What was found and why it is refused.
    pub msg: String,
    /// What to do.
    pub hint: String,
}

impl Domain {
    /// Accept `v` if finite and inside the range (or 0 where allowed).
    pub fn check(&self, key: &str, v: f64) -> std::result::Result<f64, Violation> {
        let ok = v.is_finite() && ((self.zero && v == 0.0) || (v >= self.min && v <= self.max));
        if ok {
            return Ok(v);
        }
        let u = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        let range = format!(
            "{}{}{u} … {}{u}",
            if self.zero && self.min > 0.0 {
                "0 or "
            } else {
                ""
            },
            fmt_g(self.min),
            fmt_g(self.max)
        );
        Err(Violation {
            key: key.to_string(),
            msg: match v.is_finite() {
                true => format!(
                    "{} = {}{u} is not a plausible {}: expected {range}",
                    key_leaf(key),
                    fmt_g(v),
                    self.what
                ),
                false => format!("{} must be a finite number, found {v}", key_leaf(key)),
            },
            hint: match self.unit.is_empty() {
                true => self.reason.to_string(),
                false => format!("{}; is the unit right?", self.reason),
            },
        })
    }
}

fn key_leaf(key: &str) -> &str {
    key.rsplit('.').next().unwrap_or(key)
}

/// A number in short form, 4 significant digits at most (1e-7, 0.5, 2.25e6, 8.44e8).
pub fn fmt_g(v: f64) -> String {
    if v != 0.0 && v.is_finite() && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = match m.contains('.') {
            true => m.trim_end_matches('0').trim_end_matches('.'),
            false => m,
        };
        format!("{m}e{e}")
    } else {
        format!("{v}")
    }
}

/// Check the parameters of a hyperelastic model: the count, each value finite and
/// plausible (Pa coefficients by [`MODULUS`], dimensionless ones within the model's
/// own bounds (Gent Jm ∈ [1e-3, 1e6]), Ogden exponents by [`OGDEN_EXPONENT`]), and
/// a positive initial shear modulus. `key` prefixes the parameter names.
pub fn check_hyperelastic(
    model: &dyn StrainEnergy,
    params: &[f64],
    key: &str,
) -> std::result::Result<(), Violation> {
    let info = model.params();
    if params.len() != info.len() {
        return Err(Violation {
            key: key.to_string(),
            msg: format!(
                "{} needs {} parameters ({}), found {}",
                model.name(),
                info.len(),
                info.iter()
                    .map(|p| p.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                params.len()
            ),
            hint: "give every parameter of the model by name".into(),
        });
    }
    for (p, &v) in info.iter().zip(params) {
        let k = format!("{key}.{}", p.name);
        if p.unit == "Pa" {
            MODULUS.check(&k, v)?;
        } else if p.name.starts_with("alpha") {
            OGDEN_EXPONENT.check(&k, v.abs()).map_err(|mut e| {
                e.msg = format!("{}: {} = {v}: |α| {}", model.name(), p.name, e.msg);
                e
            })?;
        } else {
            let dom = Domain {
                what: "dimensionless parameter",
                unit: "",
                min: p.lower,
                max: p.upper,
                zero: false,
                reason: "the model's own bounds (the fitter's search range)",
            };
            dom.check(&k, v)?;
        }
    }
    SHEAR_MODULUS
        .check(
            &format!("{key}.initial_shear_modulus"),
            model.initial_shear_modulus(params),
        )
        .map(|_| ())
}

/// The hint for serde's refusal of a name it does not know ("unknown field `voltag`,
/// expected one of `voltage`, `frequency`", "unknown variant …", "expected `a` or
/// `b`"): the near miss among the names it expected ([`did_you_mean`]) and the
/// list, "did you mean 'voltage'? known: voltage, frequency". None for any other
/// message.
pub fn unknown_name_hint(message: &str) -> Option<String> {
    let rest = ["unknown field `", "unknown variant `"]
        .iter()
        .find_map(|p| message.find(p).map(|i| &message[i + p.len()..]))?;
    let (found, rest) = rest.split_once('`')?;
    let known: Vec<&str> = rest.split('`').skip(1).step_by(2).collect();
    if known.is_empty() {
        return None;
    }
    let list = known.join(", ");
    Some(match did_you_mean(found, &known) {
        Some(m) => format!("did you mean '{m}'? known: {list}"),
        None => format!("known: {list}"),
    })
}

/// The known name closest to `word` if it is a near miss (edit distance ≤ 2, and
/// less than half the word): `presett` → `preset`.
pub fn did_you_mean<'k>(word: &str, known: &[&'k str]) -> Option<&'k str> {
    let lev = |a: &str, b: &str| {
        let b: Vec<char> = b.chars().collect();
        let mut row: Vec<usize> = (0..=b.len()).collect();
        for (i, ca) in a.chars().enumerate() {
            let mut prev = row[0];
            row[0] = i + 1;
            for j in 0..b.len() {
                let cur = row[j + 1];
                row[j + 1] = (prev + usize::from(ca != b[j]))
                    .min(row[j] + 1)
                    .min(cur + 1);
                prev = cur;
            }
        }
        row[b.len()]
    };
    let w = word.to_lowercase();
    known
        .iter()
        .map(|k| (lev(&w, &k.to_lowercase()), *k))
        .filter(|&(d, _)| d <= 2 && 2 * d < w.chars().count().max(1))
        .min_by_key(|&(d, _)| d)
        .map(|(_, k)| k)
}
