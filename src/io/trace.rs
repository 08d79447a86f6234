//! Actuator traces (one experiment per file) → [`Trace`] in SI.
//!
//! Header columns are `name_unit` (also `name [unit]`): `time_s|ms|…` and
//! `voltage_V|kV|mV` (the measured drive: the open-circuit voltage of the scene's
//! source, which becomes the scene's input), and at least one measured channel:
//! `contraction_um|mm|m` (shortening from the rest length, positive),
//! `length_mm|…`, `stretch` (thickness stretch λ), `capacitance_pF|nF|F`,
//! `current_uA|mA|A`, `force_N`. Times must be finite and strictly increasing;
//! irregular spacing (logging bursts) is normal. An empty cell of a measured channel
//! means "not logged at this row" (channels logged at lower rates) and is kept as a
//! missing value (NaN); an empty time or voltage is an error. Every value is checked
//! against the plausible range of its quantity ([`ChannelKind::domain`]), located at
//! its line and column.

use super::table::{column_unit, split_header, Table};
use crate::error::{Error, Location, Result};
use crate::sim::budget::{self, Domain};
use crate::sim::input::measured::Work;
use crate::sim::input::{Measured, Term, Waveform};
use crate::sim::scene::Scene;
use crate::sim::Sample;
use crate::units::Dimension;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Where a trace came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// Path as given by the user.
    pub path: String,
    /// SHA-256 of the file's bytes (hex).
    pub sha256: String,
    /// Rows read.
    pub rows: usize,
    /// Columns as written in the header.
    pub columns: Vec<String>,
}

/// What a measured channel holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ChannelKind {
    /// Shortening from the rest length under the load (m), positive when shorter.
    Contraction,
    /// Actuator length (m).
    Length,
    /// Thickness stretch λ (1).
    Stretch,
    /// Capacitance (F).
    Capacitance,
    /// Current into the actuator (A).
    Current,
    /// Force (N).
    Force,
}

/// Contraction: an actuator shortens by less than its length, below a metre.
const CONTRACTION: Domain = Domain {
    what: "contraction",
    unit: "m",
    min: -1.0,
    max: 1.0,
    zero: true,
    reason: "an actuator shortens by less than its length, below a metre (a column in m that holds µm numbers reads 10⁶ times too large)",
};
/// Thickness stretch.
const STRETCH: Domain = Domain {
    what: "stretch",
    unit: "",
    min: 0.05,
    max: 10.0,
    zero: false,
    reason: "a thickness stretch is near 1 (0.05 … 10); a contraction or a strain is not a stretch",
};
/// Capacitance of an actuator.
const CAPACITANCE: Domain = Domain {
    what: "capacitance",
    unit: "F",
    min: 1e-15,
    max: 1e-3,
    zero: false,
    reason: "DEA capacitances are pF to µF (a column in F that holds pF numbers reads 10¹² times too large)",
};
/// Current into an actuator.
const CURRENT: Domain = Domain {
    what: "current",
    unit: "A",
    min: -1.0,
    max: 1.0,
    zero: true,
    reason: "kV drives deliver µA to mA; 1 A at kilovolts is kilowatts (a column in A that holds µA numbers?)",
};

impl ChannelKind {
    /// Every kind, in the order of the docs.
    pub const ALL: [ChannelKind; 6] = [
        ChannelKind::Contraction,
        ChannelKind::Length,
        ChannelKind::Stretch,
        ChannelKind::Capacitance,
        ChannelKind::Current,
        ChannelKind::Force,
    ];

    /// The name used in headers, `--sigma` and `--channels`.
    pub fn name(self) -> &'static str {
        match self {
            ChannelKind::Contraction => "contraction",
            ChannelKind::Length => "length",
            ChannelKind::Stretch => "stretch",
            ChannelKind::Capacitance => "capacitance",
            ChannelKind::Current => "current",
            ChannelKind::Force => "force",
        }
    }

    /// The kind of a name (`contraction`, …), if any.
    pub fn parse(name: &str) -> Option<ChannelKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The SI unit of its values (`1` for a stretch).
    pub fn unit(self) -> &'static str {
        match self.dimension() {
            Some(d) => d.si(),
            None => "1",
        }
    }

    /// The dimension of its header unit (`None`: dimensionless).
    pub fn dimension(self) -> Option<Dimension> {
        match self {
            ChannelKind::Contraction | ChannelKind::Length => Some(Dimension::Length),
            ChannelKind::Stretch => None,
            ChannelKind::Capacitance => Some(Dimension::Capacitance),
            ChannelKind::Current => Some(Dimension::Current),
            ChannelKind::Force => Some(Dimension::Force),
        }
    }

    /// The plausible range of its values (SI), as in `sim::budget::TABLE`.
    pub fn domain(self) -> &'static Domain {
        match self {
            ChannelKind::Contraction => &CONTRACTION,
            ChannelKind::Length => &budget::LENGTH,
            ChannelKind::Stretch => &STRETCH,
            ChannelKind::Capacitance => &CAPACITANCE,
            ChannelKind::Current => &CURRENT,
            ChannelKind::Force => &budget::FORCE,
        }
    }

    /// The channel's value in a simulated sample (SI): contraction = rest length −
    /// length (the run starts at rest under the load), length, thickness stretch,
    /// capacitance, current. `None` for a force: the simulator drives a given load
    /// and computes no force.
    pub fn simulated(self, s: &Sample, rest_length_m: f64) -> Option<f64> {
        match self {
            ChannelKind::Contraction => Some(rest_length_m - s.length_m),
            ChannelKind::Length => Some(s.length_m),
            ChannelKind::Stretch => Some(s.stretch),
            ChannelKind::Capacitance => Some(s.capacitance_f),
            ChannelKind::Current => Some(s.current_a),
            ChannelKind::Force => None,
        }
    }
}

impl std::fmt::Display for ChannelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One measured channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// What it holds.
    pub kind: ChannelKind,
    /// One value per trace row (SI); NaN where the row has no value.
    pub values: Vec<f64>,
    /// Its header as written.
    pub header: String,
}

/// One experiment: the measured drive voltage and channels at the logged times.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// The file.
    pub provenance: Provenance,
    /// Times (s), finite and strictly increasing (any origin).
    pub time_s: Vec<f64>,
    /// Drive voltage (V) at each time.
    pub voltage_v: Vec<f64>,
    /// Measured channels, in header order, one kind at most once.
    pub channels: Vec<Channel>,
    /// Source line of each row.
    pub line: Vec<usize>,
}

const ACCEPTED: &str = "time_s|ms, voltage_V|kV, and any of contraction_um|mm|m, length_mm, stretch, capacitance_pF|nF|F, current_uA|mA|A, force_N";
const EXAMPLE: &str = "time_s,voltage_V,contraction_um,capacitance_pF";
/// Columns that take a `_unit` suffix.
const COLUMNS: &[&str] = &[
    "time",
    "voltage",
    "contraction",
    "length",
    "stretch",
    "capacitance",
    "current",
    "force",
];

/// The first voltage, as a share of the largest |V| of the trace, above which the
/// trace does not start at rest (the run starts at rest under the load at 0 V).
pub const START_SHARE: f64 = 0.05;

/// Read one trace file.
pub fn read(path: &Path) -> Result<Trace> {
    from_table(&Table::read(path)?)
}

/// Interpret a parsed table as a trace.
pub fn from_table(table: &Table) -> Result<Trace> {
    let path = &table.path;
    let hloc = |c: usize| Location::at(path, table.header_line, c + 1);
    let mut time = None;
    let mut voltage = None;
    // (column, factor, kind)
    let mut chans: Vec<(usize, f64, ChannelKind)> = Vec::new();
    for (c, h) in table.header.iter().enumerate() {
        let (name, u) = split_header(h, COLUMNS);
        let u = u.as_deref();
        match name.as_str() {
            "time" | "voltage" => {
                let (slot, dim) = match name.as_str() {
                    "time" => (&mut time, Dimension::Time),
                    _ => (&mut voltage, Dimension::Voltage),
                };
                if let Some((c0, _)) = *slot {
                    return Err(second(table, c, c0));
                }
                *slot = Some((c, column_unit(table, c, u, dim)?));
            }
            other => {
                let Some(kind) = ChannelKind::parse(other) else {
                    return Err(table.unknown_column(c, ACCEPTED, EXAMPLE));
                };
                let f = match kind.dimension() {
                    Some(d) => column_unit(table, c, u, d)?,
                    None => match u {
                        None | Some("1") | Some("-") => 1.0,
                        Some(o) => {
                            return Err(Error::input(
                                hloc(c),
                                format!("unknown unit '{o}' in column '{h}'"),
                            )
                            .with_hint("a stretch has no unit: name the column 'stretch'"))
                        }
                    },
                };
                if let Some(&(c0, _, _)) = chans.iter().find(|x| x.2 == kind) {
                    return Err(second(table, c, c0));
                }
                chans.push((c, f, kind));
            }
        }
    }
    let hline = Location::line(path, table.header_line);
    let Some((tc, tf)) = time else {
        return Err(Error::input(hline, "no time column")
            .with_hint(format!("name one column time_s or time_ms, e.g. {EXAMPLE}")));
    };
    let Some((vc, vf)) = voltage else {
        return Err(Error::input(hline, "no voltage column").with_hint(
            "name the measured drive voltage_V or voltage_kV: it becomes the scene's input",
        ));
    };
    if chans.is_empty() {
        return Err(Error::input(hline, "no measured channel besides the voltage")
            .with_hint(format!("add at least one of contraction_um, length_mm, stretch, capacitance_pF, current_uA, force_N, e.g. {EXAMPLE}")));
    }
    let rows = table.rows.len();
    let mut t: Vec<f64> = Vec::with_capacity(rows);
    let mut v = Vec::with_capacity(rows);
    let mut line: Vec<usize> = Vec::with_capacity(rows);
    let mut values: Vec<Vec<f64>> = vec![Vec::with_capacity(rows); chans.len()];
    let plausible = |dom: &Domain, row: &crate::io::table::Row, c: usize, x: f64| {
        dom.check(&table.header[c], x)
            .map_err(|e| Error::input(table.loc(row, c), e.msg).with_hint(e.hint))
    };
    // Column names for errors, made once rather than per row.
    let names: Vec<String> = table.header.iter().map(|h| format!("'{h}'")).collect();
    for row in &table.rows {
        let need = |c: usize| {
            table.number(row, c, &names[c]).map_err(|e| {
                match table.field(row, c).is_empty() {
                    true => e.with_hint("every row needs a time and a voltage; leave only measured channels empty where they were not logged"),
                    false => e,
                }
            })
        };
        let tv = plausible(&budget::INSTANT, row, tc, need(tc)? * tf)?;
        if let (Some(&prev), Some(&pl)) = (t.last(), line.last()) {
            if tv == prev {
                return Err(Error::input(
                    table.loc(row, tc),
                    format!("time {tv} s repeats line {pl}"),
                )
                .with_hint("remove the repeated row (times must increase strictly)"));
            }
            if tv < prev {
                return Err(Error::input(
                    table.loc(row, tc),
                    format!("times must increase: expected more than {prev} s (line {pl}), found {tv} s"),
                )
                .with_hint("sort the file by time"));
            }
        }
        v.push(plausible(&budget::VOLTAGE, row, vc, need(vc)? * vf)?);
        for (k, &(c, f, kind)) in chans.iter().enumerate() {
            let x = match table.field(row, c).is_empty() {
                true => f64::NAN,
                false => {
                    let x = table.number(row, c, &names[c])? * f;
                    plausible(kind.domain(), row, c, x)?
                }
            };
            values[k].push(x);
        }
        t.push(tv);
        line.push(row.line());
    }
    if t.len() < 2 {
        return Err(Error::input(
            Location::line(path, line[0]),
            "a trace needs at least 2 rows",
        )
        .with_hint("one row per logged time"));
    }
    budget::SPAN
        .check("time span", t[t.len() - 1] - t[0])
        .map_err(|e| {
            Error::input(Location::at(path, line[line.len() - 1], tc + 1), e.msg).with_hint(e.hint)
        })?;
    for (k, &(c, _, _)) in chans.iter().enumerate() {
        if values[k].iter().all(|x| x.is_nan()) {
            return Err(Error::input(
                hloc(c),
                format!("column '{}' holds no value", table.header[c]),
            )
            .with_hint("drop the column or fill in the logged values"));
        }
    }
    Ok(Trace {
        provenance: Provenance {
            path: path.display().to_string(),
            sha256: table.sha256.clone(),
            rows: t.len(),
            columns: table.header.clone(),
        },
        channels: chans
            .iter()
            .zip(values)
            .map(|(&(c, _, kind), values)| Channel {
                kind,
                values,
                header: table.header[c].clone(),
            })
            .collect(),
        time_s: t,
        voltage_v: v,
        line,
    })
}

fn second(table: &Table, c: usize, c0: usize) -> Error {
    Error::input(
        Location::at(&table.path, table.header_line, c + 1),
        format!(
            "a second column of the same kind, '{}' (column {} is '{}')",
            table.header[c],
            c0 + 1,
            table.header[c0]
        ),
    )
    .with_hint("keep one time, one voltage and one column per measured channel")
}

impl Trace {
    /// The channel of a kind, if measured.
    pub fn channel(&self, kind: ChannelKind) -> Option<&Channel> {
        self.channels.iter().find(|c| c.kind == kind)
    }

    /// The measured drive as a smooth input with its real corners
    /// (`sim::input::measured`), on the trace's times shifted to start at 0,
    /// fitted by `deadline` (None: no limit; past it, an error with a hint).
    pub fn input(&self, deadline: Option<Instant>) -> Result<Measured> {
        let t0 = self.time_s[0];
        let t: Vec<f64> = self.time_s.iter().map(|t| t - t0).collect();
        let work = Work::until(deadline);
        Measured::fit_with(&t, &self.voltage_v, &work).map_err(|e| {
            let err = Error::input(
                Location::file(&self.provenance.path),
                format!("the voltage: {e}"),
            );
            match deadline.is_some_and(|d| Instant::now() > d) {
                true => err.with_hint(
                    "give a longer time budget (identify --max-time) or a shorter trace",
                ),
                false => err,
            }
        })
    }

    /// `base` driven by this trace: the input replaced by the measured voltage
    /// ([`Trace::input`]), `time.span` = last − first time and `time.samples` the
    /// trace's times after the first, shifted so that the first is 0. Then
    /// `sim::simulate(&scene, …).samples[i]` (samples[0] is the t = 0 state) lines
    /// up with trace row i.
    ///
    /// The run starts at rest under the load at 0 V (the first voltage then applies
    /// at t = 0): a trace whose first voltage exceeds [`START_SHARE`] of its largest
    /// |V| (and 3 noise σ) did not start at rest and is refused. A base scene with
    /// a closed loop is refused too: a measured voltage replaces the controller.
    /// The measured drive is fitted by `deadline` ([`Trace::input`]).
    pub fn scene(&self, base: &Scene, deadline: Option<Instant>) -> Result<Scene> {
        let file = &self.provenance.path;
        if base.control.is_some() {
            return Err(Error::settings(format!(
                "scene '{}' has a [control] loop; the trace {file} gives the voltage itself",
                base.name
            ))
            .with_hint("use a scene without [control]: the measured drive becomes its input"));
        }
        let input = self.input(deadline)?;
        let vmax = self.voltage_v.iter().fold(0.0, |a: f64, v| a.max(v.abs()));
        let v0 = self.voltage_v[0];
        if v0.abs() > (START_SHARE * vmax).max(3.0 * input.noise()) {
            let vcol = self
                .provenance
                .columns
                .iter()
                .position(|h| split_header(h, COLUMNS).0 == "voltage")
                .map_or(1, |c| c + 1);
            return Err(Error::input(
                Location::at(file, self.line[0], vcol),
                format!(
                    "the trace starts at {v0} V, {:.0} % of its largest |V|: the simulation starts at rest under the load at 0 V",
                    100.0 * v0.abs() / vmax
                ),
            )
            .with_hint("start the log before the drive is switched on (at 0 V and at rest)"));
        }
        let t0 = self.time_s[0];
        let mut scene = base.clone();
        scene.input = Waveform {
            terms: vec![Term::Measured(Arc::new(input))],
        };
        scene.time.span = self.time_s[self.time_s.len() - 1] - t0;
        scene.time.samples = self.time_s[1..].iter().map(|t| t - t0).collect();
        Ok(scene)
    }
}
