//! DMA files → [`DmaData`] in SI.
//!
//! Header columns are `name_unit` (also `name [unit]`, `name (unit)`, or a units row
//! under the header): one frequency column (`frequency_<Hz|mHz|kHz>` or
//! `omega_rad_s`), one storage modulus column (`storage_modulus_<Pa|kPa|MPa|GPa>`,
//! also `E'`), and a loss modulus column (`loss_modulus_…`, also `E''`) or a
//! `tan_delta` column; the temperature in a `temperature_<C|K>` column (several
//! isotherms in one file: one block of rows per temperature) or a
//! `# temperature: 25 C` line (one isotherm). A file without either is a master curve
//! at the reference temperature. An instrument's preamble, units row and extra
//! columns (strain amplitude, force, phase) are read past
//! ([`Table::parse_export`]); `--columns` names the columns of other exports.
//!
//! Order: an isotherm's frequencies go one way. A sweep from high to low frequency
//! (as many instruments run it) is reversed, with a note; a repeated frequency or one
//! that turns back is a located error. A master curve may repeat frequencies (two
//! isotherms overlap there) and is sorted by frequency, with a note when it was not.

use super::temperature::{self, Scale};
use super::{DmaData, DmaSource, Isotherm};
use crate::error::{Error, Location, Result};
use crate::io::table::{column_unit, normalise, split_header, ColumnMap, Table};
use crate::units::Dimension;
use std::path::Path;

/// The roles `--columns` may give a DMA file's columns.
pub const ROLES: &[&str] = &[
    "frequency",
    "omega",
    "storage",
    "loss",
    "tan_delta",
    "temperature",
];

/// The frequencies a file may hold (Hz): reduced frequencies of real master curves
/// span 10⁻²⁰ … 10¹⁴ Hz; five decades of margin each side, and beyond them a unit slip.
pub const FREQUENCY_RANGE_HZ: (f64, f64) = (1e-25, 1e19);

/// The largest modulus a file may hold (Pa): stiffer than diamond (1.2 TPa) is a unit slip.
pub const MODULUS_MAX: f64 = 1e12;

/// The largest tan δ a file may hold: a liquid's is large, but 10⁴ is a unit slip or
/// a modulus column read as tan δ.
pub const TAN_DELTA_MAX: f64 = 1e4;

/// Rows of a temperature column within this of their block's mean (K) are one
/// isotherm: an oven holds its set point to a few tenths of a kelvin, and isotherms
/// are set ≥ 1 K apart.
pub const ISOTHERM_TOLERANCE_K: f64 = 0.5;

/// Columns that take a `_unit` suffix.
const COLUMNS: &[&str] = &[
    "angular_frequency",
    "frequency",
    "omega",
    "storage_modulus",
    "loss_modulus",
    "tan_delta",
    "temperature",
];

const ACCEPTED: &str = "frequency_Hz (or omega_rad_s), storage_modulus_Pa|kPa|MPa|GPa, loss_modulus_… or tan_delta, optionally temperature_C|K";

/// What a column holds, with its factor to SI.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Col {
    /// Factor to rad/s.
    Omega(f64),
    Storage(f64),
    Loss(f64),
    TanDelta,
    Temperature(Scale),
}

/// The role of a header name (lower case, as split from its unit), or None.
fn role_name(name: &str) -> Option<&'static str> {
    // primes and Greek letters before `normalise` drops them
    match name.trim() {
        "e'" | "e′" | "g'" | "g′" => return Some("storage"),
        "e''" | "e″" | "g''" | "g″" => return Some("loss"),
        "tan_δ" | "tan δ" | "tanδ" => return Some("tan_delta"),
        _ => {}
    }
    Some(match normalise(name).as_str() {
        "frequency" | "freq" => "frequency",
        "omega" | "angular_frequency" | "ang_frequency" => "omega",
        "storage_modulus" | "storage" | "e_storage" | "tensile_storage_modulus" => "storage",
        "loss_modulus" | "loss" | "e_loss" | "tensile_loss_modulus" => "loss",
        "tan_delta" | "tan_d" | "tandelta" | "loss_factor" | "loss_tangent" => "tan_delta",
        "temperature" | "temp" => "temperature",
        _ => return None,
    })
}

/// The role and unit of header field `h`: from `map` when it names the column, else
/// from its name.
fn role_of(h: &str, map: &ColumnMap) -> (Option<String>, Option<String>) {
    let (name, unit) = split_header(h, COLUMNS);
    match map.find(h) {
        Some((role, u)) => (Some(role.to_string()), u.map(str::to_string).or(unit)),
        None => (role_name(&name).map(str::to_string), unit),
    }
}

/// The column kind of `role` with unit `u` at column `c`.
fn column(table: &Table, c: usize, role: &str, u: Option<&str>) -> Result<Col> {
    let h = &table.header[c];
    let loc = Location::at(&table.path, table.header_line, c + 1);
    let rad = |u: &str| matches!(u, "rad_s" | "rad/s" | "1/s" | "rad s-1" | "s-1");
    Ok(match role {
        "frequency" | "omega" => match u {
            Some(u) if rad(u) => Col::Omega(1.0),
            _ if role == "omega" => {
                return Err(Error::input(
                    loc,
                    format!("column '{h}' holds angular frequency: its unit is rad/s"),
                )
                .with_hint("write it as omega_rad_s, or give frequency_Hz"))
            }
            _ => Col::Omega(
                2.0 * std::f64::consts::PI * column_unit(table, c, u, Dimension::Frequency)?,
            ),
        },
        "storage" => Col::Storage(column_unit(table, c, u, Dimension::Stress)?),
        "loss" => Col::Loss(column_unit(table, c, u, Dimension::Stress)?),
        "tan_delta" => match u {
            None | Some("-") | Some("1") | Some("") => Col::TanDelta,
            Some(other) => {
                return Err(Error::input(
                    loc,
                    format!("tan δ is a pure number; column '{h}' has the unit '{other}'"),
                )
                .with_hint("name it tan_delta (no unit)"))
            }
        },
        "temperature" => Col::Temperature(match u {
            None => {
                return Err(Error::input(loc, format!("column '{h}' has no unit"))
                    .with_hint("write it as temperature_C or temperature_K"))
            }
            Some(u) => Scale::of(u).ok_or_else(|| {
                Error::input(loc, format!("unknown unit '{u}' in column '{h}'"))
                    .with_hint("a temperature is in C (°C) or K")
            })?,
        }),
        _ => unreachable!("roles are those of ROLES"),
    })
}

/// Read the DMA files `paths`: isotherms sorted by temperature, or one master curve.
/// Two isotherms at one temperature, or a master curve beside isotherms, are refused.
pub fn read_all(paths: &[&Path], map: &ColumnMap) -> Result<DmaData> {
    let mut isotherms: Vec<Isotherm> = Vec::new();
    let mut sources = Vec::new();
    for path in paths {
        let (mut iso, source) = read_with(path, map)?;
        for new in &iso {
            let clash = isotherms
                .iter()
                .find(|old| match (old.temperature_k, new.temperature_k) {
                    (Some(a), Some(b)) => (a - b).abs() <= ISOTHERM_TOLERANCE_K,
                    _ => true,
                });
            if let Some(old) = clash {
                let what = match new.temperature_k {
                    Some(t) if old.temperature_k.is_some() => format!(
                        "an isotherm at {} was already read from {} (line {})",
                        temperature::celsius(t),
                        old.file,
                        old.line[0]
                    ),
                    _ => format!(
                        "a master curve (a file without temperature) cannot be read beside other data ({} was read first)",
                        old.file
                    ),
                };
                return Err(Error::input(Location::line(path, new.line[0]), what).with_hint(
                    "give each isotherm once, with its temperature (a temperature_C column or a '# temperature: 25 C' line), or one master curve alone",
                ));
            }
        }
        isotherms.append(&mut iso);
        sources.push(source);
    }
    isotherms.sort_by(|a, b| {
        a.temperature_k
            .partial_cmp(&b.temperature_k)
            .expect("finite")
    });
    Ok(DmaData { isotherms, sources })
}

/// Read one DMA file: its isotherms (in file order) and its provenance.
pub fn read_with(path: &Path, map: &ColumnMap) -> Result<(Vec<Isotherm>, DmaSource)> {
    let export = Table::read_export(path, &|fields| {
        let roles: Vec<Option<String>> = fields.iter().map(|f| role_of(f, map).0).collect();
        let has = |r: &[&str]| roles.iter().flatten().any(|x| r.contains(&x.as_str()));
        has(&["frequency", "omega"]) && has(&["storage"])
    })?;
    let (iso, mut source) = from_table(&export.table, map)?;
    let read = std::mem::take(&mut source.notes);
    source.notes = export.notes;
    source.notes.extend(read);
    Ok((iso, source))
}

/// One point as read: line, ω (rad/s), E′, E″ (Pa), T (K).
#[derive(Debug, Clone, Copy)]
struct Point {
    line: usize,
    omega: f64,
    storage: f64,
    loss: f64,
    temperature: Option<f64>,
}

/// Interpret a parsed table as DMA data ([`read_with`]).
pub fn from_table(table: &Table, map: &ColumnMap) -> Result<(Vec<Isotherm>, DmaSource)> {
    let path = &table.path;
    map.check(table)?;
    let slots: [Option<(usize, Col)>; 4] = [None; 4];
    let [mut freq, mut storage, mut loss, mut temp] = slots;
    let mut unused: Vec<String> = Vec::new();
    let mut notes = Vec::new();
    for (c, h) in table.header.iter().enumerate() {
        let (role, u) = role_of(h, map);
        let Some(role) = role else {
            if h.trim().is_empty() || h.trim().parse::<f64>().is_ok() {
                return Err(table.unknown_column(
                    c,
                    ACCEPTED,
                    "frequency_Hz,storage_modulus_MPa,loss_modulus_MPa",
                ));
            }
            unused.push(h.clone());
            continue;
        };
        let col = column(table, c, &role, u.as_deref())?;
        let slot = match col {
            Col::Omega(_) => &mut freq,
            Col::Storage(_) => &mut storage,
            Col::Loss(_) | Col::TanDelta => &mut loss,
            Col::Temperature(_) => &mut temp,
        };
        // an export with both E″ and tan δ: E″ is read, tan δ (E″/E′) not used
        match (*slot, col) {
            (Some((_, Col::Loss(_))), Col::TanDelta) => {
                unused.push(h.clone());
                continue;
            }
            (Some((c0, Col::TanDelta)), Col::Loss(_)) => {
                unused.push(table.header[c0].clone());
                *slot = Some((c, col));
                continue;
            }
            _ => {}
        }
        if let Some((c0, _)) = *slot {
            return Err(table.second_column(c, c0, "keep one frequency, one storage modulus, one loss modulus or tan δ, and at most one temperature column"));
        }
        *slot = Some((c, col));
    }
    let hline = Location::line(path, table.header_line);
    let missing = |what: &str| {
        let hint = if unused.is_empty() {
            format!("accepted columns: {ACCEPTED}")
        } else {
            format!(
                "name it with --columns (roles {}), e.g. --columns frequency=Freq:Hz; not recognised: {}",
                ROLES.join(", "),
                unused.join(", ")
            )
        };
        Error::input(hline.clone(), format!("no {what} column")).with_hint(hint)
    };
    let Some((fc, Col::Omega(ff))) = freq else {
        return Err(missing("frequency (frequency_Hz or omega_rad_s)"));
    };
    let Some((sc, Col::Storage(sf))) = storage else {
        return Err(missing("storage modulus (storage_modulus_MPa, …)"));
    };
    let Some((lc, lcol)) = loss else {
        return Err(missing(
            "loss modulus or tan δ (loss_modulus_MPa or tan_delta)",
        ));
    };
    if lcol == Col::TanDelta {
        notes.push("loss modulus E″ = E′ · tan δ".to_string());
    }
    let directive = table.directives.iter().find(|(_, k, _)| k == "temperature");
    let fixed = match (directive, temp) {
        (Some((line, _, _)), Some((c, _))) => {
            return Err(Error::input(
                Location::line(path, *line),
                format!(
                    "a '# temperature' line and a temperature column ('{}')",
                    table.header[c]
                ),
            )
            .with_hint("a file holds its temperature one way: remove the line, or the column"))
        }
        (Some((line, _, v)), None) => Some(temperature::parse(v).map_err(|e| {
            Error::input(Location::line(path, *line), format!("# temperature: {e}"))
                .with_hint("e.g. '# temperature: 25 C'")
        })?),
        _ => None,
    };
    let name = |c: usize| format!("'{}'", table.header[c]);
    let (fname, sname, lname) = (name(fc), name(sc), name(lc));
    let tname = temp.map(|(c, _)| name(c));
    let mut points = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let f = table.number(row, fc, &fname)? * ff;
        let hz = f / (2.0 * std::f64::consts::PI);
        let (lo, hi) = FREQUENCY_RANGE_HZ;
        if !(lo..=hi).contains(&hz) {
            return Err(Error::input(
                table.loc(row, fc),
                format!("frequency {hz:e} Hz is outside {lo:e} … {hi:e} Hz"),
            )
            .with_hint("frequencies are > 0; is the column's unit right (Hz, rad/s)?"));
        }
        let e1 = table.number(row, sc, &sname)? * sf;
        let v = table.number(row, lc, &lname)?;
        let e2 = match lcol {
            Col::TanDelta => {
                if !(v > 0.0 && v <= TAN_DELTA_MAX) {
                    return Err(Error::input(
                        table.loc(row, lc),
                        format!("tan δ must be in (0, {TAN_DELTA_MAX:e}], found {v}"),
                    )
                    .with_hint("tan δ = E″/E′ of a material that dissipates is > 0"));
                }
                v * e1
            }
            Col::Loss(f) => v * f,
            _ => unreachable!("the loss slot holds a loss or tan δ column"),
        };
        for (x, c, what) in [(e1, sc, "storage modulus"), (e2, lc, "loss modulus")] {
            if !(x > 0.0 && x <= MODULUS_MAX) {
                return Err(Error::input(
                    table.loc(row, c),
                    format!("{what} must be in (0, {MODULUS_MAX:e}] Pa, found {x:e} Pa"),
                )
                .with_hint(if x <= 0.0 {
                    "a modulus of a dissipating solid is > 0: the fit works on its logarithm; drop the point or check the column"
                } else {
                    "is the unit right? a column in Pa labelled GPa reads 10⁹ times too large"
                }));
            }
        }
        let t = match (temp, &tname) {
            (Some((c, Col::Temperature(s))), Some(tn)) => {
                let k = s.kelvin(table.number(row, c, tn)?);
                temperature::check(k).map_err(|e| Error::input(table.loc(row, c), e))?;
                Some(k)
            }
            _ => fixed,
        };
        points.push(Point {
            line: row.line(),
            omega: f,
            storage: e1,
            loss: e2,
            temperature: t,
        });
    }
    if points.is_empty() {
        return Err(
            Error::input(hline, "the file has a header but no data rows")
                .with_hint("add one line per measured frequency"),
        );
    }
    let file = path.display().to_string();
    let blocks = match temp {
        Some(_) => blocks(&points, path)?,
        None => vec![points],
    };
    let mut isotherms = Vec::with_capacity(blocks.len());
    for b in blocks {
        isotherms.push(order(b, &file, fc, &mut notes)?);
    }
    if !unused.is_empty() {
        notes.push(format!("columns not used: {}", unused.join(", ")));
    }
    let master = isotherms.len() == 1 && isotherms[0].temperature_k.is_none();
    let source = DmaSource {
        path: file,
        sha256: table.sha256.clone(),
        points: isotherms.iter().map(Isotherm::len).sum(),
        isotherms: if master { 0 } else { isotherms.len() },
        columns: table.header.clone(),
        notes,
    };
    Ok((isotherms, source))
}

/// The rows of a file with a temperature column in blocks of one temperature each
/// (consecutive rows within [`ISOTHERM_TOLERANCE_K`] of the block's mean); a
/// temperature that comes back after another is refused.
fn blocks(points: &[Point], path: &Path) -> Result<Vec<Vec<Point>>> {
    let mut out: Vec<Vec<Point>> = Vec::new();
    let mean = |b: &[Point]| b.iter().filter_map(|p| p.temperature).sum::<f64>() / b.len() as f64;
    for p in points {
        let t = p
            .temperature
            .expect("a temperature column gives every row one");
        match out.last_mut() {
            Some(b) if (mean(b) - t).abs() <= ISOTHERM_TOLERANCE_K => b.push(*p),
            _ => {
                if let Some(b) = out
                    .iter()
                    .find(|b| (mean(b) - t).abs() <= ISOTHERM_TOLERANCE_K)
                {
                    return Err(Error::input(
                        Location::line(path, p.line),
                        format!(
                            "temperature {} comes back: its isotherm is on lines {}–{}",
                            temperature::celsius(t),
                            b[0].line,
                            b[b.len() - 1].line
                        ),
                    )
                    .with_hint("keep each isotherm's rows together, one block per temperature"));
                }
                out.push(vec![*p]);
            }
        }
    }
    Ok(out)
}

/// The points of one block as an isotherm: frequencies strictly increasing (a
/// decreasing sweep reversed), or a master curve sorted by frequency.
fn order(mut b: Vec<Point>, file: &str, fc: usize, notes: &mut Vec<String>) -> Result<Isotherm> {
    let temperature_k = b[0]
        .temperature
        .map(|_| b.iter().filter_map(|p| p.temperature).sum::<f64>() / b.len() as f64);
    let at = |p: &Point| Location::at(file, p.line, fc + 1);
    match temperature_k {
        None => {
            if b.windows(2).any(|w| w[1].omega < w[0].omega) {
                b.sort_by(|x, y| x.omega.total_cmp(&y.omega));
                notes.push("master curve sorted by frequency".into());
            }
        }
        Some(t) => {
            if b.len() < 2 {
                return Err(Error::input(
                    Location::line(file, b[0].line),
                    format!(
                        "the isotherm at {} has one point: a sweep needs at least 2",
                        temperature::celsius(t)
                    ),
                )
                .with_hint(
                    "is the temperature column right? an isotherm's rows share one temperature",
                ));
            }
            let down = b[1].omega < b[0].omega;
            for w in b.windows(2) {
                let (p, q) = (&w[0], &w[1]);
                if q.omega == p.omega {
                    return Err(Error::input(
                        at(q),
                        format!("frequency repeats line {} in the isotherm at {}", p.line, temperature::celsius(t)),
                    )
                    .with_hint("an isotherm measures each frequency once: remove the repeated row (a master curve may repeat, an isotherm may not)"));
                }
                if (q.omega < p.omega) != down {
                    return Err(Error::input(
                        at(q),
                        format!(
                            "frequencies of the isotherm at {} go {} until line {}, then turn back",
                            temperature::celsius(t),
                            if down { "down" } else { "up" },
                            p.line
                        ),
                    )
                    .with_hint(
                        "an isotherm is one sweep, up or down in frequency: sort its rows",
                    ));
                }
            }
            if down {
                b.reverse();
                notes.push(format!(
                    "isotherm at {} swept from high to low frequency: read in increasing order",
                    temperature::celsius(t)
                ));
            }
        }
    }
    Ok(Isotherm {
        temperature_k,
        omega: b.iter().map(|p| p.omega).collect(),
        storage: b.iter().map(|p| p.storage).collect(),
        loss: b.iter().map(|p| p.loss).collect(),
        line: b.iter().map(|p| p.line).collect(),
        file: file.to_string(),
    })
}
