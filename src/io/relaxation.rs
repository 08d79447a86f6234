//! Stress-relaxation files → [`RelaxationData`] in SI.
//!
//! Header columns are `name_unit` (also `name [unit]` or `name (unit)`): one time
//! column (`time_s`, `time_ms`, `time_min`, `time_h`), one stress column
//! (`stress_<Pa|kPa|MPa>`, also `nominal_stress_…`, or `force_<N|mN|kN>` with a
//! reference area), and optionally one loading column that records the strain history
//! (`strain`, `strain_pct` or `stretch`). Times must start at ≥ 0 (the start of
//! loading) and increase strictly.

use super::table::{column_unit, normalise, split_header, vendor_role, ColumnMap, Table};
use crate::data::{STRESS_MAX, STRETCH_RANGE};
use crate::error::{Error, Location, Result};
use crate::material::viscoelastic::{History, Prony, Schedule};
use crate::units::Dimension;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Where relaxation data came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelaxationSource {
    /// Path as given by the user.
    pub path: String,
    /// SHA-256 of the file's bytes (hex).
    pub sha256: String,
    /// Number of points read.
    pub points: usize,
    /// First time (s).
    pub time_min_s: f64,
    /// Last time (s).
    pub time_max_s: f64,
    /// Columns as written in the header.
    pub columns: Vec<String>,
    /// Conversions applied on reading (e.g. force → stress).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub conversions: Vec<String>,
    /// What the reader did beyond reading (preamble skipped, units row read, columns
    /// not used).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// A relaxation curve in SI: nominal stress against time, with the recorded strain
/// history when the file has one.
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxationData {
    /// Times (s), strictly increasing, ≥ 0, measured from the start of loading.
    pub time: Vec<f64>,
    /// Nominal stress (Pa).
    pub stress: Vec<f64>,
    /// Engineering strain recorded at each time (from a strain or stretch column).
    pub strain: Option<Vec<f64>>,
    /// Source line of each point.
    pub line: Vec<usize>,
    /// The file.
    pub source: RelaxationSource,
}

impl RelaxationData {
    /// The domain of a relaxation curve, for data built without the reader (the
    /// estimator calls it): equal lengths, at least one point, times finite, ≥ 0,
    /// increasing and at most [`TIME_MAX_S`], stresses finite with |σ| ≤
    /// [`STRESS_MAX`], strains finite with 1 + ε in (0, [`STRETCH_RANGE`].1].
    pub fn check(&self) -> Result<()> {
        let n = self.time.len();
        let at = |i: usize| {
            let line = self.line.get(i).copied().unwrap_or(0);
            Location::line(&self.source.path, line)
        };
        if n == 0
            || self.stress.len() != n
            || self.line.len() != n
            || self.strain.as_ref().is_some_and(|e| e.len() != n)
        {
            return Err(Error::input(
                Location::file(&self.source.path),
                format!(
                    "a relaxation curve needs as many stresses, strains and lines as times ({n} times, {} stresses)",
                    self.stress.len()
                ),
            ));
        }
        for i in 0..n {
            let t = self.time[i];
            let prev = if i > 0 { self.time[i - 1] } else { -1.0 };
            if !(t.is_finite() && (0.0..=TIME_MAX_S).contains(&t) && t > prev) {
                return Err(Error::input(
                    at(i),
                    format!("time {t} s: times must be finite, increasing and within 0 … {TIME_MAX_S:e} s"),
                ));
            }
            let y = self.stress[i];
            if !(y.is_finite() && y.abs() <= STRESS_MAX) {
                return Err(Error::input(
                    at(i),
                    format!("stress {y} Pa: must be finite with |σ| ≤ {STRESS_MAX:e} Pa"),
                ));
            }
            if let Some(e) = self.strain.as_ref().map(|e| e[i]) {
                if !(e.is_finite() && e > -1.0 && 1.0 + e <= STRETCH_RANGE.1) {
                    return Err(Error::input(
                        at(i),
                        format!(
                            "strain {e}: must be finite with 1 + ε in (0, {}]",
                            STRETCH_RANGE.1
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// How to read a relaxation file.
#[derive(Debug, Clone, Copy, Default)]
pub struct RelaxationOptions {
    /// Reference cross-section (m²) for force columns.
    pub area: Option<f64>,
}

/// Longest plausible relaxation record (s): 30 years. A longer time is a unit error,
/// and times like 1e300 s leave the hereditary integrals no resolvable τ grid.
pub const TIME_MAX_S: f64 = 1e9;

const ACCEPTED: &str = "time_s|ms|min|h, stress_Pa|kPa|MPa (or nominal_stress_…), force_N with --area, and optionally strain, strain_pct or stretch";

/// Columns that take a `_unit` suffix.
const COLUMNS: &[&str] = &[
    "nominal_stress",
    "true_stress",
    "cauchy_stress",
    "stress",
    "force",
    "time",
    "strain",
];

#[derive(Debug, Clone, Copy, PartialEq)]
enum Col {
    Time(f64),
    Stress(f64),
    Strain(f64),
    Stretch,
}

/// The roles `--columns` may give a relaxation file's columns.
pub const ROLES: &[&str] = &["time", "stress", "force", "strain", "stretch"];

/// Read one relaxation file.
pub fn read(path: &Path, opts: &RelaxationOptions) -> Result<RelaxationData> {
    read_with(path, opts, &ColumnMap::default())
}

/// The role and unit of header field `h`: from `map` when it names the column, else
/// from its name (as dea-fit or a testing-machine program writes it).
fn role_of(h: &str, map: &ColumnMap) -> (String, Option<String>) {
    let (name, unit) = split_header(h, COLUMNS);
    match map.find(h) {
        Some((role, u)) => (role.to_string(), u.map(str::to_string).or(unit)),
        None => {
            let role = match vendor_role(&normalise(&name)) {
                Some("strain_pct") => return ("strain".into(), Some("%".into())),
                Some(r) => r.to_string(),
                None => name,
            };
            (role, unit)
        }
    }
}

/// Read one relaxation file, a testing machine's export included: a preamble above
/// the header and a units row under it ([`Table::parse_export`]; the header is the
/// first line naming a time and a stress or force column), the columns named by
/// `map` (`--columns`) or by the names testing-machine programs write.
pub fn read_with(path: &Path, opts: &RelaxationOptions, map: &ColumnMap) -> Result<RelaxationData> {
    let export = Table::read_export(path, &|fields| {
        let roles: Vec<String> = fields.iter().map(|f| role_of(f, map).0).collect();
        roles.iter().any(|r| r == "time")
            && roles
                .iter()
                .any(|r| ["stress", "nominal_stress", "force"].contains(&r.as_str()))
    })?;
    let mut data = from_table_with(&export.table, opts, map)?;
    let read = std::mem::take(&mut data.source.notes);
    data.source.notes = export.notes;
    data.source.notes.extend(read);
    Ok(data)
}

/// Interpret a parsed table as a relaxation curve.
pub fn from_table(table: &Table, opts: &RelaxationOptions) -> Result<RelaxationData> {
    from_table_with(table, opts, &ColumnMap::default())
}

/// Interpret a parsed table as a relaxation curve, the columns named by `map` or
/// their names ([`read_with`]).
pub fn from_table_with(
    table: &Table,
    opts: &RelaxationOptions,
    map: &ColumnMap,
) -> Result<RelaxationData> {
    let path = &table.path;
    map.check(table)?;
    let hloc = |c: usize| Location::at(path, table.header_line, c + 1);
    let mut time = None;
    let mut stress = None;
    let mut load = None;
    let mut conversions = Vec::new();
    let mut unused = Vec::new();
    for (c, h) in table.header.iter().enumerate() {
        let (name, u) = role_of(h, map);
        let col = match name.as_str() {
            "time" => Col::Time(column_unit(table, c, u.as_deref(), Dimension::Time)?),
            "stress" | "nominal_stress" | "engineering_stress" => {
                Col::Stress(column_unit(table, c, u.as_deref(), Dimension::Stress)?)
            }
            "force" => {
                let f = column_unit(table, c, u.as_deref(), Dimension::Force)?;
                let a = opts.area.ok_or_else(|| {
                    Error::input(
                        hloc(c),
                        format!("column '{h}' needs the reference cross-section to give a stress"),
                    )
                    .with_hint("pass --area, e.g. --area 22mm2")
                })?;
                conversions.push(format!("nominal stress = force / {a} m²"));
                Col::Stress(f / a)
            }
            "strain" => Col::Strain(match u.as_deref() {
                None | Some("-") | Some("1") => 1.0,
                Some("%") | Some("pct") | Some("percent") => 0.01,
                Some(other) => {
                    return Err(Error::input(
                        hloc(c),
                        format!("unknown unit '{other}' in column '{h}'"),
                    )
                    .with_hint("strain is a fraction ('strain') or a percentage ('strain_pct')"))
                }
            }),
            "stretch" | "lambda" => Col::Stretch,
            "true_stress" | "cauchy_stress" => return Err(Error::input(
                hloc(c),
                format!("column '{h}' holds true stress; relaxation fits use nominal stress"),
            )
            .with_hint(
                "convert to nominal stress (force / reference area) or give force_N with --area",
            )),
            _ if h.trim().is_empty() || h.trim().parse::<f64>().is_ok() => {
                return Err(table.unknown_column(c, ACCEPTED, "time_s,stress_kPa"))
            }
            _ => {
                unused.push(h.clone());
                continue;
            }
        };
        let slot = match col {
            Col::Time(_) => &mut time,
            Col::Stress(_) => &mut stress,
            Col::Strain(_) | Col::Stretch => &mut load,
        };
        if let Some((c0, _)) = *slot {
            return Err(table.second_column(
                c,
                c0,
                "keep one time, one stress (or force) and at most one strain or stretch column",
            ));
        }
        *slot = Some((c, col));
    }
    let hline = Location::line(path, table.header_line);
    let (tc, tf) = match time {
        Some((c, Col::Time(f))) => (c, f),
        _ => {
            return Err(Error::input(hline, "no time column").with_hint(missing(
                "name one column time_s, time_ms or time_min",
                &unused,
            )))
        }
    };
    let (sc, sf) = match stress {
        Some((c, Col::Stress(f))) => (c, f),
        _ => {
            return Err(Error::input(hline, "no stress column").with_hint(missing(
                "name one column stress_<Pa|kPa|MPa> or force_N (with --area)",
                &unused,
            )))
        }
    };
    let mut t = Vec::with_capacity(table.rows.len());
    let mut y = Vec::with_capacity(table.rows.len());
    let mut eps = Vec::new();
    let mut line = Vec::with_capacity(table.rows.len());
    // Column names for errors, made once rather than per row.
    let name = |c: usize| format!("'{}'", table.header[c]);
    let (tname, sname, lname) = (name(tc), name(sc), load.map(|(lc, _)| name(lc)));
    for row in &table.rows {
        let tv = table.number(row, tc, &tname)? * tf;
        if tv < 0.0 {
            return Err(Error::input(
                table.loc(row, tc),
                format!("time must be ≥ 0, found {}", table.field(row, tc)),
            )
            .with_hint("measure time from the start of loading (t = 0)"));
        }
        if tv > TIME_MAX_S {
            return Err(Error::input(
                table.loc(row, tc),
                format!("time {tv:e} s: a relaxation test does not last beyond {TIME_MAX_S:e} s (30 years)"),
            )
            .with_hint("is the time column's unit right (s, ms, min, h)?"));
        }
        if let Some(&prev) = t.last() {
            if tv <= prev {
                return Err(Error::input(
                    table.loc(row, tc),
                    format!(
                        "times must increase: expected more than {prev} s (line {}), found {tv} s",
                        line.last().copied().unwrap_or(0)
                    ),
                )
                .with_hint("sort the file by time and remove repeated rows"));
            }
        }
        let sv = table.number(row, sc, &sname)? * sf;
        if sv.abs() > STRESS_MAX {
            return Err(Error::input(
                table.loc(row, sc),
                format!("stress {sv:e} Pa: no elastomer test reaches {STRESS_MAX:e} Pa"),
            )
            .with_hint(
                "is the unit right? a column in Pa labelled MPa reads 10⁶ times too large",
            ));
        }
        if let (Some((lc, kind)), Some(lname)) = (load, &lname) {
            let v = table.number(row, lc, lname)?;
            let e = match kind {
                Col::Strain(f) => v * f,
                _ => {
                    if v <= 0.0 {
                        return Err(Error::input(
                            table.loc(row, lc),
                            format!("stretch must be > 0, found {v}"),
                        )
                        .with_hint("is this column a strain? name it 'strain' or 'strain_pct'"));
                    }
                    v - 1.0
                }
            };
            let stretch = 1.0 + e;
            if stretch > STRETCH_RANGE.1 {
                return Err(Error::input(
                    table.loc(row, lc),
                    format!(
                        "stretch {stretch}: a stretch above {} is not a relaxation test",
                        STRETCH_RANGE.1
                    ),
                )
                .with_hint(
                    "is this column a displacement, or a strain in %? name it 'strain_pct'",
                ));
            }
            if e <= -1.0 {
                return Err(Error::input(
                    table.loc(row, lc),
                    format!("strain must be > −1, found {e}"),
                ));
            }
            eps.push(e);
        }
        t.push(tv);
        y.push(sv);
        line.push(row.line());
    }
    if t.len() < 2 {
        return Err(Error::input(
            Location::line(path, line[0]),
            format!(
                "a relaxation curve needs at least 2 points, found {}",
                t.len()
            ),
        ));
    }
    if y.iter().all(|v| *v == 0.0) {
        return Err(Error::input(
            Location::at(path, line[0], sc + 1),
            "the stress is zero at every point: nothing to fit",
        )
        .with_hint("is the stress column in the right unit, or the right column?"));
    }
    Ok(RelaxationData {
        source: RelaxationSource {
            path: path.display().to_string(),
            sha256: table.sha256.clone(),
            points: t.len(),
            time_min_s: t[0],
            time_max_s: *t.last().expect("non-empty"),
            columns: table.header.clone(),
            conversions,
            notes: if unused.is_empty() {
                Vec::new()
            } else {
                vec![format!("columns not used: {}", unused.join(", "))]
            },
        },
        time: t,
        stress: y,
        strain: load.map(|_| eps),
        line,
    })
}

/// The hint for a missing column: `what`, and the columns that were not used.
fn missing(what: &str, unused: &[String]) -> String {
    if unused.is_empty() {
        what.to_string()
    } else {
        format!(
            "{what}, or name it with --columns (e.g. --columns time=Time:s,force=Load:N); not recognised: {}",
            unused.join(", ")
        )
    }
}

/// A synthetic relaxation test: known Prony constants, loading, sampling and noise.
#[derive(Debug, Clone)]
pub struct Synthetic {
    /// The true series (Pa per unit strain: the small-strain reading).
    pub prony: Prony,
    /// Held engineering strain ε0.
    pub strain: f64,
    /// Linear ramp duration from t = 0 (s); `None`: ideal step.
    pub ramp_time: Option<f64>,
    /// Sample times (s), increasing.
    pub times: Vec<f64>,
    /// Relative Gaussian noise (standard deviation as a fraction of the stress).
    pub noise: f64,
    /// Seed of the noise generator (ChaCha8).
    pub seed: u64,
    /// Write the strain history as a `strain` column.
    pub record_strain: bool,
}

/// Log-spaced times: `count` points from `t0` to `t1` (s), preceded by t = 0 when
/// `with_zero`.
pub fn log_times(t0: f64, t1: f64, count: usize, with_zero: bool) -> Vec<f64> {
    let (a, b) = (t0.ln(), t1.ln());
    let mut t: Vec<f64> = if with_zero { vec![0.0] } else { Vec::new() };
    t.extend((0..count).map(|i| (a + (b - a) * i as f64 / (count.max(2) - 1) as f64).exp()));
    t
}

impl Synthetic {
    /// The CSV text (`time_s,stress_kPa[,strain]`), the generating parameters written
    /// as `#` comments after `preamble` lines.
    pub fn csv(&self, preamble: &[&str]) -> Result<String> {
        use std::fmt::Write as _;
        let history = match self.ramp_time {
            Some(tr) => History::ramp(self.strain, tr),
            None => History::step(self.strain),
        };
        let sched = Schedule::new(&history, &self.times)?;
        let clean = self.prony.response(&sched);
        let (mut s, mut normal) = crate::io::synthetic_start(
            self.seed,
            preamble,
            "(small-strain reading, Pa per unit strain)",
            &self.prony,
        );
        let _ = writeln!(
            s,
            "# loading: strain {} {}",
            self.strain,
            match self.ramp_time {
                Some(tr) => format!("reached by a linear ramp over {tr} s from t = 0"),
                None => "applied as an ideal step at t = 0".into(),
            }
        );
        let _ = writeln!(
            s,
            "# noise: relative {} (Gaussian standard deviation), seed {} (ChaCha8)",
            self.noise, self.seed
        );
        let _ = writeln!(
            s,
            "time_s,stress_kPa{}",
            if self.record_strain { ",strain" } else { "" }
        );
        let stress: Vec<f64> = clean
            .iter()
            .map(|c| c * (1.0 + self.noise * normal()))
            .collect();
        super::finite_output(
            "the synthetic relaxation curve",
            self.times
                .iter()
                .zip(&stress)
                .flat_map(|(&t, &y)| [("time_s", t), ("stress_kPa", y / 1e3)]),
        )?;
        for (k, (&t, &y)) in self.times.iter().zip(&stress).enumerate() {
            let _ = write!(s, "{t:.6e},{:.6e}", y / 1e3);
            if self.record_strain {
                let _ = write!(s, ",{:.9}", sched.input()[k]);
            }
            s.push('\n');
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_headers() {
        let split = |h| split_header(h, COLUMNS);
        assert_eq!(split("stress_kPa"), ("stress".into(), Some("kPa".into())));
        assert_eq!(split("Time [ms]"), ("time".into(), Some("ms".into())));
        assert_eq!(split("time_min"), ("time".into(), Some("min".into())));
        assert_eq!(split("strain_pct"), ("strain".into(), Some("pct".into())));
        assert_eq!(split("stress"), ("stress".into(), None));
    }
}
