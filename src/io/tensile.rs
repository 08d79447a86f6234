//! Tensile-test files (uniaxial, equibiaxial, planar) → [`Dataset`] in SI.
//!
//! Header columns are `name_unit` (also `name [unit]` or `name (unit)`):
//! one kinematic column (`stretch`, `strain`, `strain_pct`, or `displacement_<length>`
//! with a gauge length), one stress column (`nominal_stress_<stress>`,
//! `true_stress_<stress>` converted with incompressibility σ = P·λ, or `force_<force>`
//! with a reference area), and optionally `weight`, `mode` and `time_<time>` (ignored).
//! The mode comes from a `mode` column, a `# mode: …` comment, or the caller.
//! Every point is checked against the tensile domain ([`Sample::check`]: stretch in
//! [`crate::data::STRETCH_RANGE`], |stress| ≤ [`crate::data::STRESS_MAX`], weight > 0)
//! and refused with its line, column and a hint.

use super::table::{split_header, Row, Table};
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

const ACCEPTED: &str = "stretch, strain, strain_pct, displacement_mm, nominal_stress_Pa|kPa|MPa, true_stress_Pa|kPa|MPa, force_N, weight, mode, time_s";

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

/// Read one tensile-test file.
pub fn read(path: &Path, opts: &TensileOptions) -> Result<Dataset> {
    let table = Table::read(path)?;
    from_table(&table, opts)
}

/// Interpret a parsed table as tensile data.
pub fn from_table(table: &Table, opts: &TensileOptions) -> Result<Dataset> {
    let path = &table.path;
    let hloc = |c: usize| Location::at(path, table.header_line, c + 1);
    let mut kin: Option<(usize, Kin)> = None;
    let mut stress: Option<(usize, Stress)> = None;
    let mut weight_col = None;
    let mut mode_col = None;
    let mut conversions = Vec::new();
    for (c, h) in table.header.iter().enumerate() {
        let (name, unit) = split_header(
            h,
            &[
                "nominal_stress",
                "true_stress",
                "force",
                "displacement",
                "time",
            ],
        );
        let k = match name.as_str() {
            "stretch" | "lambda" => Some(Kin::Stretch),
            "strain" => Some(Kin::Strain(match unit.as_deref() {
                None | Some("-") | Some("1") => 1.0,
                Some("%") | Some("pct") => 0.01,
                Some(u) => {
                    let e = Error::input(hloc(c), format!("unknown unit '{u}' in column '{h}'"));
                    return Err(if Dimension::Length.factor(u).is_some() {
                        e.with_hint(format!(
                            "a length is a displacement: name the column 'displacement_{u}' and pass --gauge-length"
                        ))
                    } else {
                        e.with_hint(
                            "strain is a fraction ('strain') or a percentage ('strain_pct')",
                        )
                    });
                }
            })),
            "strain_pct" | "strain_percent" => Some(Kin::Strain(0.01)),
            "displacement" => {
                let f = unit_factor(table, c, h, unit.clone(), Dimension::Length)?;
                let l0 = opts.gauge_length.ok_or_else(|| {
                    Error::input(
                        hloc(c),
                        format!("column '{h}' needs the gauge length to give a stretch"),
                    )
                    .with_hint("pass --gauge-length, e.g. --gauge-length 80mm")
                })?;
                conversions.push(format!("stretch = 1 + displacement / {l0} m"));
                Some(Kin::Displacement(f / l0))
            }
            _ => None,
        };
        if let Some(k) = k {
            if let Some((c0, _)) = kin {
                return Err(Error::input(
                    hloc(c),
                    format!(
                        "a second deformation column '{h}' (column {} is '{}')",
                        c0 + 1,
                        table.header[c0]
                    ),
                )
                .with_hint("keep one of stretch, strain, strain_pct, displacement"));
            }
            kin = Some((c, k));
            continue;
        }
        let s = match name.as_str() {
            "nominal_stress" | "engineering_stress" => Some(Stress::Nominal(unit_factor(
                table,
                c,
                h,
                unit.clone(),
                Dimension::Stress,
            )?)),
            "true_stress" | "cauchy_stress" => {
                conversions.push("nominal stress = true stress / stretch (incompressible)".into());
                Some(Stress::True(unit_factor(
                    table,
                    c,
                    h,
                    unit.clone(),
                    Dimension::Stress,
                )?))
            }
            "force" => {
                let f = unit_factor(table, c, h, unit.clone(), Dimension::Force)?;
                let a = opts.area.ok_or_else(|| {
                    Error::input(
                        hloc(c),
                        format!("column '{h}' needs the reference cross-section to give a stress"),
                    )
                    .with_hint("pass --area, e.g. --area 22mm2")
                })?;
                conversions.push(format!("nominal stress = force / {a} m²"));
                Some(Stress::Force(f / a))
            }
            _ => None,
        };
        if let Some(s) = s {
            if let Some((c0, _)) = stress {
                return Err(Error::input(
                    hloc(c),
                    format!(
                        "a second stress column '{h}' (column {} is '{}')",
                        c0 + 1,
                        table.header[c0]
                    ),
                )
                .with_hint("keep one of nominal_stress, true_stress, force"));
            }
            stress = Some((c, s));
            continue;
        }
        match name.as_str() {
            "weight" => weight_col = Some(c),
            "mode" => mode_col = Some(c),
            "time" => {
                unit_factor(table, c, h, unit, Dimension::Time)?;
            }
            _ => return Err(table.unknown_column(c, ACCEPTED, "stretch,nominal_stress_MPa")),
        }
    }
    let (kc, kin) = kin.ok_or_else(|| {
        Error::input(Location::line(path, table.header_line), "no stretch column")
            .with_hint("name one column stretch, strain, strain_pct or displacement_mm")
    })?;
    let (sc, stress) = stress.ok_or_else(|| {
        Error::input(Location::line(path, table.header_line), "no stress column")
            .with_hint("name one column nominal_stress_<Pa|kPa|MPa>, true_stress_<unit> or force_N")
    })?;

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
        let lam = match kin {
            Kin::Stretch => x,
            Kin::Strain(f) => 1.0 + x * f,
            Kin::Displacement(f) => 1.0 + x * f,
        };
        let y = table.number(row, sc, &sname)?;
        let p = match stress {
            Stress::Nominal(f) => y * f,
            Stress::True(f) => y * f / lam,
            Stress::Force(f) => y * f,
        };
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
            line: row.line,
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
                        line: row.line,
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
        }],
    })
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
