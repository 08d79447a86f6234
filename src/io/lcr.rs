//! LCR-meter and impedance-analyser exports → a frequency sweep of complex
//! admittances, in SI.
//!
//! Three families are read:
//! * Keysight/Agilent E4990A-style files: `!` header lines, then `BEGIN CH1_DATA`,
//!   a header like `Frequency(Hz), R(Ohm)-data, X(Ohm)-data`, data lines such as
//!   `+2.00000000000e+001, +9.15e-002, +1.24e+000`, and `END` (CRLF allowed). The
//!   first block is read; further blocks are reported in the notes.
//! * E4980A-style data lines `<A>,<B>,<status>[,<bin>]` without a header. The pair
//!   comes from `--pair` or a `# function: CPD` comment, the frequencies from
//!   `--frequencies` or a `# frequencies: 100Hz, 1kHz, …` comment. Points with a
//!   status other than 0 or the overload sentinel 9.9E37 are dropped and counted.
//! * Hioki-style and plain CSV (`,` `;` or tab; a preamble of instrument lines
//!   before the header is skipped): a frequency column plus the columns of at least
//!   one standard pair (Cp–D, Cp–Rp, Cp–G, Cp–Q, Cs–D, Cs–Rs, Cs–Q, Z–θ, R–X, G–B,
//!   Y–θ, Ls–Rs, Lp–Rp). Units come from the header (`Cp(F)`, `Cp [pF]`, `Cp_pF`);
//!   values may carry an SI prefix (`15.75p`).

use super::table::{Row, Table};
use crate::error::{Error, Location, Result};
use crate::material::check::fmt_g;
use crate::material::dielectric::Pair;
use crate::units::{parse_engineering, parse_quantity, CountRange, Dimension, MAX_POINTS};
use nalgebra::Complex;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Values at or above this are the E4980A's overload sentinel (9.9E37).
pub const OVERLOAD: f64 = 9.9e37;

/// Export family a file was read as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// E4990A-style `!` header with `BEGIN`/`END` blocks.
    E4990a,
    /// E4980A-style headerless `<A>,<B>,<status>` lines.
    E4980a,
    /// CSV with a header (Hioki-style or plain).
    Csv,
}

impl std::fmt::Display for Format {
    /// The name the JSON uses (`e4990a`, `e4980a`, `csv`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Format::E4990a => "e4990a",
            Format::E4980a => "e4980a",
            Format::Csv => "csv",
        })
    }
}

/// The most negative dissipation factor D = G/|B| read as measurement noise: an LCR
/// meter's D accuracy is about ±5e-4 to ±1e-3 (E4980A basic accuracy), so a D just
/// below zero on a low-loss coupon is noise (the analysis warns), while anything
/// more negative is a sign error in the data.
pub const D_NOISE: f64 = 1e-3;

/// Refuse a point with clearly negative loss (G < 0: D < −[`D_NOISE`], θ beyond
/// −90°): a passive sample dissipates power, it cannot deliver it.
fn passive(path: &Path, line: usize, f: f64, y: Complex<f64>) -> Result<()> {
    if !(y.re.is_finite() && y.im.is_finite()) {
        return Err(Error::input(
            Location::line(path, line),
            format!(
                "the admittance at {f} Hz is not finite ({} + {}j S)",
                y.re, y.im
            ),
        )
        .with_hint("a value on this line overflows or is infinite; check its unit prefix"));
    }
    let d = y.re / y.im.abs();
    if y.re < 0.0 && d < -D_NOISE {
        let theta = y.im.atan2(y.re).to_degrees();
        return Err(Error::input(
            Location::line(path, line),
            format!(
                "negative loss at {f} Hz: D = {d:.4} (conductance G = {:.4e} S < 0, impedance angle {:.2}° beyond ±90°); a passive sample dissipates, D ≥ 0",
                y.re,
                -theta
            ),
        )
        .with_hint("check the sign of the D, Rp or θ column (a capacitor's impedance angle is about −89°, not −91°) and the open/short compensation"));
    }
    Ok(())
}

/// How to read exports whose files do not say everything.
#[derive(Debug, Clone, Default)]
pub struct LcrOptions {
    /// The pair the meter measured (needed for headerless E4980A data); the bool is
    /// true when angles are in degrees.
    pub pair: Option<(Pair, bool)>,
    /// The frequency list (Hz) of headerless data.
    pub frequencies: Option<Vec<f64>>,
}

/// One frequency point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LcrPoint {
    /// Frequency (Hz).
    pub freq: f64,
    /// Complex admittance G + jB (S).
    pub y: Complex<f64>,
    /// Line of the file.
    pub line: usize,
}

/// A parsed sweep with provenance.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The file.
    pub path: PathBuf,
    /// SHA-256 of its bytes.
    pub sha256: String,
    /// Export family.
    pub format: Format,
    /// Pair the values were given as.
    pub pair: Pair,
    /// Instrument line (E4990A `!` header), if any.
    pub instrument: Option<String>,
    /// Columns used, as written.
    pub columns: Vec<String>,
    /// Points in increasing frequency.
    pub points: Vec<LcrPoint>,
    /// What the reader did (skipped lines, dropped points, assumed units).
    pub notes: Vec<String>,
}

/// Read one export file.
pub fn read(path: &Path, opts: &LcrOptions) -> Result<Sweep> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &bytes, opts)
}

/// Parse export bytes that came from `path`.
pub fn parse(path: &Path, bytes: &[u8], opts: &LcrOptions) -> Result<Sweep> {
    let Ok(text) = std::str::from_utf8(bytes) else {
        // The table reader owns the located "not UTF-8" message.
        return Err(Table::parse(path, bytes)
            .err()
            .unwrap_or_else(|| Error::input(Location::file(path), "the file is not UTF-8 text")));
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines: Vec<&str> = text.lines().collect();
    let sha = super::sha256_hex(bytes);
    let first = lines
        .iter()
        .position(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some(first) = first else {
        return Err(
            Error::input(Location::file(path), "the file holds no data").with_hint(
                "an export needs a frequency column and one measured pair, e.g. freq_Hz,Cp_pF,D",
            ),
        );
    };
    let is_block = lines.iter().any(|l| {
        let t = l.trim_start();
        t.starts_with('!') || t.to_ascii_uppercase().starts_with("BEGIN")
    });
    let mut sweep = if is_block {
        read_e4990a(path, &lines, opts)?
    } else if lines[first]
        .split([',', ';', '\t'])
        .next()
        .and_then(|f| parse_engineering(f, ""))
        .is_some()
    {
        read_e4980a(path, &lines, opts)?
    } else {
        read_csv(path, &lines, first, opts, Format::Csv, Vec::new())?
    };
    sweep.sha256 = sha;
    order_frequencies(&mut sweep)?;
    Ok(sweep)
}

/// Strictly increasing frequencies; a wholly decreasing sweep is reversed.
fn order_frequencies(s: &mut Sweep) -> Result<()> {
    let p = &s.points;
    if p.len() > 1 && p.windows(2).all(|w| w[1].freq < w[0].freq) {
        s.points.reverse();
        s.notes
            .push("the sweep runs from high to low frequency; it was reversed".into());
        return Ok(());
    }
    for w in s.points.windows(2) {
        if w[1].freq <= w[0].freq {
            return Err(Error::input(
                Location::line(&s.path, w[1].line),
                format!(
                    "frequency not increasing: {} Hz follows {} Hz (line {})",
                    w[1].freq, w[0].freq, w[0].line
                ),
            )
            .with_hint("one sweep per file, each frequency once, in increasing (or wholly decreasing) order"));
        }
    }
    Ok(())
}

fn read_e4990a(path: &Path, lines: &[&str], opts: &LcrOptions) -> Result<Sweep> {
    let instrument = lines
        .iter()
        .find_map(|l| l.trim().strip_prefix('!'))
        .map(|s| s.trim().to_string());
    let begins: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].trim().to_ascii_uppercase().starts_with("BEGIN"))
        .collect();
    let Some(&begin) = begins.first() else {
        return Err(Error::input(
            Location::file(path),
            "'!' header lines but no BEGIN … END data block",
        )
        .with_hint("an E4990A export holds a 'BEGIN CH1_DATA' line, a header, data and 'END'"));
    };
    let end = (begin + 1..lines.len())
        .find(|&i| lines[i].trim().eq_ignore_ascii_case("END"))
        .ok_or_else(|| {
            Error::input(
                Location::line(path, begin + 1),
                format!("'{}' has no matching END", lines[begin].trim()),
            )
            .with_hint("the export is truncated: save it again from the instrument")
        })?;
    let header = (begin + 1..end)
        .find(|&i| !lines[i].trim().is_empty())
        .ok_or_else(|| {
            Error::input(
                Location::line(path, begin + 1),
                "empty data block: no header and no data between BEGIN and END",
            )
        })?;
    let mut notes = Vec::new();
    if begins.len() > 1 {
        notes.push(format!(
            "the file holds {} data blocks; the first ('{}', line {}) was read",
            begins.len(),
            lines[begin].trim(),
            begin + 1
        ));
    }
    // Keep only the block (blank the rest, so line numbers stay those of the file).
    let kept: Vec<&str> = (0..lines.len())
        .map(|i| if i >= header && i < end { lines[i] } else { "" })
        .collect();
    read_csv(path, &kept, header, opts, Format::E4990a, notes).map(|mut s| {
        s.instrument = instrument;
        s
    })
}

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Freq,
    Cp,
    Cs,
    Lp,
    Ls,
    D,
    Q,
    Rp,
    Rs,
    R,
    X,
    Z,
    ThetaZ,
    G,
    B,
    Y,
    ThetaY,
}

impl Kind {
    fn of(name: &str) -> Option<Kind> {
        let n: String = name
            .to_lowercase()
            .replace("-data", "")
            .chars()
            .filter(|c| !matches!(c, ' ' | '|' | '-' | '_' | '.'))
            .collect();
        Some(match n.as_str() {
            "frequency" | "freq" | "f" => Kind::Freq,
            "cp" => Kind::Cp,
            "cs" => Kind::Cs,
            "lp" => Kind::Lp,
            "ls" => Kind::Ls,
            "d" | "df" | "tand" | "tanδ" | "tandelta" | "dissipation" => Kind::D,
            "q" => Kind::Q,
            "rp" => Kind::Rp,
            "rs" | "esr" => Kind::Rs,
            "r" => Kind::R,
            "x" => Kind::X,
            "z" | "impedance" => Kind::Z,
            "theta" | "θ" | "phase" | "thetaz" | "θz" | "phasez" | "thetazdeg" => Kind::ThetaZ,
            "g" => Kind::G,
            "b" => Kind::B,
            "y" | "admittance" => Kind::Y,
            "thetay" | "θy" | "phasey" => Kind::ThetaY,
            _ => return None,
        })
    }

    fn dimension(self) -> Option<Dimension> {
        Some(match self {
            Kind::Freq => Dimension::Frequency,
            Kind::Cp | Kind::Cs => Dimension::Capacitance,
            Kind::Lp | Kind::Ls => Dimension::Inductance,
            Kind::Rp | Kind::Rs | Kind::R | Kind::X | Kind::Z => Dimension::Resistance,
            Kind::G | Kind::B | Kind::Y => Dimension::Conductance,
            Kind::ThetaZ | Kind::ThetaY => Dimension::Angle,
            Kind::D | Kind::Q => return None,
        })
    }
}

/// Pairs in order of preference and the two column kinds each needs.
const PAIRS: [(Pair, Kind, Kind); 13] = [
    (Pair::CpD, Kind::Cp, Kind::D),
    (Pair::CpRp, Kind::Cp, Kind::Rp),
    (Pair::CpG, Kind::Cp, Kind::G),
    (Pair::CpQ, Kind::Cp, Kind::Q),
    (Pair::CsD, Kind::Cs, Kind::D),
    (Pair::CsRs, Kind::Cs, Kind::Rs),
    (Pair::CsQ, Kind::Cs, Kind::Q),
    (Pair::ZTheta, Kind::Z, Kind::ThetaZ),
    (Pair::RX, Kind::R, Kind::X),
    (Pair::GB, Kind::G, Kind::B),
    (Pair::YTheta, Kind::Y, Kind::ThetaY),
    (Pair::LsRs, Kind::Ls, Kind::Rs),
    (Pair::LpRp, Kind::Lp, Kind::Rp),
];

/// Split `Cp(F)`, `Cp [pF]`, `R(Ohm)-data`, `Cp_pF` into (name, unit).
fn split_header(h: &str) -> (String, Option<String>) {
    let h = h.trim();
    let h = h
        .strip_suffix("-data")
        .or_else(|| h.strip_suffix("-DATA"))
        .unwrap_or(h);
    if let Some(open) = h.find(['(', '[']) {
        let close = h[open..]
            .find([')', ']'])
            .map(|c| open + c)
            .unwrap_or(h.len());
        let unit = h[open + 1..close].trim().to_string();
        let name = format!("{}{}", &h[..open], h.get(close + 1..).unwrap_or(""));
        return (
            name.trim().to_string(),
            Some(unit).filter(|u| !u.is_empty()),
        );
    }
    if let Some((name, unit)) = h.rsplit_once('_') {
        if Kind::of(name).is_some() && Kind::of(h).is_none() {
            return (name.to_string(), Some(unit.to_string()));
        }
    }
    (h.to_string(), None)
}

struct Column {
    col: usize,
    factor: f64,
    /// SI symbol a value may carry after its prefix (`15.7pF`).
    symbol: &'static str,
}

fn read_csv(
    path: &Path,
    lines: &[&str],
    first: usize,
    opts: &LcrOptions,
    format: Format,
    mut notes: Vec<String>,
) -> Result<Sweep> {
    // The header is the first line naming a frequency column; anything before it
    // (instrument preamble) is skipped ([`Table::parse_export`]).
    let is_freq = |f: &str| Kind::of(&split_header(f).0) == Some(Kind::Freq);
    let names_freq = |l: &&str| {
        !l.trim_start().starts_with('#')
            && l.split([',', ';', '\t'])
                .any(|f| is_freq(f.trim().trim_matches('"')))
    };
    let export = lines[first..]
        .iter()
        .any(names_freq)
        .then(|| {
            let text = lines.join("\n");
            Table::parse_export(path, text.as_bytes(), &|fields: &[&str]| {
                fields.iter().any(|f| is_freq(f))
            })
        })
        .transpose()?
        .filter(|e| e.table.header.iter().any(|h| is_freq(h)));
    let Some(export) = export else {
        return Err(Error::input(
            Location::line(path, first + 1),
            format!("no frequency column: found '{}'", lines[first].trim()),
        )
        .with_hint(
            "name the columns, e.g. 'freq_Hz,Cp_pF,D' or 'Frequency(Hz), R(Ohm)-data, X(Ohm)-data'",
        ));
    };
    let table = export.table;
    notes.extend(export.notes);
    let hloc = |c: usize| Location::at(path, table.header_line, c + 1);

    let mut cols: Vec<(Kind, Column, Option<String>)> = Vec::new();
    let mut ignored = Vec::new();
    for (c, h) in table.header.iter().enumerate() {
        let (name, unit) = split_header(h);
        let Some(kind) = Kind::of(&name) else {
            ignored.push(h.clone());
            continue;
        };
        if cols.iter().any(|(k, _, _)| *k == kind) {
            return Err(
                Error::input(hloc(c), format!("a second '{name}' column ('{h}')"))
                    .with_hint("keep one column per quantity"),
            );
        }
        let factor = match (kind.dimension(), unit.as_deref()) {
            (None, None | Some("-") | Some("1")) => 1.0,
            (None, Some("%")) => 0.01,
            (None, Some(u)) => {
                return Err(Error::input(
                    hloc(c),
                    format!("'{name}' is dimensionless, found unit '{u}'"),
                )
                .with_hint("write D or Q without a unit (or with %)"))
            }
            (Some(Dimension::Angle), None) => {
                notes.push(format!("column '{h}' has no unit: read as degrees"));
                PI / 180.0
            }
            (Some(_), None) => 1.0,
            (Some(d), Some(u)) => d.factor(u).ok_or_else(|| {
                Error::input(hloc(c), format!("unknown unit '{u}' in column '{h}'"))
                    .with_hint(format!("expected one of {}", d.accepted()))
            })?,
        };
        cols.push((
            kind,
            Column {
                col: c,
                factor,
                symbol: kind.dimension().map(Dimension::si).unwrap_or(""),
            },
            unit,
        ));
    }
    let find = |k: Kind| cols.iter().find(|(kk, _, _)| *kk == k).map(|(_, c, _)| c);
    let freq = find(Kind::Freq).expect("the header line names a frequency column");
    let available: Vec<Pair> = PAIRS
        .iter()
        .filter(|(_, a, b)| find(*a).is_some() && find(*b).is_some())
        .map(|p| p.0)
        .collect();
    let pair = match opts.pair {
        Some((p, _)) if available.contains(&p) => p,
        Some((p, _)) => {
            return Err(Error::input(
                Location::line(path, table.header_line),
                format!(
                    "--pair {} asked for, but the header has no such columns",
                    p.name()
                ),
            )
            .with_hint(format!(
                "pairs in this file: {}",
                names(&available).unwrap_or("none".into())
            )))
        }
        None => *available.first().ok_or_else(|| {
            let magnitude_only = find(Kind::Z).is_some() || find(Kind::Y).is_some();
            Error::input(
                Location::line(path, table.header_line),
                if magnitude_only {
                    "magnitude only: |Z| (or |Y|) without a phase cannot give Cp and D".to_string()
                } else {
                    format!(
                        "no measured pair in the header '{}'",
                        table.header.join(", ")
                    )
                },
            )
            .with_hint(
                "export one of Cp–D, Cp–Rp, Cs–D, Cs–Rs, Z–θ, R–X, G–B (with units in the header)",
            )
        })?,
    };
    let (_, ka, kb) = *PAIRS.iter().find(|p| p.0 == pair).expect("listed");
    let (ca, cb) = (find(ka).expect("available"), find(kb).expect("available"));
    if available.len() > 1 {
        notes.push(format!(
            "several pairs in the file ({}); {} was used",
            names(&available).unwrap_or_default(),
            pair.name()
        ));
    }
    if !ignored.is_empty() {
        notes.push(format!("columns not used: {}", ignored.join(", ")));
    }
    let mut points = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let f = value(&table, row, freq, "frequency")?;
        check_frequency(&table, row, freq.col, f)?;
        let a = value(&table, row, ca, &table.header[ca.col])?;
        let b = value(&table, row, cb, &table.header[cb.col])?;
        let y = pair.to_admittance(a, b, 2.0 * PI * f);
        passive(path, row.line(), f, y)?;
        points.push(LcrPoint {
            freq: f,
            y,
            line: row.line(),
        });
    }
    Ok(Sweep {
        path: path.to_path_buf(),
        sha256: table.sha256.clone(),
        format,
        pair,
        instrument: None,
        columns: [freq.col, ca.col, cb.col]
            .iter()
            .map(|&c| table.header[c].clone())
            .collect(),
        points,
        notes,
    })
}

fn names(pairs: &[Pair]) -> Option<String> {
    (!pairs.is_empty()).then(|| {
        pairs
            .iter()
            .map(|p| p.name())
            .collect::<Vec<_>>()
            .join(", ")
    })
}

fn check_frequency(table: &Table, row: &Row, col: usize, f: f64) -> Result<()> {
    frequency_problem(f).map_or(Ok(()), |(msg, hint)| {
        Err(Error::input(table.loc(row, col), msg).with_hint(hint))
    })
}

/// Lowest and highest frequency (Hz) any dielectric measurement reaches: broadband
/// dielectric spectrometers start at a few µHz, network analysers end near 100 GHz.
/// LCR meters and impedance analysers (E4980A 20 Hz–2 MHz, E4990A 20 Hz–120 MHz)
/// lie well inside.
pub const FREQUENCY_RANGE_HZ: [f64; 2] = [1e-6, 1e12];

/// Why a frequency cannot be a measured one (message, hint), or None.
fn frequency_problem(f: f64) -> Option<(String, &'static str)> {
    let [lo, hi] = FREQUENCY_RANGE_HZ;
    if !(f > 0.0 && f.is_finite()) {
        Some((
            format!("frequency must be > 0 Hz, found {f}"),
            "the first column is the frequency of each point",
        ))
    } else if !(lo..=hi).contains(&f) {
        Some((
            format!(
                "frequency {f:e} Hz is outside any dielectric measurement ({lo:e} … {hi:e} Hz)"
            ),
            "is the frequency column's unit right (Hz, kHz, MHz)?",
        ))
    } else {
        None
    }
}

/// A located number in SI: engineering notation, SI prefixes, decimal comma.
fn value(table: &Table, row: &Row, c: &Column, what: &str) -> Result<f64> {
    let raw = table.field(row, c.col);
    let text = if raw.contains(',') && !raw.contains('.') {
        Cow::Owned(raw.replace(',', "."))
    } else {
        Cow::Borrowed(raw)
    };
    let v = parse_engineering(&text, c.symbol)
        .or_else(|| parse_engineering(&text, "Ohm"))
        .ok_or_else(|| {
            Error::input(
                table.loc(row, c.col),
                if raw.is_empty() {
                    format!("{what} is empty; expected a number")
                } else {
                    format!("expected a number for {what}, found '{raw}'")
                },
            )
        })?;
    if v.abs() >= OVERLOAD {
        return Err(Error::input(
            table.loc(row, c.col),
            format!("{what} is the overload sentinel {raw}: the meter was out of range"),
        )
        .with_hint("remove the point or repeat the measurement in a suitable range"));
    }
    Ok(v * c.factor)
}

fn read_e4980a(path: &Path, lines: &[&str], opts: &LcrOptions) -> Result<Sweep> {
    let directive = |key: &str| {
        lines.iter().enumerate().find_map(|(i, l)| {
            let c = l.trim().strip_prefix('#')?;
            let (k, v) = c.split_once(':')?;
            (k.trim().eq_ignore_ascii_case(key)).then(|| (i + 1, v.trim().to_string()))
        })
    };
    let (pair, deg) =
        match (opts.pair, directive("function")) {
            (Some(p), _) => p,
            (None, Some((line, v))) => Pair::parse(&v).ok_or_else(|| {
                Error::input(
                    Location::line(path, line),
                    format!("unknown measurement function '{v}'"),
                )
                .with_hint("use an E4980A function name such as CPD, CPRP, CSRS, ZTD, RX, GB")
            })?,
            (None, None) => return Err(Error::input(
                Location::file(path),
                "headerless <A>,<B>,<status> data: the measured pair is not stated",
            )
            .with_hint(
                "pass --pair cp-d (or cp-rp, cs-rs, z-theta, ...) or add a '# function: CPD' line",
            )),
        };
    let freqs: Vec<f64> = match (&opts.frequencies, directive("frequencies")) {
        (Some(f), _) => f.clone(),
        (None, Some((line, v))) => v
            .split([',', ';'])
            .filter(|s| !s.trim().is_empty())
            .map(|s| {
                parse_quantity(s, Dimension::Frequency)
                    .map_err(|e| Error::input(Location::line(path, line), e))
            })
            .collect::<Result<_>>()?,
        (None, None) => {
            return Err(Error::input(
                Location::file(path),
                "headerless <A>,<B>,<status> data: the frequency list is not in the file",
            )
            .with_hint("pass --frequencies 100Hz,1kHz,10kHz or add a '# frequencies: ...' line"))
        }
    };
    let data: Vec<(usize, &str)> = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(|(i, l)| (i + 1, l.trim()))
        .collect();
    if data.len() != freqs.len() {
        return Err(Error::input(
            Location::file(path),
            format!(
                "{} data lines but {} frequencies: every line needs its frequency",
                data.len(),
                freqs.len()
            ),
        )
        .with_hint("give the sweep's frequency list in measurement order"));
    }
    let angle = if pair.has_angle() && deg {
        PI / 180.0
    } else {
        1.0
    };
    let mut points = Vec::new();
    let mut dropped: Vec<(i64, usize)> = Vec::new();
    let mut overloads = 0;
    for ((line, l), &f) in data.iter().zip(&freqs) {
        let fields: Vec<&str> = l.split(',').map(str::trim).collect();
        if !(3..=4).contains(&fields.len()) {
            return Err(Error::input(
                Location::line(path, *line),
                format!(
                    "expected '<A>,<B>,<status>' (3 or 4 fields), found {} fields",
                    fields.len()
                ),
            ));
        }
        let num = |c: usize, what: &str| {
            parse_engineering(fields[c], "").ok_or_else(|| {
                Error::input(
                    Location::at(path, *line, c + 1),
                    format!("expected a number for {what}, found '{}'", fields[c]),
                )
            })
        };
        let (a, b, status) = (num(0, "A")?, num(1, "B")?, num(2, "the status")?);
        if status.fract() != 0.0 {
            return Err(Error::input(
                Location::at(path, *line, 3),
                format!("status must be an integer code, found '{}'", fields[2]),
            ));
        }
        if a.abs() >= OVERLOAD || b.abs() >= OVERLOAD {
            overloads += 1;
            continue;
        }
        if status != 0.0 {
            match dropped.iter_mut().find(|d| d.0 == status as i64) {
                Some(d) => d.1 += 1,
                None => dropped.push((status as i64, 1)),
            }
            continue;
        }
        if let Some((msg, hint)) = frequency_problem(f) {
            return Err(Error::settings(msg).with_hint(hint));
        }
        let y = pair.to_admittance(a, b * angle, 2.0 * PI * f);
        passive(path, *line, f, y)?;
        points.push(LcrPoint {
            freq: f,
            y,
            line: *line,
        });
    }
    let mut notes = Vec::new();
    if overloads > 0 {
        notes.push(format!(
            "{overloads} point(s) with the overload value 9.9E37 were dropped"
        ));
    }
    for (code, n) in dropped {
        notes.push(format!(
            "{n} point(s) with status {code} ({}) were dropped",
            status_meaning(code)
        ));
    }
    if points.is_empty() {
        return Err(Error::input(
            Location::file(path),
            "no valid point: every line is an overload or has a non-zero status",
        )
        .with_hint("check the meter's range and the fixture connection"));
    }
    Ok(Sweep {
        path: path.to_path_buf(),
        sha256: String::new(),
        format: Format::E4980a,
        pair,
        instrument: None,
        columns: vec!["A".into(), "B".into(), "status".into()],
        points,
        notes,
    })
}

/// Meaning of an E4980A status code (Keysight E4980A user's guide, FETCh? format).
pub fn status_meaning(code: i64) -> &'static str {
    match code {
        0 => "normal",
        -1 => "no data",
        1 => "overload / analog bridge unbalanced",
        2 => "A/D converter not working",
        3 => "signal source overloaded",
        4 => "ALC unable to regulate",
        _ => "unknown status code",
    }
}

/// Write points as a plain `freq_Hz,<a>,<b>` CSV of `pair` (the inverse of the
/// reader, used for synthetic data and round-trip tests). Angles in degrees.
/// Every value is finite ([`super::finite_output`]), or nothing is made.
pub fn write_csv(pair: Pair, points: &[(f64, Complex<f64>)]) -> Result<String> {
    let (ha, hb) = csv_header(pair);
    written(points, &[pair], &["freq_Hz", ha, hb])?;
    let mut s = format!("freq_Hz,{ha},{hb}\n");
    for &(f, y) in points {
        let (a, b) = scaled(pair, y, f);
        s.push_str(&format!("{f},{a:.10e},{b:.10e}\n"));
    }
    Ok(s)
}

/// The guard of the synthetic writers: f and each pair's two readings of every
/// point finite (`columns`: f's name, then two per pair).
fn written(points: &[(f64, Complex<f64>)], pairs: &[Pair], columns: &[&str]) -> Result<()> {
    super::finite_output(
        "the synthetic export",
        points.iter().flat_map(|&(f, y)| {
            let readings = pairs.iter().flat_map(move |&p| {
                let (a, b) = scaled(p, y, f);
                [a, b]
            });
            columns
                .iter()
                .copied()
                .zip(std::iter::once(f).chain(readings))
        }),
    )
}

/// Points per decade of a log sweep: at most 1000, so that the frequencies, rounded
/// to four significant digits as a meter prints them (at worst 0.05 % off), stay
/// distinct (a step of 10^(1/1000) − 1 = 0.23 %) and the readers take the sweep back
/// (at 7356 a decade two points both print as 100 Hz). An LCR meter's whole sweep
/// holds at most 1601 points.
pub const PER_DECADE: CountRange = CountRange::new(
    1,
    1000,
    "points per decade of a log sweep; more would repeat frequencies rounded to 4 digits",
);

/// Points of the log sweep from `f_min` to `f_max` (Hz) at `per_decade` points per
/// decade: round(log10(f_max/f_min)·per_decade) + 1, checked against
/// [`PER_DECADE`] and [`MAX_POINTS`] in floating point before anything is sized by
/// it. Refused unless 0 < f_min < f_max < ∞, both in [`FREQUENCY_RANGE_HZ`].
pub fn log_sweep_points(
    f_min: f64,
    f_max: f64,
    per_decade: usize,
) -> std::result::Result<usize, String> {
    if !(f_min > 0.0 && f_max > f_min && f_max.is_finite()) {
        return Err(format!(
            "a log sweep needs 0 < f_min < f_max < ∞, found {} Hz to {} Hz",
            fmt_g(f_min),
            fmt_g(f_max)
        ));
    }
    // A sweep the tool makes is one its readers take back.
    if let Some((msg, _)) = [f_min, f_max].into_iter().find_map(frequency_problem) {
        return Err(msg);
    }
    let per_decade = PER_DECADE.check(per_decade as u64)?;
    const SWEEP: CountRange = CountRange::new(1, MAX_POINTS, "points of one sweep");
    SWEEP
        .check_real((f_max / f_min).log10() * per_decade as f64 + 1.0)
        .map_err(|e| {
            format!(
                "{} Hz to {} Hz at {per_decade} per decade: {e}",
                fmt_g(f_min),
                fmt_g(f_max)
            )
        })
}

/// Log-spaced frequencies from `f_min` to `f_max` (Hz) at `per_decade` points per
/// decade, each rounded to four significant digits as a meter's frequency list
/// prints them; their count is [`log_sweep_points`] (refused outside its range).
pub fn log_frequencies(f_min: f64, f_max: f64, per_decade: usize) -> Result<Vec<f64>> {
    let n = log_sweep_points(f_min, f_max, per_decade).map_err(Error::settings)?;
    Ok((0..n)
        .map(|i| {
            let f = f_min * 10f64.powf(i as f64 / per_decade as f64);
            format!("{f:.3e}").parse().unwrap_or(f)
        })
        .collect())
}

/// A synthetic sweep of a lossy capacitor: at each frequency f, εr′ and tan δ from
/// `eps_tan(f)`, Cp = εr′·`c0`·(1 + e₁) + `stray` and D = tan δ·(1 + e₂) with e₁,
/// e₂ drawn from `noise` (relative, in that order); the loss belongs to the coupon
/// only (G = ω·εr′·c0·D: the stray capacitance is lossless). Returns (f, Y).
pub fn synthetic_points(
    freqs: &[f64],
    c0: f64,
    stray: f64,
    noise: &rand_distr::Normal<f64>,
    rng: &mut impl rand::Rng,
    eps_tan: impl Fn(f64) -> (f64, f64),
) -> Vec<(f64, Complex<f64>)> {
    use rand_distr::Distribution;
    freqs
        .iter()
        .map(|&f| {
            let (eps, tan) = eps_tan(f);
            let omega = 2.0 * PI * f;
            let cp = eps * c0 * (1.0 + noise.sample(rng)) + stray;
            let d = tan * (1.0 + noise.sample(rng));
            (f, Complex::new(omega * eps * c0 * d, omega * cp))
        })
        .collect()
}

/// Write points in the E4990A block format (`!` header, CRLF, `+d.ddde+ddd`).
/// Every value is finite ([`super::finite_output`]), or nothing is made.
pub fn write_e4990a(pair: Pair, points: &[(f64, Complex<f64>)]) -> Result<String> {
    let (ha, hb) = match pair {
        Pair::ZTheta => ("|Z|(Ohm)-data", "theta-z(deg)-data"),
        Pair::RX => ("R(Ohm)-data", "X(Ohm)-data"),
        Pair::CpD => ("Cp(F)-data", "D-data"),
        Pair::YTheta => ("|Y|(S)-data", "theta-y(deg)-data"),
        _ => ("Cp(F)-data", "D-data"),
    };
    let pair = match pair {
        Pair::ZTheta | Pair::RX | Pair::YTheta => pair,
        _ => Pair::CpD,
    };
    written(points, &[pair], &["frequency", ha, hb])?;
    let e = |v: f64| {
        let s = format!("{v:+.11e}");
        let (m, x) = s.split_once('e').expect("exponent");
        let x: i32 = x.parse().expect("integer exponent");
        format!("{m}e{}{:03}", if x < 0 { '-' } else { '+' }, x.abs())
    };
    let mut s = String::from(
        "!dea-fit synthetic export (E4990A format)\r\n!Date: synthetic\r\n\r\nBEGIN CH1_DATA\r\n",
    );
    s.push_str(&format!("Frequency(Hz), {ha}, {hb}\r\n"));
    for &(f, y) in points {
        let (a, b) = scaled(pair, y, f);
        s.push_str(&format!("{}, {}, {}\r\n", e(f), e(a), e(b)));
    }
    s.push_str("END\r\n");
    Ok(s)
}

/// Write points as a Hioki-style CSV: instrument preamble lines, then
/// `FREQ[Hz],Z[ohm],PHASE[deg],Cp[F],D` (several pairs; the reader picks Cp–D).
/// Every value is finite ([`super::finite_output`]), or nothing is made.
pub fn write_hioki(points: &[(f64, Complex<f64>)]) -> Result<String> {
    written(
        points,
        &[Pair::ZTheta, Pair::CpD],
        &["FREQ[Hz]", "Z[ohm]", "PHASE[deg]", "Cp[F]", "D"],
    )?;
    let mut s =
        String::from("\"dea-fit synthetic export (Hioki LCR style)\"\n\"SPEED\",\"SLOW\"\n\n");
    s.push_str("FREQ[Hz],Z[ohm],PHASE[deg],Cp[F],D\n");
    for &(f, y) in points {
        let (z, th) = scaled(Pair::ZTheta, y, f);
        let (cp, d) = scaled(Pair::CpD, y, f);
        s.push_str(&format!("{f},{z:.8e},{th:.6},{cp:.8e},{d:.8e}\n"));
    }
    Ok(s)
}

fn csv_header(pair: Pair) -> (&'static str, &'static str) {
    match pair {
        Pair::CpD => ("Cp_F", "D"),
        Pair::CpQ => ("Cp_F", "Q"),
        Pair::CpG => ("Cp_F", "G_S"),
        Pair::CpRp => ("Cp_F", "Rp_Ohm"),
        Pair::CsD => ("Cs_F", "D"),
        Pair::CsQ => ("Cs_F", "Q"),
        Pair::CsRs => ("Cs_F", "Rs_Ohm"),
        Pair::LsRs => ("Ls_H", "Rs_Ohm"),
        Pair::LpRp => ("Lp_H", "Rp_Ohm"),
        Pair::RX => ("R_Ohm", "X_Ohm"),
        Pair::ZTheta => ("Z_Ohm", "theta_deg"),
        Pair::GB => ("G_S", "B_S"),
        Pair::YTheta => ("Y_S", "thetay_deg"),
    }
}

/// The pair's reading at f, angles in degrees.
fn scaled(pair: Pair, y: Complex<f64>, f: f64) -> (f64, f64) {
    let (a, b) = pair.from_admittance(y, 2.0 * PI * f);
    if pair.has_angle() {
        (a, b.to_degrees())
    } else {
        (a, b)
    }
}
