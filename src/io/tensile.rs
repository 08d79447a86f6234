//! Tensile-test files (uniaxial, equibiaxial, planar) → [`Dataset`] in SI.
//!
//! Header columns are `name_unit` (also `name [unit]` or `name (unit)`):
//! a kinematic column (`stretch`, `strain`, `strain_pct`, or `displacement_<length>`
//! with a gauge length), a stress column (`nominal_stress_<stress>`,
//! `true_stress_<stress>` converted with incompressibility σ = P·λ, or `force_<force>`
//! with a reference area), and optionally `weight`, `mode` and `time_<time>` (not
//! used). A testing machine's export reads as it is ([`read_with`]): the metadata
//! lines above its header are skipped, a units row under it is read, the names its
//! program writes are known ([`super::table::vendor_role`]: `Extension`, `Load`, `Standard
//! force`, `Tensile strain`, ...), `--columns` names any other ([`ColumnMap`]),
//! other columns are not used (a note lists them). Of two deformation (or stress)
//! columns one is used and the other checked against it ([`AGREE_REL`]): a
//! disagreement is a warning with its numbers.
//! The mode comes from a `mode` column, a `# mode: …` comment, or the caller.
//! Every point is checked against the tensile domain ([`Sample::check`]: stretch in
//! [`crate::data::STRETCH_RANGE`], |stress| ≤ [`crate::data::STRESS_MAX`], weight > 0)
//! and refused with its line, column and a hint.

use super::table::{normalise, split_header, vendor_role, ColumnMap, Row, Table};
use crate::data::{Dataset, Field, Sample, Source};
use crate::error::{Error, Location, Result};
use crate::fit::problem::PARALLEL_ROWS;
use crate::material::hyperelastic::{Mode, StrainEnergy};
use crate::units::Dimension;
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// How to read a tensile file.
#[derive(Debug, Clone, Copy, Default)]
pub struct TensileOptions {
    /// Reference cross-section (m²) for force columns.
    pub area: Option<f64>,
    /// Gauge length (m) for displacement columns.
    pub gauge_length: Option<f64>,
    /// Mode the caller requires (`--equibiaxial FILE`), or `None` for "uniaxial unless
    /// the file says otherwise".
    pub mode: Option<Mode>,
}

#[derive(Debug, Clone, Copy)]
enum Kin {
    Stretch,
    Strain(f64),
    Displacement(f64),
}

#[derive(Debug, Clone, Copy)]
enum Stress {
    Nominal(f64),
    True(f64),
    Force(f64),
}

const ACCEPTED: &str = "stretch, strain, strain_pct, displacement_mm, nominal_stress_Pa|kPa|MPa, true_stress_Pa|kPa|MPa, force_N, weight, mode, time_s, or the names testing-machine programs write (Extension, Load, Standard force, Strain, Tensile strain, Tensile stress, Time, ...)";

fn unit_factor(
    table: &Table,
    col: usize,
    header: &str,
    unit: Option<String>,
    dim: Dimension,
) -> Result<f64> {
    let loc = Location::at(&table.path, table.header_line, col + 1);
    let Some(unit) = unit else {
        return Err(Error::input(loc, format!("column '{header}' has no unit"))
            .with_hint(format!("write it as e.g. '{header}_{}'", dim.units()[0].0)));
    };
    dim.factor(&unit).ok_or_else(|| {
        let e = Error::input(loc, format!("unknown unit '{unit}' in column '{header}'"));
        match dim.suggest(&unit) {
            Some(s) => e.with_hint(format!("units are case-sensitive: did you mean '{s}'?")),
            None => e.with_hint(format!("expected one of {}", dim.accepted())),
        }
    })
}

/// The hint for a missing column: `what`, and the columns that were not used (a
/// misspelt name among them?).
fn missing_hint(what: &str, unused: &[String]) -> String {
    if unused.is_empty() {
        what.to_string()
    } else {
        format!(
            "{what}, or name the column with --columns (e.g. --columns stretch=Extension:mm,force=Load:N); not recognised: {}",
            unused.join(", ")
        )
    }
}

/// The roles `--columns` may give a tensile file's columns.
pub const ROLES: &[&str] = &[
    "stretch",
    "strain",
    "displacement",
    "force",
    "stress",
    "true_stress",
    "weight",
    "mode",
    "time",
];

/// Column names that take a `_unit` suffix (`force_N`, `displacement_mm`).
const SUFFIXED: &[&str] = &[
    "nominal_stress",
    "true_stress",
    "force",
    "displacement",
    "time",
];

/// The role and unit of header field `h`: from `map` when it names the column, else
/// from the name.
fn role_of<'a>(h: &str, map: &'a ColumnMap) -> (Option<&'a str>, Option<String>, bool) {
    let (name, unit) = split_header(h, SUFFIXED);
    match map.find(h) {
        Some((role, u)) => (Some(role), u.map(str::to_string).or(unit), true),
        None => {
            // `strain_pct` and `strain_percent` are names, not a unit suffix.
            let role = vendor_role(&normalise(&name));
            (role, unit, false)
        }
    }
}

/// Whether `fields` are a tensile export's header: one names a deformation and one
/// a stress or force (by [`vendor_role`] or `map`).
fn is_header(fields: &[&str], map: &ColumnMap) -> bool {
    let roles: Vec<&str> = fields.iter().filter_map(|f| role_of(f, map).0).collect();
    let deformation = roles
        .iter()
        .any(|r| matches!(*r, "stretch" | "strain" | "strain_pct" | "displacement"));
    let stress = roles
        .iter()
        .any(|r| matches!(*r, "stress" | "true_stress" | "force"));
    deformation && stress
}

/// Units of a strain written as a fraction.
const FRACTION: &[&str] = &["-", "1", "mm/mm", "m/m", "in/in"];
/// Units of a strain written in percent.
const PERCENT: &[&str] = &["%", "pct", "percent"];

/// The deformation column `c` (role `role`, unit `unit`) as a [`Kin`], or None for a
/// displacement without a gauge length (the caller decides whether that is an
/// error). A `stretch` given a strain or length unit in `--columns` is a strain or
/// a displacement.
fn kinematic(
    table: &Table,
    c: usize,
    role: &str,
    unit: Option<String>,
    opts: &TensileOptions,
) -> Result<Option<Kin>> {
    let h = &table.header[c];
    let hloc = Location::at(&table.path, table.header_line, c + 1);
    let u = unit.as_deref();
    let is_length = u.is_some_and(|u| Dimension::Length.factor(u).is_some());
    Ok(Some(match role {
        "strain_pct" => Kin::Strain(0.01),
        "stretch" if u.is_none() || u.is_some_and(|u| ["-", "1"].contains(&u)) => Kin::Stretch,
        "stretch" | "strain" if u.is_none() || u.is_some_and(|u| FRACTION.contains(&u)) => {
            Kin::Strain(1.0)
        }
        "stretch" | "strain" if u.is_some_and(|u| PERCENT.contains(&u)) => Kin::Strain(0.01),
        "strain" if is_length => {
            let u = u.unwrap_or_default();
            return Err(Error::input(hloc, format!("unknown unit '{u}' in column '{h}'"))
                .with_hint(format!(
                    "a length is a displacement: name the column 'displacement_{u}' and pass --gauge-length"
                )));
        }
        "strain" => {
            return Err(Error::input(
                hloc,
                format!("unknown unit '{}' in column '{h}'", u.unwrap_or_default()),
            )
            .with_hint("strain is a fraction ('strain') or a percentage ('strain_pct')"))
        }
        _ => {
            let f = unit_factor(table, c, h, unit, Dimension::Length)?;
            match opts.gauge_length {
                Some(l0) => Kin::Displacement(f / l0),
                None => return Ok(None),
            }
        }
    }))
}

/// The stress column `c` (role `role`) as a [`Stress`], or None for a force without
/// a reference area.
fn stress_of(
    table: &Table,
    c: usize,
    role: &str,
    unit: Option<String>,
    opts: &TensileOptions,
) -> Result<Option<Stress>> {
    let h = &table.header[c];
    Ok(Some(match role {
        "stress" => Stress::Nominal(unit_factor(table, c, h, unit, Dimension::Stress)?),
        "true_stress" => Stress::True(unit_factor(table, c, h, unit, Dimension::Stress)?),
        _ => {
            let f = unit_factor(table, c, h, unit, Dimension::Force)?;
            match opts.area {
                Some(a) => Stress::Force(f / a),
                None => return Ok(None),
            }
        }
    }))
}

/// Preference among columns of one kind when the map names none: a stretch, a
/// strain, a displacement; a nominal stress, a force, a true stress.
fn kin_rank(k: &Kin) -> u8 {
    match k {
        Kin::Stretch => 0,
        Kin::Strain(_) => 1,
        Kin::Displacement(_) => 2,
    }
}

fn stress_rank(s: &Stress) -> u8 {
    match s {
        Stress::Nominal(_) => 0,
        Stress::Force(_) => 1,
        Stress::True(_) => 2,
    }
}

/// Two columns of one quantity agree when they differ by at most this fraction of
/// the quantity's largest magnitude (strain λ − 1, or stress) plus [`AGREE_ABS`]: a
/// crosshead's extension and an extensometer's strain, or a force over the area
/// and the program's stress, differ by the rounding of the export and a few tenths
/// of a percent of calibration; a slipping grip or a wrong gauge length or area
/// makes them differ by percents.
pub const AGREE_REL: f64 = 0.01;

/// The absolute part of the agreement of two columns, in the quantity's own scale
/// (strain, or stress relative to the largest): the rounding of an export.
pub const AGREE_ABS: f64 = 1e-3;

/// Read one tensile-test file.
pub fn read(path: &Path, opts: &TensileOptions) -> Result<Dataset> {
    read_with(path, opts, &ColumnMap::default())
}

/// Read one tensile-test file, a testing machine's export included: a preamble above
/// the header and a units row under it ([`Table::parse_export`]), the columns named
/// by `map` (`--columns`) or by the names testing-machine programs write.
pub fn read_with(path: &Path, opts: &TensileOptions, map: &ColumnMap) -> Result<Dataset> {
    let export = Table::read_export(path, &|fields| is_header(fields, map))?;
    let mut data = from_table_with(&export.table, opts, map)?;
    let notes = &mut data.sources[0].notes;
    let read = std::mem::take(notes);
    notes.extend(export.notes);
    notes.extend(read);
    Ok(data)
}

/// Interpret a parsed table as tensile data.
pub fn from_table(table: &Table, opts: &TensileOptions) -> Result<Dataset> {
    from_table_with(table, opts, &ColumnMap::default())
}

/// Interpret a parsed table as tensile data, the columns named by `map` or their
/// names ([`read_with`]).
pub fn from_table_with(table: &Table, opts: &TensileOptions, map: &ColumnMap) -> Result<Dataset> {
    let path = &table.path;
    map.check(table)?;
    let hloc = |c: usize| Location::at(path, table.header_line, c + 1);
    // Every deformation and stress column: (column, reading or None when it lacks
    // the gauge length or area, named by the map).
    let mut kins: Vec<Candidate<Kin>> = Vec::new();
    let mut stresses: Vec<Candidate<Stress>> = Vec::new();
    let mut weight_col = None;
    let mut mode_col = None;
    let mut unused = Vec::new();
    for (c, h) in table.header.iter().enumerate() {
        let (role, unit, mapped) = role_of(h, map);
        match role {
            Some(r @ ("stretch" | "strain" | "strain_pct" | "displacement")) => {
                kins.push((c, kinematic(table, c, r, unit, opts)?, mapped));
            }
            Some(r @ ("stress" | "true_stress" | "force")) => {
                stresses.push((c, stress_of(table, c, r, unit, opts)?, mapped));
            }
            Some("weight") => weight_col = Some(c),
            Some("mode") => mode_col = Some(c),
            Some(_) => unused.push(h.clone()),
            None if h.trim().is_empty() || h.trim().parse::<f64>().is_ok() => {
                return Err(table.unknown_column(c, ACCEPTED, "stretch,nominal_stress_MPa"))
            }
            None => unused.push(h.clone()),
        }
    }
    let mut notes = Vec::new();
    if !unused.is_empty() {
        notes.push(format!("columns not used: {}", unused.join(", ")));
    }
    // The column used: the one the map names, else the preferred usable one.
    let pick_kin = kins
        .iter()
        .filter_map(|&(c, k, m)| k.map(|k| (c, k, m)))
        .min_by_key(|&(_, k, m)| (!m, kin_rank(&k)));
    let Some((kc, kin, _)) = pick_kin else {
        if let Some(&(c, _, _)) = kins.first() {
            return Err(Error::input(
                hloc(c),
                format!(
                    "column '{}' needs the gauge length to give a stretch",
                    table.header[c]
                ),
            )
            .with_hint("pass --gauge-length, e.g. --gauge-length 80mm"));
        }
        return Err(
            Error::input(Location::line(path, table.header_line), "no stretch column").with_hint(
                missing_hint(
                    "name one column stretch, strain, strain_pct or displacement_mm",
                    &unused,
                ),
            ),
        );
    };
    let pick_stress = stresses
        .iter()
        .filter_map(|&(c, s, m)| s.map(|s| (c, s, m)))
        .min_by_key(|&(_, s, m)| (!m, stress_rank(&s)));
    let Some((sc, stress, _)) = pick_stress else {
        if let Some(&(c, _, _)) = stresses.first() {
            return Err(Error::input(
                hloc(c),
                format!(
                    "column '{}' needs the reference cross-section to give a stress",
                    table.header[c]
                ),
            )
            .with_hint("pass --area, e.g. --area 22mm2"));
        }
        return Err(
            Error::input(Location::line(path, table.header_line), "no stress column").with_hint(
                missing_hint(
                    "name one column nominal_stress_<Pa|kPa|MPa>, true_stress_<unit> or force_N",
                    &unused,
                ),
            ),
        );
    };
    let mut conversions = Vec::new();
    match kin {
        Kin::Displacement(_) => conversions.push(format!(
            "stretch = 1 + displacement / {} m",
            opts.gauge_length.unwrap_or(f64::NAN)
        )),
        Kin::Strain(_) | Kin::Stretch => {}
    }
    match stress {
        Stress::True(_) => {
            conversions.push("nominal stress = true stress / stretch (incompressible)".into())
        }
        Stress::Force(_) => conversions.push(format!(
            "nominal stress = force / {} m²",
            opts.area.unwrap_or(f64::NAN)
        )),
        Stress::Nominal(_) => {}
    }
    for (others, used, what, missing) in [
        (
            kins.iter()
                .map(|k| (k.0, k.1.is_some()))
                .collect::<Vec<_>>(),
            kc,
            "deformation",
            "--gauge-length",
        ),
        (
            stresses.iter().map(|s| (s.0, s.1.is_some())).collect(),
            sc,
            "stress",
            "--area",
        ),
    ] {
        for (c, usable) in others.into_iter().filter(|o| o.0 != used) {
            notes.push(if usable {
                format!(
                    "two {what} columns: '{}' used, '{}' checked against it",
                    table.header[used], table.header[c]
                )
            } else {
                format!(
                    "two {what} columns: '{}' used, '{}' not (it needs {missing})",
                    table.header[used], table.header[c]
                )
            });
        }
    }

    // The file's own mode statement (a comment), checked against the caller's.
    let mut file_mode: Option<(Mode, usize)> = None;
    for (line, key, value) in &table.directives {
        if key == "mode" {
            let m = Mode::parse(value).ok_or_else(|| {
                Error::input(
                    Location::line(path, *line),
                    format!("unknown mode '{value}'"),
                )
                .with_hint("use uniaxial, equibiaxial or planar")
            })?;
            if let Some((m0, l0)) = file_mode.filter(|(m0, _)| *m0 != m) {
                return Err(Error::input(
                    Location::line(path, *line),
                    format!("this '# mode:' line says {m}, but line {l0} says {m0}"),
                )
                .with_hint("keep one '# mode:' line; a file mixing modes needs a mode column"));
            }
            file_mode = Some((m, *line));
        }
    }
    let default_mode = match (opts.mode, file_mode) {
        (Some(want), Some((m, line))) if want != m => {
            return Err(Error::input(
                Location::line(path, line),
                format!("the file says mode {m} but it was given as {want} data"),
            )
            .with_hint("pass it with the flag of its mode, or correct the comment"))
        }
        (Some(want), _) => want,
        (None, Some((m, _))) => m,
        (None, None) => Mode::Uniaxial,
    };
    // What a mode column must agree with, if anything: the flag, else the comment.
    let declared = match (opts.mode, file_mode) {
        (Some(want), _) => Some((
            want,
            format!("a file given as {want} data"),
            "a file passed with --equibiaxial or --planar holds that mode only; pass a file mixing modes without the flag",
        )),
        (None, Some((m, line))) => Some((
            m,
            format!("a file whose '# mode:' comment (line {line}) says {m}"),
            "the mode column gives each row's mode: drop the '# mode:' line, or correct this row",
        )),
        (None, None) => None,
    };

    // Column names for errors, made once rather than per row.
    let (kname, sname) = (
        format!("'{}'", table.header[kc]),
        format!("'{}'", table.header[sc]),
    );
    let read_row = |row: &Row| -> Result<Sample> {
        let x = table.number(row, kc, &kname)?;
        let lam = stretch_of(kin, x);
        let y = table.number(row, sc, &sname)?;
        let p = nominal_of(stress, y, lam);
        let weight = match weight_col {
            Some(c) => table.number(row, c, "'weight'")?,
            None => 1.0,
        };
        let mode = match mode_col {
            Some(c) => {
                let m = Mode::parse(table.field(row, c)).ok_or_else(|| {
                    Error::input(
                        table.loc(row, c),
                        format!("unknown mode '{}'", table.field(row, c)),
                    )
                    .with_hint("use uniaxial, equibiaxial or planar")
                })?;
                if let Some((_, why, hint)) = declared.as_ref().filter(|d| d.0 != m) {
                    return Err(
                        Error::input(table.loc(row, c), format!("mode {m} in {why}"))
                            .with_hint(*hint),
                    );
                }
                m
            }
            None => default_mode,
        };
        let sample = Sample {
            mode,
            stretch: lam,
            stress: p,
            weight,
            source: 0,
            line: row.line(),
        };
        if let Err(f) = sample.check() {
            let col = match f.field {
                Field::Stretch => kc,
                Field::Stress => sc,
                Field::Weight => weight_col.unwrap_or(kc),
            };
            let converted = f.field == Field::Stretch && !matches!(kin, Kin::Stretch)
                || f.field == Field::Stress && !matches!(stress, Stress::Nominal(_));
            let message = if converted {
                format!("{} (from '{}')", f.message, table.field(row, col))
            } else {
                f.message
            };
            let hint = match (f.field, kin, stress) {
                (Field::Stretch, Kin::Strain(_) | Kin::Displacement(_), _) if lam <= 0.0 => {
                    "a strain of -1 or less means the coupon has zero length".to_string()
                }
                (Field::Stress, _, Stress::Force(_)) => {
                    "is the unit right? check the force unit and --area (e.g. --area 22mm2)"
                        .to_string()
                }
                _ => f.hint,
            };
            return Err(Error::input(table.loc(row, col), message).with_hint(hint));
        }
        Ok(sample)
    };
    // Rows are read each on its own, so a parallel read (each sample written once, in
    // its final place) gives the serial samples; on any error the serial read finds the
    // first in file order, the one reported.
    let parallel = (table.rows.len() >= PARALLEL_ROWS).then(|| {
        let failed = AtomicBool::new(false);
        let samples: Vec<Sample> = table
            .rows
            .par_iter()
            .map(|row| {
                read_row(row).unwrap_or_else(|_| {
                    failed.store(true, Ordering::Relaxed);
                    Sample {
                        mode: default_mode,
                        stretch: f64::NAN,
                        stress: f64::NAN,
                        weight: f64::NAN,
                        source: 0,
                        line: row.line(),
                    }
                })
            })
            .collect();
        (!failed.into_inner()).then_some(samples)
    });
    let samples = match parallel {
        Some(Some(samples)) => samples,
        _ => table
            .rows
            .iter()
            .map(&read_row)
            .collect::<Result<Vec<_>>>()?,
    };
    let warnings = disagreements(table, &samples, (kc, &kins), (sc, &stresses), opts);
    // The modes present and the stretch range, in one pass.
    let mut present = [false; 3];
    let (lo, hi) = samples
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            present[s.mode as usize] = true;
            (a.min(s.stretch), b.max(s.stretch))
        });
    let modes: Vec<Mode> = Mode::ALL
        .into_iter()
        .filter(|&m| present[m as usize])
        .collect();
    Ok(Dataset {
        samples,
        sources: vec![Source {
            path: path.display().to_string(),
            sha256: table.sha256.clone(),
            modes,
            points: table.rows.len(),
            stretch_min: lo,
            stretch_max: hi,
            columns: table.header.clone(),
            conversions,
            notes,
            warnings,
        }],
    })
}

/// A deformation or stress column: its index, its reading (None when it lacks the
/// gauge length or area) and whether `--columns` named it.
type Candidate<T> = (usize, Option<T>, bool);

/// The stretch a deformation column's value `x` gives.
fn stretch_of(kin: Kin, x: f64) -> f64 {
    match kin {
        Kin::Stretch => x,
        Kin::Strain(f) | Kin::Displacement(f) => 1.0 + x * f,
    }
}

/// The nominal stress a stress column's value `y` gives at stretch `lam`.
fn nominal_of(stress: Stress, y: f64, lam: f64) -> f64 {
    match stress {
        Stress::Nominal(f) | Stress::Force(f) => y * f,
        Stress::True(f) => y * f / lam,
    }
}

/// The largest difference of `other` from `used` (index, difference) when it
/// exceeds [`AGREE_REL`] of `scale` plus `abs`.
fn disagreement(used: &[f64], other: &[f64], scale: f64, abs: f64) -> Option<(usize, f64)> {
    let (i, d) = used
        .iter()
        .zip(other)
        .map(|(u, o)| (o - u).abs())
        .enumerate()
        .fold((0, 0.0), |b, (i, d)| if d > b.1 { (i, d) } else { b });
    (d > AGREE_REL * scale + abs).then_some((i, d))
}

/// The factor k minimising Σ (k·a − b)²: Σ a·b / Σ a².
fn scale_between(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    ab / aa
}

/// The warnings of the deformation and stress columns checked against the ones used
/// (`used.0`, `used_stress.0`): for each that disagrees beyond [`AGREE_REL`], the
/// largest difference, where, and the gauge length or area that would make a
/// displacement or force agree. A column with a value that is not a number is not
/// compared (the note says it was checked; its values are not).
fn disagreements(
    table: &Table,
    samples: &[Sample],
    (kc, kins): (usize, &[Candidate<Kin>]),
    (sc, stresses): (usize, &[Candidate<Stress>]),
    opts: &TensileOptions,
) -> Vec<String> {
    let mut out = Vec::new();
    let column = |c: usize| -> Option<Vec<f64>> {
        table
            .rows
            .iter()
            .map(|r| table.number(r, c, "").ok())
            .collect()
    };
    let lines = |i: usize| table.rows[i].line();
    let eps: Vec<f64> = samples.iter().map(|s| s.stretch - 1.0).collect();
    let eps_max = eps.iter().fold(0.0f64, |a, e| a.max(e.abs()));
    let used_kin = kins.iter().find(|k| k.0 == kc).and_then(|k| k.1);
    for &(c, k, _) in kins.iter().filter(|k| k.0 != kc) {
        let (Some(k), Some(x)) = (k, column(c)) else {
            continue;
        };
        let other: Vec<f64> = x.iter().map(|&x| stretch_of(k, x) - 1.0).collect();
        let Some((i, d)) = disagreement(&eps, &other, eps_max, AGREE_ABS) else {
            continue;
        };
        let mut w = format!(
            "the deformation columns disagree: at line {} '{}' gives stretch {:.4} and '{}' {:.4} (difference {:.2e} in strain, {:.1} % of the largest strain {:.3}); '{}' was used",
            lines(i),
            table.header[c],
            1.0 + other[i],
            table.header[kc],
            1.0 + eps[i],
            d,
            100.0 * d / eps_max.max(f64::MIN_POSITIVE),
            eps_max,
            table.header[kc]
        );
        if let Some(l0) = opts.gauge_length {
            let l = match (k, used_kin) {
                (Kin::Displacement(_), _) => Some(l0 * scale_between(&other, &eps).recip()),
                (_, Some(Kin::Displacement(_))) => Some(l0 * scale_between(&eps, &other).recip()),
                _ => None,
            };
            if let Some(l) = l.filter(|l| l.is_finite() && *l > 0.0) {
                w.push_str(&format!(
                    "; the displacement agrees best with the strain for a gauge length of {:.2} mm (given {:.2} mm)",
                    l * 1e3,
                    l0 * 1e3
                ));
            }
        }
        out.push(w);
    }
    let p: Vec<f64> = samples.iter().map(|s| s.stress).collect();
    let p_max = p.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let used_stress = stresses.iter().find(|s| s.0 == sc).and_then(|s| s.1);
    for &(c, st, _) in stresses.iter().filter(|s| s.0 != sc) {
        let (Some(st), Some(y)) = (st, column(c)) else {
            continue;
        };
        let other: Vec<f64> = y
            .iter()
            .zip(samples)
            .map(|(&y, s)| nominal_of(st, y, s.stretch))
            .collect();
        let Some((i, d)) = disagreement(&p, &other, p_max, AGREE_ABS * p_max) else {
            continue;
        };
        let mut w = format!(
            "the stress columns disagree: at line {} '{}' gives a nominal stress of {:.4e} Pa and '{}' {:.4e} Pa (difference {:.1} % of the largest stress); '{}' was used",
            lines(i),
            table.header[c],
            other[i],
            table.header[sc],
            p[i],
            100.0 * d / p_max.max(f64::MIN_POSITIVE),
            table.header[sc]
        );
        if let Some(a) = opts.area {
            let area = match (st, used_stress) {
                (Stress::Force(_), _) => Some(a * scale_between(&p, &other).recip()),
                (_, Some(Stress::Force(_))) => Some(a * scale_between(&other, &p).recip()),
                _ => None,
            };
            if let Some(area) = area.filter(|x| x.is_finite() && *x > 0.0) {
                w.push_str(&format!(
                    "; the force agrees best with the stress for an area of {:.3} mm² (given {:.3} mm²)",
                    area * 1e6,
                    a * 1e6
                ));
            }
        }
        out.push(w);
    }
    out
}

/// Append synthetic tensile rows `stretch,nominal_stress_kPa` (stretch to 6 decimals,
/// stress in kPa to 6) to `out`: the model's nominal stress at each stretch with
/// Gaussian noise, relative (`noise`, a fraction of the stress) and absolute
/// (`noise_abs`, Pa), drawn from `rng` (two draws per row). Used by `dea-fit synth
/// hyperelastic` and `dea-fit bench scale`.
pub fn synthetic_rows(
    model: &dyn StrainEnergy,
    p: &[f64],
    mode: Mode,
    stretches: impl Iterator<Item = f64>,
    (noise, noise_abs): (f64, f64),
    rng: &mut impl rand::Rng,
    out: &mut String,
) -> Result<()> {
    use rand_distr::Distribution;
    use std::fmt::Write as _;
    let unit = rand_distr::Normal::new(0.0, 1.0).expect("a unit normal is valid");
    for l in stretches {
        let clean = model.nominal_stress(p, mode, l);
        let e1: f64 = unit.sample(rng);
        let e2: f64 = unit.sample(rng);
        let y = clean * (1.0 + noise * e1) + noise_abs * e2;
        if !y.is_finite() {
            return Err(Error::settings(format!(
                "the model gives a non-finite stress ({y}) at stretch {l}: no data written"
            ))
            .with_hint(
                "keep --stretch inside the model's domain (e.g. below Gent's locking stretch)",
            ));
        }
        let _ = writeln!(out, "{l:.6},{:.6}", y / 1e3);
    }
    Ok(())
}
