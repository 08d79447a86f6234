//! Material cards for finite-element codes (`dea-fit export`): the constants of a
//! hyperelastic fit, a relaxation fit or an identified material, written in the
//! convention of Abaqus, CalculiX, ANSYS Mechanical APDL, LS-DYNA, FEBio or COMSOL.
//! Each code is one module (CalculiX shares Abaqus's); this one reads the material
//! ([`read`]), puts the viscoelastic part in the one form every convention is
//! derived from ([`Relaxation`]), writes every number within the width the code
//! reads ([`Target::field`]), and assembles the card with its header: source files,
//! units, what was converted and how, and a warning wherever the card is not the
//! fit's model exactly.
//! Conventions, derivations and their sources: docs/export.md.

mod abaqus;
mod ansys;
mod comsol;
mod febio;
mod lsdyna;

use crate::dma::law::LawKind;
use crate::error::{Error, Location, Result};
use crate::material::file::{self, HyperelasticPart, MaterialFile};
use crate::material::hyperelastic::ogden::Ogden;
use crate::material::hyperelastic::{Mode, OgdenForm};
use crate::material::viscoelastic::{Formulation, TimeTemperature};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Schema tag of the `--json` output.
pub const SCHEMA: &str = "dea-fit/export/1";

/// Default bulk-to-shear modulus ratio K/μ0 (`--bulk-ratio`) of the cards of codes
/// without a fully incompressible rubber (LS-DYNA, FEBio, CalculiX): ν = 0.4995,
/// the volume change in uniaxial tension is ≈ σ/(3K), so the stress differs from
/// the incompressible fit's by O(σ/K) ≈ 0.1 % per unit of σ/μ0 (CalculiX, one
/// element at λ = 1.5, Neo-Hookean: 0.06 % uniaxial, 0.12 % equibiaxial, 0.09 %
/// planar, measured with ccx 2.20).
pub const BULK_RATIO: f64 = 1000.0;

/// Width of a floating-point field of an Abaqus data line: "a maximum of 20
/// spaces including the sign, decimal point, and any exponential notation"
/// (Abaqus Analysis User's Guide, "Input syntax rules"); CalculiX reads 20
/// characters a field and refuses a longer number (ccx 2.20 stops at
/// `-1.4184493597207666E3`, 21 characters).
pub const ABAQUS_WIDTH: usize = 20;

/// Width of a field of LS-DYNA's long format (`*KEYWORD LONG=Y`, Oasys PRIMER
/// manual, "Format"); the number takes at most one character less, so that a blank
/// separates it from the field before it.
pub const LSDYNA_WIDTH: usize = 20;

/// The relative rounding of [`within`] at `width` characters: the worst case keeps
/// width − 7 significant digits (a sign, one digit, the point and `E-ddd` take 8
/// characters), so |written − v| ≤ 5·10^−(width − 7)·|v|: 5·10⁻¹³ in 20 characters
/// (Abaqus, CalculiX), 5·10⁻¹² in 19 (LS-DYNA).
pub fn precision(width: usize) -> f64 {
    5.0 * 10f64.powi(7 - width as i32)
}

/// The stretches at which a finite-strain approximation is quantified (and the
/// read-back tests evaluate the cards).
pub const STRETCHES: [f64; 4] = [1.1, 1.5, 2.0, 3.0];

/// A finite-element code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Target {
    /// Abaqus (Standard; keyword input `.inp`).
    Abaqus,
    /// CalculiX (`ccx`, Abaqus keyword input `.inp`): a nearly incompressible card
    /// ready for its elements, no viscoelasticity.
    Calculix,
    /// ANSYS Mechanical APDL (commands `.mac`).
    Ansys,
    /// LS-DYNA (keyword input `.k`, long format).
    Lsdyna,
    /// FEBio (XML `<Material>` section).
    Febio,
    /// COMSOL Multiphysics (a parameter file for Global Definitions ▸ Parameters).
    Comsol,
}

impl Target {
    /// Every target, in the order of `--help`.
    pub const ALL: [Target; 6] = [
        Target::Abaqus,
        Target::Calculix,
        Target::Ansys,
        Target::Lsdyna,
        Target::Febio,
        Target::Comsol,
    ];

    /// The name `--to` takes.
    pub fn name(self) -> &'static str {
        match self {
            Target::Abaqus => "abaqus",
            Target::Calculix => "calculix",
            Target::Ansys => "ansys",
            Target::Lsdyna => "lsdyna",
            Target::Febio => "febio",
            Target::Comsol => "comsol",
        }
    }

    /// The code's name in messages.
    pub fn title(self) -> &'static str {
        match self {
            Target::Abaqus => "Abaqus",
            Target::Calculix => "CalculiX",
            Target::Ansys => "ANSYS Mechanical APDL",
            Target::Lsdyna => "LS-DYNA",
            Target::Febio => "FEBio",
            Target::Comsol => "COMSOL",
        }
    }

    /// File extension of the card.
    pub fn extension(self) -> &'static str {
        match self {
            Target::Abaqus | Target::Calculix => "inp",
            Target::Ansys => "mac",
            Target::Lsdyna => "k",
            Target::Febio => "feb",
            Target::Comsol => "txt",
        }
    }

    /// How the code's viscoelasticity acts on the hyperelastic stress; None for a
    /// code without viscoelastic hyperelasticity (CalculiX).
    fn family(self) -> Option<Family> {
        match self {
            Target::Abaqus | Target::Ansys | Target::Febio => Some(Family::RelaxesStress),
            Target::Lsdyna | Target::Comsol => Some(Family::StrainArms),
            Target::Calculix => None,
        }
    }

    /// A number as the code reads it, by the code's width rule: Abaqus and
    /// CalculiX at most [`ABAQUS_WIDTH`] characters ([`within`]); LS-DYNA
    /// right-aligned in a [`LSDYNA_WIDTH`]-character column, at most one character
    /// less; ANSYS (free-format fields "as wide as the number of characters
    /// specified", Command Reference §1.3.2), FEBio (XML text read as a double) and
    /// COMSOL (a parameter expression) read any width: the shortest decimal that
    /// reads back as the same f64 ([`num`], at most 24 characters).
    pub fn field(self, v: f64) -> String {
        match self {
            Target::Abaqus | Target::Calculix => within(v, ABAQUS_WIDTH),
            Target::Lsdyna => format!("{:>LSDYNA_WIDTH$}", within(v, LSDYNA_WIDTH - 1)),
            Target::Ansys | Target::Febio | Target::Comsol => num(v),
        }
    }
}

/// The two ways the codes add viscoelasticity to a hyperelastic solid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Family {
    /// A normalised relaxation function scales the (instantaneous) hyperelastic
    /// stress, as QLV does (Abaqus, ANSYS, FEBio).
    RelaxesStress,
    /// Maxwell branches linear in a strain measure, in parallel with the long-term
    /// hyperelastic spring, as the arms of El Atrache Ceballos (2021) are (LS-DYNA, COMSOL).
    StrainArms,
}

/// One input file of a card.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SourceFile {
    /// Path as given.
    pub path: String,
    /// `hyperelastic fit`, `relaxation fit`, `DMA fit` or `identified material`.
    pub kind: &'static str,
    /// The estimator's or the identification's status (`ok`, `warning`,
    /// `ill_posed`, …); None for an identified material written before its status
    /// was recorded (status unknown).
    pub status: Option<String>,
}

impl SourceFile {
    /// "path (kind, status s)", the status `unknown` where the file states none.
    pub fn describe(&self) -> String {
        format!(
            "{} ({}, status {})",
            self.path,
            self.kind,
            self.status.as_deref().unwrap_or("unknown")
        )
    }
}

/// The viscoelastic part, in the form every code's convention is derived from: the
/// relaxation function E(t) = E∞ + Σ Eᵢ·e^(−t/τᵢ) of the small-strain (Young's)
/// modulus and the reference modulus R the hyperelastic constants stand for.
///
/// * QLV relaxation fit: σ(t) = ∫ E(t − s)/R dσₑ(s), R = E_ref = 3μ0 of its
///   hyperelastic fit; the instantaneous response is (E0/R)·σₑ, the long-term one
///   (E∞/R)·σₑ.
/// * Parallel (the arms of El Atrache Ceballos (2021), a relaxation fit of the parallel reading or an
///   identified material): σ = σₑ(λ) + Σ kᵢ·hᵢ with arms linear in the strain,
///   R = E∞ = the equilibrium spring (3μ0 of the hyperelastic part when there is
///   one), and a Kelvin–Voigt dashpot Nv.
#[derive(Debug, Clone, PartialEq)]
pub struct Relaxation {
    /// The reading the constants belong to.
    pub formulation: Formulation,
    /// E∞ (Pa).
    pub long_term_pa: f64,
    /// Terms (τᵢ in s, Eᵢ in Pa).
    pub terms: Vec<(f64, f64)>,
    /// R (Pa).
    pub reference_pa: f64,
    /// Kelvin–Voigt dashpot Nv (Pa·s), 0 if none.
    pub nv_pa_s: f64,
    /// The hyperelastic model a QLV fit relaxes (for messages).
    pub qlv_model: Option<String>,
    /// The time–temperature shift of a DMA fit: the codes that have one write it
    /// after the Prony series ([`trs`]); None for the other fits.
    pub shift: Option<TimeTemperature>,
}

impl Relaxation {
    /// E0 = E∞ + ΣEᵢ (Pa).
    pub fn instantaneous_pa(&self) -> f64 {
        self.long_term_pa + self.terms.iter().map(|t| t.1).sum::<f64>()
    }
}

/// What a card is made from: at most one hyperelastic and one viscoelastic part,
/// from one or two material files.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name of the material in the card (from the first file's name).
    pub name: String,
    /// Hyperelastic part (long-term in the parallel reading, the QLV fit's
    /// reference in the QLV one), as fitted.
    pub hyperelastic: Option<HyperelasticPart>,
    /// Viscoelastic part.
    pub relaxation: Option<Relaxation>,
    /// The files.
    pub sources: Vec<SourceFile>,
    /// What combining them needs the user to know (a fit's blocking status).
    pub warnings: Vec<String>,
    /// How they were combined.
    pub notes: Vec<String>,
}

/// Read one or two material files (a hyperelastic fit, a relaxation fit, an
/// identified material) into the parts of one card; a part given twice, a QLV
/// relaxation fit paired with another hyperelastic fit than its own, and a
/// composite fit are refused with the file and what to do.
pub fn read(paths: &[PathBuf]) -> Result<Material> {
    if paths.is_empty() || paths.len() > 2 {
        return Err(Error::settings(format!(
            "export takes one or two material files, found {}",
            paths.len()
        ))
        .with_hint("dea-fit export FIT.json --to abaqus, or a hyperelastic and a relaxation fit: dea-fit export HYPER.json RELAX.json --to abaqus"));
    }
    let mut hyper: Option<(PathBuf, HyperelasticPart)> = None;
    let mut relax: Option<(PathBuf, file::RelaxationPart)> = None;
    let mut arms: Option<(PathBuf, file::Viscous)> = None;
    let mut sources = Vec::new();
    let mut warnings = Vec::new();
    for p in paths {
        let (part, status) = file::read_material(p)?;
        let kind = match &part {
            MaterialFile::Hyperelastic(_) => "hyperelastic fit",
            MaterialFile::Relaxation(r) if r.schema == file::DMA_SCHEMA => "DMA fit",
            MaterialFile::Relaxation(_) => "relaxation fit",
            MaterialFile::Identified(_) => "identified material",
        };
        // the status travels: a blocking status and the constants the file calls
        // not identifiable (of the parts a card takes)
        if let Some(d) = file::doubts(p, &["hyperelastic", "viscous"])? {
            warnings.push(d.sentence("the card carries them as they are"));
        }
        sources.push(SourceFile {
            path: p.display().to_string(),
            kind,
            status,
        });
        let twice = |what: &str, first: &Path| {
            Error::input(
                Location::file(p),
                format!("a second {what} part: {} already gives one", first.display()),
            )
            .with_hint("give one hyperelastic and at most one viscoelastic part (a hyperelastic and a relaxation fit, or one identified material)")
        };
        let (h, v) = match part {
            MaterialFile::Hyperelastic(h) => (Some(h), None),
            MaterialFile::Relaxation(r) => {
                if let Some(q) = relax.as_ref().map(|r| &r.0).or(arms.as_ref().map(|a| &a.0)) {
                    return Err(twice("viscoelastic", q));
                }
                relax = Some((p.clone(), r));
                (None, None)
            }
            MaterialFile::Identified(i) => (Some(i.hyperelastic), i.viscous),
        };
        if let Some(h) = h {
            if let Some((q, _)) = &hyper {
                return Err(twice("hyperelastic", q));
            }
            hyper = Some((p.clone(), h));
        }
        if let Some(v) = v {
            if let Some(q) = relax.as_ref().map(|r| &r.0).or(arms.as_ref().map(|a| &a.0)) {
                return Err(twice("viscoelastic", q));
            }
            arms = Some((p.clone(), v));
        }
    }
    let mut notes = Vec::new();
    let relaxation = match (&relax, &arms) {
        (Some((rp, r)), _) => {
            let terms: Vec<(f64, f64)> = r
                .arms
                .iter()
                .map(|a| (a.eta_pa_s / a.k_pa, a.k_pa))
                .collect();
            match (&r.qlv, &hyper) {
                // QLV: a hyperelastic fit given with it must be the one it relaxes.
                (Some(q), h) => {
                    if let Some((hp, h)) = h {
                        let e_ref = 3.0 * mu0(h)?;
                        let same = (e_ref - q.reference_modulus_pa).abs()
                            <= 1e-9 * e_ref.abs().max(q.reference_modulus_pa.abs());
                        if q.hyperelastic_model != h.spec.name || !same {
                            return Err(Error::input(
                                Location::file(rp),
                                format!(
                                    "qlv: this QLV fit relaxes a {} fit with 3mu0 = {} Pa; {} is a {} fit with 3mu0 = {e_ref} Pa",
                                    q.hyperelastic_model, q.reference_modulus_pa, hp.display(), h.spec.name
                                ),
                            )
                            .with_hint("give the hyperelastic fit the relaxation was fitted with (dea-fit relaxation --hyperelastic), or export the relaxation fit alone"));
                        }
                    }
                    Some(Relaxation {
                        formulation: Formulation::Qlv,
                        long_term_pa: r.long_term_pa,
                        terms,
                        reference_pa: q.reference_modulus_pa,
                        nv_pa_s: 0.0,
                        qlv_model: Some(q.hyperelastic_model.clone()),
                        shift: r.shift.clone(),
                    })
                }
                (None, Some((_, h))) => {
                    let k_inf = 3.0 * mu0(h)?;
                    notes.push(format!(
                        "the model of El Atrache Ceballos (2021): the hyperelastic spring (small-strain modulus 3mu0 = {} Pa) in parallel with the relaxation fit's arms; its E_inf = {} Pa (the secant modulus at the held strain) is not used, as in the simulator",
                        num(k_inf),
                        num(r.long_term_pa)
                    ));
                    Some(Relaxation {
                        formulation: Formulation::Parallel,
                        long_term_pa: k_inf,
                        terms,
                        reference_pa: k_inf,
                        nv_pa_s: 0.0,
                        qlv_model: None,
                        shift: r.shift.clone(),
                    })
                }
                (None, None) => Some(Relaxation {
                    formulation: Formulation::Parallel,
                    long_term_pa: r.long_term_pa,
                    terms,
                    reference_pa: r.long_term_pa,
                    nv_pa_s: 0.0,
                    qlv_model: None,
                    shift: r.shift.clone(),
                }),
            }
        }
        (None, Some((_, v))) => {
            let h = &hyper
                .as_ref()
                .expect("an identified material has a hyperelastic part")
                .1;
            let k_inf = 3.0 * mu0(h)?;
            Some(Relaxation {
                formulation: Formulation::Parallel,
                long_term_pa: k_inf,
                terms: v
                    .arms
                    .iter()
                    .map(|a| (a.eta_pa_s / a.k_pa, a.k_pa))
                    .collect(),
                reference_pa: k_inf,
                nv_pa_s: v.nv_pa_s,
                qlv_model: None,
                shift: None,
            })
        }
        (None, None) => None,
    };
    if let Some(r) = &relaxation {
        if !(r.reference_pa > 0.0 && r.long_term_pa > 0.0) {
            let src = relax
                .as_ref()
                .map(|r| r.0.clone())
                .unwrap_or_else(|| paths[0].clone());
            return Err(Error::input(
                Location::file(src),
                format!("the long-term modulus is {} Pa: a solid that relaxes to no stress has no hyperelastic reference, and the codes' Prony series need g_inf > 0", r.long_term_pa),
            )
            .with_hint("fit the relaxation again over a longer record, or with a hyperelastic fit (--hyperelastic)"));
        }
    }
    let name = sanitize(
        &paths[0]
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "material".into()),
    );
    Ok(Material {
        name,
        hyperelastic: hyper.map(|h| h.1),
        relaxation,
        sources,
        warnings,
        notes,
    })
}

/// A material name every code accepts: letters, digits, `_` and `-`, starting with
/// a letter, at most 64 characters.
fn sanitize(stem: &str) -> String {
    let mut s: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect();
    if !s.starts_with(|c: char| c.is_ascii_alphabetic()) {
        s.insert_str(0, "m_");
    }
    s
}

/// Settings of a card.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Mass density (kg/m³), written where the card has a place for it (LS-DYNA
    /// needs it).
    pub density: Option<f64>,
    /// Bulk-to-shear modulus ratio K/μ0 of the codes without a fully
    /// incompressible rubber (LS-DYNA, FEBio, CalculiX); default [`BULK_RATIO`].
    pub bulk_ratio: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            density: None,
            bulk_ratio: BULK_RATIO,
        }
    }
}

/// One constant as the card holds it, in the code's convention (SI).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Constant {
    /// The code's name of it (`C10`, `MU1`, `g1`, `BETA1`, …).
    pub name: String,
    /// Value (SI).
    pub value: f64,
    /// SI unit (`Pa`, `s`, `1/s`, `1`, `kg/m^3`).
    pub unit: &'static str,
}

/// A written card: what `--json` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Card {
    /// Schema tag.
    pub schema: &'static str,
    /// dea-fit version.
    pub tool_version: &'static str,
    /// The code.
    pub target: Target,
    /// Material name in the card.
    pub material: String,
    /// `exact` when the card is the fit's model (the read-back tests check it),
    /// `approximate` when a warning says where it is not, or the blocking status
    /// of a fit it was made from (`ill_posed`, `unstable`, `not_converged`,
    /// `not_validated`, `failed`): the card is only as good as its fit.
    pub status: &'static str,
    /// The input files.
    pub sources: Vec<SourceFile>,
    /// The constants in the card, in the code's convention.
    pub constants: Vec<Constant>,
    /// Where the card is not the fit's model, or the fit is not to be trusted.
    pub warnings: Vec<String>,
    /// How the constants were converted.
    pub notes: Vec<String>,
    /// The card.
    pub text: String,
}

impl Card {
    /// The exit status: 1 under `--strict` for any status but `exact` (README,
    /// "Exit status and statuses"), else 0.
    pub fn exit_code(&self, strict: bool) -> i32 {
        i32::from(strict && self.status != "exact")
    }
}

/// The card being written by a code's module.
#[derive(Debug, Default)]
struct Draft {
    /// The code, whose width rule [`Draft::field`] writes numbers by.
    target: Option<Target>,
    body: String,
    constants: Vec<Constant>,
    warnings: Vec<String>,
    notes: Vec<String>,
}

impl Draft {
    /// Append a line to the body.
    fn line(&mut self, s: impl AsRef<str>) {
        self.body.push_str(s.as_ref());
        self.body.push('\n');
    }
    /// Record a constant of the card; returns its value.
    fn constant(&mut self, name: impl Into<String>, value: f64, unit: &'static str) -> f64 {
        self.constants.push(Constant {
            name: name.into(),
            value,
            unit,
        });
        value
    }
    /// Record a constant of the card; returns it written by the code's width rule
    /// ([`Target::field`]).
    fn field(&mut self, name: impl Into<String>, value: f64, unit: &'static str) -> String {
        let v = self.constant(name, value, unit);
        self.target.expect("a card's code").field(v)
    }
    fn warn(&mut self, s: impl Into<String>) {
        self.warnings.push(s.into());
    }
    fn note(&mut self, s: impl Into<String>) {
        self.notes.push(s.into());
    }
}

/// Write the card of `m` for `target`. A model or a part the code cannot hold
/// (Gent in Abaqus or LS-DYNA, a viscoelastic block alone where the code has no
/// place for it, more Prony terms than the code takes) is refused with what to do.
pub fn card(m: &Material, target: Target, opts: &Options) -> Result<Card> {
    if let Some(rho) = opts.density {
        crate::sim::budget::DENSITY
            .check("--density", rho)
            .map_err(|v| Error::settings(v.msg).with_hint(v.hint))?;
    }
    if !(opts.bulk_ratio.is_finite() && opts.bulk_ratio >= 1.0) {
        return Err(Error::settings(format!(
            "--bulk-ratio {}: expected a bulk-to-shear modulus ratio K/mu0 >= 1 (nearly incompressible rubber: 1000 or more)",
            opts.bulk_ratio
        ))
        .with_hint(format!("leave it out for K/mu0 = {BULK_RATIO}")));
    }
    let mut d = Draft {
        target: Some(target),
        ..Draft::default()
    };
    match target {
        Target::Abaqus | Target::Calculix => abaqus::write(m, target, opts, &mut d)?,
        Target::Ansys => ansys::write(m, opts, &mut d)?,
        Target::Lsdyna => lsdyna::write(m, opts, &mut d)?,
        Target::Febio => febio::write(m, opts, &mut d)?,
        Target::Comsol => comsol::write(m, opts, &mut d)?,
    }
    viscous_statements(m, target, &mut d);
    let exact = d.warnings.is_empty();
    // the card is only as good as its fit: a fit's blocking status is the card's
    let blocking = m.sources.iter().find_map(|s| {
        s.status
            .as_deref()
            .filter(|s| !matches!(*s, "ok" | "warning"))
    });
    let status: &'static str = match blocking {
        Some("ill_posed") => "ill_posed",
        Some("unstable") => "unstable",
        Some("not_converged") => "not_converged",
        Some("not_validated") => "not_validated",
        Some(_) => "failed",
        None if exact => "exact",
        None => "approximate",
    };
    let mut warnings = m.warnings.clone();
    warnings.append(&mut d.warnings);
    let mut notes = m.notes.clone();
    notes.append(&mut d.notes);
    let mut header = vec![
        format!(
            "{} material card written by dea-fit {} (dea-fit export --to {})",
            target.title(),
            env!("CARGO_PKG_VERSION"),
            target.name()
        ),
        format!("material: {}", m.name),
    ];
    for s in &m.sources {
        header.push(format!("source: {}", s.describe()));
    }
    header.push("units: SI (Pa, s, kg/m^3); stresses nominal in the fit, the card's own measure in the code".into());
    header.push(format!(
        "status: {status}; conversion {}",
        if exact {
            "exact (the card is the fit's model; docs/export.md)"
        } else {
            "approximate (see the warnings)"
        }
    ));
    header.extend(warnings.iter().map(|w| format!("warning: {w}")));
    header.extend(notes.iter().map(|n| format!("note: {n}")));
    let text = match target {
        Target::Febio => febio::document(&header, &d.body),
        _ => {
            let prefix = match target {
                Target::Abaqus | Target::Calculix => "** ",
                Target::Ansys => "! ",
                Target::Lsdyna => "$ ",
                _ => "# ",
            };
            let mut t = String::new();
            for h in &header {
                for l in wrap(h, 100) {
                    t.push_str(prefix);
                    t.push_str(&l);
                    t.push('\n');
                }
            }
            match target {
                Target::Lsdyna => format!("*KEYWORD LONG=Y\n{t}{}*END\n", d.body),
                _ => t + &d.body,
            }
        }
    };
    Ok(Card {
        schema: SCHEMA,
        tool_version: env!("CARGO_PKG_VERSION"),
        target,
        material: m.name.clone(),
        status,
        sources: m.sources.clone(),
        constants: d.constants,
        warnings,
        notes,
        text,
    })
}

/// Lines of at most `width` characters, broken at spaces (a longer word stays whole).
fn wrap(s: &str, width: usize) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    for w in s.split(' ') {
        if !cur.is_empty() && cur.len() + 1 + w.len() > width {
            out.push(std::mem::take(&mut cur));
            cur.push_str("  ");
        } else if !cur.is_empty() {
            cur.push(' ');
        }
        cur.push_str(w);
    }
    out.push(cur);
    out
}

/// What the viscoelastic block of a `target` card is, against the fit's
/// formulation: exact, or approximate with where and by how much (docs/export.md,
/// "Viscoelasticity").
fn viscous_statements(m: &Material, target: Target, d: &mut Draft) {
    let Some(r) = &m.relaxation else { return };
    let code = target.title();
    let Some(family) = target.family() else {
        return;
    };
    match (family, r.formulation) {
        (Family::RelaxesStress, Formulation::Qlv) => d.note(format!(
            "the fit is quasi-linear viscoelastic (QLV) and {code} relaxes the hyperelastic stress the same way: exact for a held stretch (the relaxation test); for a stretch that varies while it relaxes, {code} convolves its own stress measure where the fit convolves the nominal stress"
        )),
        (Family::RelaxesStress, Formulation::Parallel) => {
            let by = m
                .hyperelastic
                .as_ref()
                .and_then(|h| stress_proportional_ratios(h, r))
                .map(|rs| {
                    let list: Vec<String> = rs.iter().map(|x| format!("{x:.3}")).collect();
                    let at: Vec<String> = STRETCHES.iter().map(|l| format!("{l}")).collect();
                    format!(
                        "; at stretch {} the card's viscous stress is {} times that of the arms of El Atrache Ceballos (2021)",
                        at.join("/"),
                        list.join("/")
                    )
                })
                .unwrap_or_default();
            d.warn(format!(
                "approximate at finite strain: the arms of El Atrache Ceballos (2021) are linear in the strain, k_i*(lambda - 1), while {code} relaxes the hyperelastic stress (k_i*P_h(lambda)/E_inf); the small-strain relaxation modulus E(t) is the fit's exactly{by}"
            ))
        }
        (Family::StrainArms, Formulation::Parallel) => d.warn(format!(
            "approximate at finite strain: {code}'s Maxwell branches are linear in its own (Green-Lagrange type) strain, the arms of El Atrache Ceballos (2021) in the engineering strain lambda - 1; the small-strain relaxation modulus E(t) is the fit's exactly"
        )),
        (Family::StrainArms, Formulation::Qlv) => d.warn(format!(
            "approximate at finite strain: the fit is QLV (its relaxation scales the hyperelastic stress) while {code} adds strain-linear Maxwell branches to the long-term hyperelastic stress; the small-strain relaxation modulus E(t) is the fit's exactly"
        )),
    }
    if r.nv_pa_s > 0.0 {
        d.warn(format!(
            "the Kelvin-Voigt dashpot Nv = {} Pa s has no Prony term in {code}: it is left out, so the card under-damps fast loading",
            num(r.nv_pa_s)
        ));
    }
}

/// For a parallel-reading material written as a stress-relaxing card: the card's
/// viscous overstress over that of those arms, P_h(λ)/(E∞·(λ − 1)), at [`STRETCHES`] in
/// uniaxial tension (→ 1 as λ → 1). None if the model has no finite stress there.
fn stress_proportional_ratios(h: &HyperelasticPart, r: &Relaxation) -> Option<Vec<f64>> {
    let model = h.evaluator().ok()?;
    let v: Vec<f64> = STRETCHES
        .iter()
        .map(|&l| model.nominal_stress(&h.params, Mode::Uniaxial, l) / (r.long_term_pa * (l - 1.0)))
        .collect();
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// The hyperelastic part with every stress coefficient (unit Pa) multiplied by
/// `scale`: the same model, its stress scaled (the instantaneous or long-term
/// response of a QLV or parallel material).
fn scaled(h: &HyperelasticPart, scale: f64) -> Result<HyperelasticPart> {
    let model = h.evaluator()?;
    let params = model
        .params()
        .iter()
        .zip(&h.params)
        .map(|(p, &v)| if p.unit == "Pa" { v * scale } else { v })
        .collect();
    Ok(HyperelasticPart {
        spec: h.spec.clone(),
        params,
        ranges: None,
    })
}

/// μ0 (Pa) of a hyperelastic part.
fn mu0(h: &HyperelasticPart) -> Result<f64> {
    Ok(h.evaluator()?.initial_shear_modulus(&h.params))
}

/// The Ogden terms (μᵢ, αᵢ) of `h` in `form`: abaqus (2μ/α², Abaqus, FEBio as c = 2μ)
/// or original (μ/α: ANSYS, LS-DYNA, COMSOL), converted exactly (`Ogden::convert`).
fn ogden_terms(h: &HyperelasticPart, form: OgdenForm) -> Vec<(f64, f64)> {
    Ogden::convert(&h.params, h.spec.form.unwrap_or_default(), form)
        .chunks_exact(2)
        .map(|t| (t[0], t[1]))
        .collect()
}

/// The number of Ogden terms of a model name (`ogden3` → 3).
fn ogden_n(name: &str) -> Option<usize> {
    name.strip_prefix("ogden").and_then(|n| n.parse().ok())
}

/// A model the code does not have: refused with the codes that do.
fn no_model(target: Target, model: &str, have: &str) -> Error {
    Error::settings(format!(
        "{} has no {model} strain energy: a {model} fit cannot be written as a {} card without changing the model",
        target.title(),
        target.title()
    ))
    .with_hint(format!(
        "export it to {have}, or fit a model {} has for it (dea-fit hyperelastic --model neo-hookean|mooney-rivlin|yeoh|ogden1..ogden4)",
        target.title()
    ))
}

/// A viscoelastic block the code has no place for without its hyperelastic part.
fn needs_hyperelastic(target: Target) -> Error {
    Error::settings(format!(
        "a {} card holds the viscoelastic constants inside the hyperelastic material: a relaxation fit alone cannot be written",
        target.title()
    ))
    .with_hint("give the hyperelastic fit too: dea-fit export HYPER.json RELAX.json --to ... (for a QLV fit, the one it was fitted with)")
}

/// More Prony terms than the code's material takes.
fn too_many_terms(target: Target, n: usize, max: usize) -> Error {
    Error::settings(format!(
        "{} takes at most {max} viscoelastic terms, the fit has {n}",
        target.title()
    ))
    .with_hint(format!(
        "fit the relaxation with --terms {max} or fewer (or --max-terms {max})"
    ))
}

/// A number in any width (ANSYS, FEBio, COMSOL, and the cards' comments): the
/// shortest decimal that reads back as the same f64 (`{:E}`, at most 24
/// characters), so that the card holds the fit's value exactly.
pub fn num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:E}")
    }
}

/// A number in at most `width` characters (`width` ≥ 10): the shortest round-trip
/// form ([`num`]) when it fits, else the most significant digits that fit, rounded
/// to within [`precision`]`(width)` relative.
pub fn within(v: f64, width: usize) -> String {
    let s = num(v);
    if s.len() <= width {
        return s;
    }
    (0..=16)
        .rev()
        .map(|p| format!("{v:.p$E}"))
        .find(|s| s.len() <= width)
        .expect("a 1-digit mantissa fits in 10 characters")
}

/// A number as a plain decimal without an exponent (`{}`, the shortest that reads
/// back as the same f64): FEBio's expression parser (the energy of `uncoupled
/// hyperelastic`) takes no exponent.
fn plain(v: f64) -> String {
    format!("{v}")
}

/// What a relaxation-only card needs the user to add, for the codes that can hold
/// the viscoelastic block alone: the elastic constants it must be combined with.
fn alone_warning(r: &Relaxation, long_term: bool) -> String {
    let what = match (r.formulation, long_term) {
        (Formulation::Qlv, false) => format!(
            "the instantaneous hyperelastic constants: G(0) = {} times those of the {} fit the QLV relaxation was fitted with",
            num(r.instantaneous_pa() / r.reference_pa),
            r.qlv_model.as_deref().unwrap_or("hyperelastic")
        ),
        (Formulation::Qlv, true) => format!(
            "the long-term hyperelastic constants: g_inf = {} times those of the {} fit the QLV relaxation was fitted with",
            num(r.long_term_pa / r.reference_pa),
            r.qlv_model.as_deref().unwrap_or("hyperelastic")
        ),
        (Formulation::Parallel, false) => format!(
            "an instantaneous elastic definition with small-strain Young's modulus E0 = {} Pa",
            num(r.instantaneous_pa())
        ),
        (Formulation::Parallel, true) => format!(
            "a long-term elastic definition with small-strain Young's modulus E_inf = {} Pa",
            num(r.long_term_pa)
        ),
    };
    format!("no hyperelastic part: this card holds the viscoelastic block only; combine it with {what} (dea-fit export HYPER.json RELAX.json writes both consistently)")
}

/// How a code holds the time–temperature shift of a DMA fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Trs {
    /// The code takes this law (WLF or Arrhenius): the card writes it.
    Law(crate::dma::law::Law),
    /// The fit's shifts are free (tabulated in the fit file): no card; a warning.
    Free,
}

/// The shift law of `r` a card is to write (None without one, or where the code has
/// none), with the notes and warnings every code shares: the temperature unit of the
/// card (K), and for free shifts that no shift is written. `has` says whether the
/// code has a card for the law's kind; where it has none the card is the material
/// at Tr, said as a warning naming the code.
fn trs(r: &Relaxation, code: &str, has: impl Fn(LawKind) -> bool, d: &mut Draft) -> Option<Trs> {
    let s = r.shift.as_ref()?;
    let tr = s.reference_k;
    match s.law {
        Some(law) if has(law.kind) => {
            d.note(format!(
                "time-temperature shift: the DMA fit's {} law at Tr = {} K, written for {code}; temperatures in the card are in K (the model's temperatures must be in K too; for a model in degC subtract 273.15 from Tr, C1 and C2 are unchanged)",
                law.kind.label(),
                num(tr)
            ));
            Some(Trs::Law(law))
        }
        Some(law) => {
            d.warn(format!(
                "{code} has no {} time-temperature shift for this material: the card is the material at the DMA fit's reference temperature {} K only",
                law.kind.label(),
                num(tr)
            ));
            None
        }
        None => {
            d.warn(format!(
                "the DMA fit's shifts are free (no law): they are tabulated in the fit file's shift_factors, and no time-temperature shift is written for {code} (a user-subroutine shift is not portable); the card is the material at Tr = {} K (fit a law with dea-fit dma --shift wlf|arrhenius to get one)",
                num(tr)
            ));
            Some(Trs::Free)
        }
    }
}
