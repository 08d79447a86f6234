//! Permittivity of a coupon from an LCR sweep: εr (ε′), ε″, tan δ and the AC
//! conductivity per frequency, with the uncertainty of εr propagated from the
//! geometry (and stray capacitance) tolerances; optional stray subtraction and
//! Kirchhoff edge correction; sanity checks. Files of a batch run in parallel.

use super::Status;
use crate::error::{Error, Location, Result};
use crate::io::lcr::{self, Format, LcrOptions, Sweep};
use crate::material::check::{Domain, PERMITTIVITY};
use crate::material::dielectric::{
    ac_conductivity, complex_permittivity, kirchhoff_edge_capacitance, Pair, EPS0,
};
use crate::sim::budget::LENGTH;
use crate::units::Quantity;
use nalgebra::Complex;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Schema tag of one sample's result.
pub const SCHEMA: &str = "dea-fit/permittivity/1";
/// Schema tag of a batch result (what `dea-fit permittivity --json` prints).
pub const RUN_SCHEMA: &str = "dea-fit/permittivity-run/1";

/// Coupon geometry in SI with standard uncertainties (checked by [`Geometry::new`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// Electrode (plate) area A (m²).
    #[serde(rename = "area_m2")]
    pub area: f64,
    /// Standard uncertainty of A (m²); None (null) when no tolerance was stated:
    /// unknown, never 0.
    #[serde(rename = "area_std_m2")]
    pub area_std: Option<f64>,
    /// Coupon thickness d (m).
    #[serde(rename = "thickness_m")]
    pub thickness: f64,
    /// Standard uncertainty of d (m).
    #[serde(rename = "thickness_std_m")]
    pub thickness_std: Option<f64>,
}

impl Geometry {
    /// Geometry from an area or a plate diameter (exactly one) and a thickness; a
    /// diameter D ± σD gives A = πD²/4 ± πD·σD/2. Tolerances are read as one
    /// standard uncertainty.
    pub fn new(
        area: Option<Quantity>,
        diameter: Option<Quantity>,
        thickness: Option<Quantity>,
    ) -> Result<Geometry> {
        // A coupon's lengths in the scenes' plausible range (1e-7 m … 10 m), its
        // area in that range squared: 1e308 mm is no diameter, and would make C0
        // and every value written from it +∞.
        let plausible = |key: &str, v: f64, dom: &Domain| {
            dom.check(key, v)
                .map_err(|v| Error::settings(v.msg).with_hint(v.hint))
        };
        let area_dom = Domain {
            what: "plate area",
            unit: "m²",
            min: LENGTH.min * LENGTH.min,
            max: LENGTH.max * LENGTH.max,
            ..LENGTH
        };
        for (key, q, dom) in [
            ("area", area, &area_dom),
            ("diameter", diameter, &LENGTH),
            ("thickness", thickness, &LENGTH),
        ] {
            if let Some(q) = q {
                plausible(key, q.value, dom)?;
            }
        }
        let (area, area_std) = match (area, diameter) {
            (Some(a), None) => (a.value, a.tolerance),
            (None, Some(d)) => (
                PI * d.value * d.value / 4.0,
                d.tolerance.map(|t| PI * d.value * t / 2.0),
            ),
            (Some(_), Some(_)) => {
                return Err(Error::settings("both an area and a diameter were given")
                    .with_hint("give one: --area 1.439e-3 or --diameter 42.8mm"))
            }
            (None, None) => {
                return Err(Error::settings("the plate area is not given").with_hint(
                    "pass --area (m² or e.g. 14.39cm2) or --diameter (e.g. 42.8mm), or a sidecar <file>.geometry.toml",
                ))
            }
        };
        let thickness = thickness.ok_or_else(|| {
            Error::settings("the coupon thickness is not given")
                .with_hint("pass --thickness, e.g. --thickness 2.2mm±0.05mm")
        })?;
        let g = Geometry {
            area,
            area_std,
            thickness: thickness.value,
            thickness_std: thickness.tolerance,
        };
        if !(g.area > 0.0 && g.thickness > 0.0) {
            return Err(Error::settings(format!(
                "area and thickness must be > 0, found A = {} m², d = {} m",
                g.area, g.thickness
            )));
        }
        if g.thickness > g.area.sqrt() {
            return Err(Error::settings(format!(
                "the coupon is thicker ({} m) than its plates are wide (√A = {:.4} m): not a parallel-plate coupon",
                g.thickness,
                g.area.sqrt()
            ))
            .with_hint("check the units: a bare number is SI (m, m²); write 2.2mm or 14.39cm2"));
        }
        Ok(g)
    }

    /// Radius of a circular plate of the same area (m).
    pub fn radius(&self) -> f64 {
        (self.area / PI).sqrt()
    }

    /// Empty-gap (vacuum) capacitance C0 = ε0·A/d (F).
    pub fn empty_capacitance(&self) -> f64 {
        EPS0 * self.area / self.thickness
    }

    /// Kirchhoff's edge capacitance of these plates (F).
    pub fn edge_capacitance(&self) -> f64 {
        kirchhoff_edge_capacitance(self.radius(), self.thickness)
    }
}

/// The fringe-field (edge) correction for unguarded plates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EdgeCorrection {
    /// No correction (guarded electrodes, or the user accepts the bias).
    #[default]
    None,
    /// The fringe field runs in air (coupon cut flush with the plates):
    /// εr = (C − Ce)/C0, Ce Kirchhoff's edge term.
    Air,
    /// The fringe field runs in the coupon (coupon larger than the plates):
    /// εr = C/(C0 + Ce).
    Filled,
}

/// How a sweep becomes permittivity (checked by [`Settings::check`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Open-fixture (stray) capacitance subtracted from Cp (F); default none.
    #[serde(rename = "stray_F")]
    pub stray: Option<f64>,
    /// Standard uncertainty of the stray capacitance (F); None (null) when none
    /// was stated: unknown, never 0.
    #[serde(rename = "stray_std_F")]
    pub stray_std: Option<f64>,
    /// Edge correction; default none.
    pub edge: EdgeCorrection,
}

impl Settings {
    /// Reject settings that cannot work.
    pub fn check(&self) -> Result<()> {
        let s = self.stray.unwrap_or(0.0);
        let sd = self.stray_std.unwrap_or(0.0);
        if !(s >= 0.0 && s.is_finite() && sd >= 0.0) {
            return Err(Error::settings(format!(
                "the stray capacitance must be ≥ 0 F, found {s} ± {sd} F"
            )));
        }
        Ok(())
    }
}

/// One frequency of one sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PermittivityPoint {
    /// Frequency (Hz).
    #[serde(rename = "freq_Hz")]
    pub freq_hz: f64,
    /// Relative permittivity ε′ (after the corrections in use).
    pub eps_r: f64,
    /// Standard uncertainty of ε′ from the geometry and stray tolerances stated;
    /// None (null) when none was stated: unknown, never 0.
    pub eps_r_std: Option<f64>,
    /// Loss factor ε″.
    pub eps_loss: f64,
    /// Loss tangent tan δ = ε″/ε′.
    pub tan_delta: f64,
    /// AC conductivity σ = ω·ε0·ε″ (S/m).
    #[serde(rename = "conductivity_S_per_m")]
    pub conductivity: f64,
    /// Measured parallel capacitance Cp (F), before corrections.
    #[serde(rename = "cp_F")]
    pub cp: f64,
    /// Line of the export.
    pub line: usize,
}

/// The corrections and how large they are.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Corrections {
    /// Stray capacitance subtracted (F), if any.
    #[serde(rename = "stray_F")]
    pub stray: Option<f64>,
    /// Edge correction in use.
    pub edge: EdgeCorrection,
    /// Kirchhoff's edge capacitance of the plates (F), reported even when not applied.
    #[serde(rename = "edge_capacitance_F")]
    pub edge_capacitance: f64,
    /// Edge capacitance over the empty-gap capacitance ε0·A/d.
    pub edge_relative_to_empty_gap: f64,
    /// Empty-gap capacitance ε0·A/d (F).
    #[serde(rename = "empty_capacitance_F")]
    pub empty_capacitance: f64,
}

/// Where one sample came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SampleSource {
    /// Path as given.
    pub path: String,
    /// SHA-256 of the file (hex).
    pub sha256: String,
    /// Export family.
    pub format: Format,
    /// Measured pair.
    pub pair: Pair,
    /// Instrument line, when the file names one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instrument: Option<String>,
    /// Columns used.
    pub columns: Vec<String>,
    /// Where the geometry came from (`flags`, a sidecar or a manifest).
    pub geometry_from: String,
    /// Settings used.
    pub settings: Settings,
}

/// Permittivity of one sample over frequency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SamplePermittivity {
    /// Schema tag.
    pub schema: String,
    /// dea-fit version that wrote it.
    pub tool_version: String,
    /// Sample name.
    pub name: String,
    /// Points in increasing frequency.
    pub points: Vec<PermittivityPoint>,
    /// Geometry used.
    pub geometry: Geometry,
    /// Corrections used and their size.
    pub corrections: Corrections,
    /// Overall status.
    pub status: Status,
    /// What the user should know.
    pub warnings: Vec<String>,
    /// What the reader and the corrections did.
    pub notes: Vec<String>,
    /// Input and settings.
    pub provenance: SampleSource,
}

/// A file of a batch that could not be used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Failure {
    /// The file.
    pub file: String,
    /// The error, as printed.
    pub error: String,
}

/// A batch of samples: what `dea-fit permittivity --json` prints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PermittivityRun {
    /// Schema tag.
    pub schema: String,
    /// dea-fit version.
    pub tool_version: String,
    /// Samples in input order.
    pub samples: Vec<SamplePermittivity>,
    /// Files that could not be used.
    pub failed: Vec<Failure>,
    /// Batch-level warnings (each sample's own are prefixed with its name).
    pub warnings: Vec<String>,
    /// Worst status over the samples.
    pub status: Status,
}

/// One file of a batch with its geometry.
#[derive(Debug, Clone)]
pub struct Input {
    /// The export.
    pub path: PathBuf,
    /// Sample name (default: the file stem).
    pub name: String,
    /// Geometry, or the error that prevented it.
    pub geometry: std::result::Result<Geometry, String>,
    /// Where the geometry came from.
    pub geometry_from: String,
}

/// A status that outranks the other (Ok < Warning < the blocking ones < Failed).
pub fn worst(a: Status, b: Status) -> Status {
    let rank = |s: Status| match s {
        Status::Ok => 0,
        Status::Warning => 1,
        Status::Failed => 3,
        _ => 2,
    };
    if rank(b) > rank(a) {
        b
    } else {
        a
    }
}

fn freq_range(f: &[f64]) -> String {
    match (f.first(), f.last()) {
        (Some(a), Some(b)) if a != b => format!("{a} Hz – {b} Hz"),
        (Some(a), _) => format!("{a} Hz"),
        _ => String::new(),
    }
}

/// ε′ and ε″ at one point: the stray (and, fringe in air, the edge) capacitance is
/// removed from the admittance, then ε* = Y/(jω·C_ref) with C_ref = C0 (or C0 + Ce
/// with the fringe in the coupon).
fn eps_at(
    y: Complex<f64>,
    omega: f64,
    geom: &Geometry,
    stray: f64,
    edge: EdgeCorrection,
) -> (f64, f64) {
    let c0 = geom.empty_capacitance();
    let ce = geom.edge_capacitance();
    let (removed, c_ref) = match edge {
        EdgeCorrection::None => (stray, c0),
        EdgeCorrection::Air => (stray + ce, c0),
        EdgeCorrection::Filled => (stray, c0 + ce),
    };
    complex_permittivity(y - Complex::new(0.0, omega * removed), omega, c_ref)
}

/// Permittivity of one sweep. `Err` when the sweep is not a capacitor at all
/// (inductive or non-positive capacitance at every frequency); otherwise points
/// that cannot be used are dropped with a warning.
pub fn analyse(
    sweep: &Sweep,
    name: &str,
    geom: &Geometry,
    settings: &Settings,
    geometry_from: &str,
) -> Result<SamplePermittivity> {
    settings.check()?;
    let mut warnings = Vec::new();
    let mut notes = sweep.notes.clone();
    let mut status = Status::Ok;
    let (stray, stray_std) = (settings.stray.unwrap_or(0.0), settings.stray_std);
    let inductive: Vec<f64> = sweep
        .points
        .iter()
        .filter(|p| p.y.im <= 0.0)
        .map(|p| p.freq)
        .collect();
    if inductive.len() == sweep.points.len() {
        let p = &sweep.points[sweep.points.len() / 2];
        let omega = 2.0 * PI * p.freq;
        let l = -1.0 / (omega * p.y.im);
        return Err(Error::input(
            Location::file(&sweep.path),
            format!(
                "inductive at every frequency: not a capacitor (susceptance B ≤ 0 from {}; e.g. Lp = {:.4e} H at {} Hz, which would read as a negative Cp)",
                freq_range(&inductive),
                l,
                p.freq
            ),
        )
        .with_hint("this export is of an inductor or a shorted fixture; measure the coupon between the plates (open/short compensation done)"));
    }
    if !inductive.is_empty() {
        status = Status::Warning;
        warnings.push(format!(
            "negative or zero capacitance (inductive) at {} of {} frequencies ({}): those points are dropped; cable inductance or a resonance of the fixture?",
            inductive.len(),
            sweep.points.len(),
            freq_range(&inductive)
        ));
    }
    let c0 = geom.empty_capacitance();
    let ce = geom.edge_capacitance();
    let rel_edge = ce / c0;
    let mut points = Vec::new();
    let mut leaky = Vec::new();
    let mut below_stray = Vec::new();
    let mut below_one = Vec::new();
    let mut beyond = Vec::new();
    let mut negative_d = Vec::new();
    for p in sweep.points.iter().filter(|p| p.y.im > 0.0) {
        let omega = 2.0 * PI * p.freq;
        let (cp, d) = (p.y.im / omega, p.y.re / p.y.im);
        if cp - stray <= 0.0 {
            below_stray.push(p.freq);
            continue;
        }
        if d > 1.0 {
            leaky.push((p.freq, d));
        }
        if d < 0.0 {
            negative_d.push((p.freq, d));
        }
        let f = |g: &Geometry, s: f64| eps_at(p.y, omega, g, s, settings.edge);
        let (eps, loss) = f(geom, stray);
        if !(eps.is_finite() && loss.is_finite()) {
            return Err(Error::input(
                Location::line(&sweep.path, p.line),
                format!("εr at {} Hz is not finite (ε′ = {eps}, ε″ = {loss}): the measured values overflow against the empty capacitance {c0:.4e} F", p.freq),
            )
            .with_hint("check the unit prefixes of the capacitance or impedance columns and the geometry"));
        }
        // Linear propagation of the independent tolerances stated (central
        // differences); none stated: unknown.
        let mut var = None;
        for (k, sd) in [(0, geom.area_std), (1, geom.thickness_std), (2, stray_std)] {
            let Some(sd) = sd else { continue };
            let (mut gp, mut gm, mut sp, mut sm) = (*geom, *geom, stray, stray);
            let h = match k {
                0 => {
                    let h = 1e-6 * geom.area;
                    gp.area += h;
                    gm.area -= h;
                    h
                }
                1 => {
                    let h = 1e-6 * geom.thickness;
                    gp.thickness += h;
                    gm.thickness -= h;
                    h
                }
                _ => {
                    let h = 1e-6 * cp;
                    sp += h;
                    sm -= h;
                    h
                }
            };
            let deriv = (f(&gp, sp).0 - f(&gm, sm).0) / (2.0 * h);
            *var.get_or_insert(0.0) += (deriv * sd).powi(2);
        }
        if eps < 1.0 {
            below_one.push((p.freq, eps));
        }
        if eps > PERMITTIVITY.max {
            beyond.push((p.freq, eps));
        }
        points.push(PermittivityPoint {
            freq_hz: p.freq,
            eps_r: eps,
            eps_r_std: var.map(f64::sqrt),
            eps_loss: loss,
            tan_delta: loss / eps,
            conductivity: ac_conductivity(loss, omega),
            cp,
            line: p.line,
        });
    }
    if points.is_empty() {
        return Err(Error::input(
            Location::file(&sweep.path),
            format!(
                "no frequency left with a positive capacitance after subtracting the stray {stray:.4e} F"
            ),
        )
        .with_hint("is the stray capacitance larger than the sample's? measure the open fixture again"));
    }
    if !below_stray.is_empty() {
        status = worst(status, Status::Warning);
        warnings.push(format!(
            "capacitance at or below the stray value at {} frequencies ({}): dropped",
            below_stray.len(),
            freq_range(&below_stray)
        ));
    }
    if let Some(&(f, d)) = leaky.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
        status = worst(status, Status::Warning);
        warnings.push(format!(
            "D > 1 at {} of {} frequencies (largest D = {d:.3} at {f} Hz): a leaky sample, not a capacitor there; εr from Cp is not meaningful where conduction dominates",
            leaky.len(),
            points.len()
        ));
    }
    if let Some(&(f, d)) = negative_d.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
        // The reader refuses D below −D_NOISE; what is left is within the meter's
        // accuracy, but a negative loss is not a material's.
        status = worst(status, Status::Warning);
        warnings.push(format!(
            "D slightly negative at {} of {} frequencies (most negative D = {d:.2e} at {f} Hz), within an LCR meter's accuracy of about ±{}: the loss there (ε″, tan δ, σ) is below what the meter resolves and is not a material value",
            negative_d.len(),
            points.len(),
            crate::io::lcr::D_NOISE
        ));
    }
    if let Some(&(f, e)) = below_one.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
        status = worst(status, Status::IllPosed);
        warnings.push(format!(
            "εr below 1 at {} frequencies (smallest {e:.4} at {f} Hz): impossible for a material; check the thickness and area (units: a bare number is m or m²) and the stray subtraction",
            below_one.len()
        ));
    }
    if let Some(&(f, e)) = beyond.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
        status = worst(status, Status::IllPosed);
        warnings.push(format!(
            "εr above {:e} at {} frequencies (largest {e:.4e} at {f} Hz): {}; check the capacitance unit, the thickness and the area",
            PERMITTIVITY.max,
            beyond.len(),
            PERMITTIVITY.reason
        ));
    }
    let gap_pct = 100.0 * rel_edge;
    let median_eps = {
        let mut e: Vec<f64> = points.iter().map(|p| p.eps_r).collect();
        e.sort_by(f64::total_cmp);
        e[e.len() / 2]
    };
    match settings.edge {
        EdgeCorrection::None => notes.push(format!(
            "edge correction off: Kirchhoff's fringe capacitance of these plates is {ce:.4e} F, {gap_pct:.1} % of the empty-gap capacitance; on unguarded plates with the fringe in air εr reads {:.1} % high (--edge air), with the fringe in the coupon {:.1} % high (--edge filled)",
            100.0 * rel_edge / median_eps,
            gap_pct
        )),
        EdgeCorrection::Air => notes.push(format!(
            "edge correction applied (fringe in air): Kirchhoff's {ce:.4e} F ({gap_pct:.1} % of the empty gap) subtracted from Cp"
        )),
        EdgeCorrection::Filled => notes.push(format!(
            "edge correction applied (fringe in the coupon): εr = C/(C0 + Ce), Ce = {ce:.4e} F ({gap_pct:.1} % of the empty gap)"
        )),
    }
    if let Some(s) = settings.stray {
        let value = if stray_std.is_some() {
            crate::report::format::si_pm(s, stray_std, "F")
        } else {
            format!("{} (no tolerance)", crate::report::format::si(s, "F"))
        };
        notes.push(format!("stray capacitance {value} subtracted from Cp"));
    }
    Ok(SamplePermittivity {
        schema: SCHEMA.into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        name: name.to_string(),
        points,
        geometry: *geom,
        corrections: Corrections {
            stray: settings.stray,
            edge: settings.edge,
            edge_capacitance: ce,
            edge_relative_to_empty_gap: rel_edge,
            empty_capacitance: c0,
        },
        status,
        warnings,
        notes,
        provenance: SampleSource {
            path: sweep.path.display().to_string(),
            sha256: sweep.sha256.clone(),
            format: sweep.format,
            pair: sweep.pair,
            instrument: sweep.instrument.clone(),
            columns: sweep.columns.clone(),
            geometry_from: geometry_from.to_string(),
            settings: *settings,
        },
    })
}

/// Read and analyse one input.
pub fn analyse_file(
    input: &Input,
    opts: &LcrOptions,
    settings: &Settings,
) -> Result<SamplePermittivity> {
    let sweep = lcr::read(&input.path, opts)?;
    let geom = input
        .geometry
        .clone()
        .map_err(|e| Error::input(Location::file(&input.path), e))?;
    analyse(&sweep, &input.name, &geom, settings, &input.geometry_from)
}

/// Frequencies missing from some samples of a series: one message per sample that
/// lacks frequencies the others have (relative tolerance 1e-6).
pub fn grid_check(samples: &[SamplePermittivity]) -> Vec<String> {
    let mut all: Vec<f64> = samples
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.freq_hz))
        .collect();
    all.sort_by(f64::total_cmp);
    all.dedup_by(|a, b| same_freq(*a, *b));
    samples
        .iter()
        .filter_map(|s| {
            let missing: Vec<f64> = all
                .iter()
                .copied()
                .filter(|&f| !s.points.iter().any(|p| same_freq(p.freq_hz, f)))
                .collect();
            (!missing.is_empty()).then(|| {
                let shown: Vec<String> = missing.iter().take(5).map(|f| format!("{f} Hz")).collect();
                format!(
                    "frequency point missing in sample '{}': {} of the series' {} frequencies ({}{})",
                    s.name,
                    missing.len(),
                    all.len(),
                    shown.join(", "),
                    if missing.len() > 5 { ", …" } else { "" }
                )
            })
        })
        .collect()
}

/// Two frequencies are the same point of a sweep (relative 1e-6).
pub fn same_freq(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs())
}

/// Analyse many files in parallel (rayon); `on_done` is called once per file as it
/// finishes (progress bars are the caller's). Errors of single files are collected
/// in `failed`, never abort the batch.
pub fn analyse_batch(
    inputs: &[Input],
    opts: &LcrOptions,
    settings: &Settings,
    on_done: &(dyn Fn() + Sync),
) -> Result<PermittivityRun> {
    settings.check()?;
    let results: Vec<Result<SamplePermittivity>> = inputs
        .par_iter()
        .map(|i| {
            let r = analyse_file(i, opts, settings);
            on_done();
            r
        })
        .collect();
    let mut samples = Vec::new();
    let mut failed = Vec::new();
    let mut warnings = Vec::new();
    let mut status = Status::Ok;
    for (i, r) in inputs.iter().zip(results) {
        match r {
            Ok(s) => {
                status = worst(status, s.status);
                warnings.extend(s.warnings.iter().map(|w| format!("{}: {w}", s.name)));
                samples.push(s);
            }
            Err(e) => failed.push(Failure {
                file: i.path.display().to_string(),
                error: e.to_string(),
            }),
        }
    }
    let grid = grid_check(&samples);
    if !grid.is_empty() {
        status = worst(status, Status::Warning);
        warnings.extend(grid);
    }
    if !failed.is_empty() {
        status = Status::Failed;
    }
    Ok(PermittivityRun {
        schema: RUN_SCHEMA.into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        samples,
        failed,
        warnings,
        status,
    })
}

/// The sample name of a file: its stem.
pub fn default_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}
