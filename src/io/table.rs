//! A located reader for delimited text tables (CSV, `;`- or tab-separated).
//!
//! Accepts `#` comment lines (a `# key: value` comment is kept as a directive),
//! blank lines, a UTF-8 BOM, LF, CRLF or CR line ends, double-quoted fields, and a
//! decimal comma when the separator is `;`. Lines whose fields are all empty count as
//! blank. Every field keeps its line and column so that errors can point at it; a
//! spreadsheet, UTF-16 or Latin-1 file is recognised and named as such.

use crate::error::{Error, Location, Result};
use crate::units::Dimension;
use rayon::prelude::*;
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// One data row: its line and where its fields are in the table's field store (read
/// them with [`Table::field`]), in 8 bytes: a file under 4 GiB has fewer lines and
/// fields than 4 bytes count ([`Table`]'s `ends`).
#[derive(Debug, Clone, Copy)]
pub struct Row {
    /// 1-based line number in the file.
    line: u32,
    /// Index of the row's first field in the table's `ends`.
    first: u32,
}

impl Row {
    /// The row's 1-based line number in the file.
    pub fn line(&self) -> usize {
        self.line as usize
    }
}

/// A parsed table: header, rows, `# key: value` directives and provenance.
///
/// The data fields are held back to back in one string (`cells`, with the end of
/// each field in `ends`), not as a string per field: a 10⁶-row file then costs a few
/// allocations instead of three million, and the file's own bytes hold the fields.
/// A large file is split in parts at line ends and the parts are read in parallel
/// ([`PART_BYTES`]), each in its own text and its own stretch of `ends` and `rows`,
/// sized before reading.
#[derive(Debug, Clone)]
pub struct Table {
    /// The file.
    pub path: PathBuf,
    /// SHA-256 of its bytes.
    pub sha256: String,
    /// Header fields as written.
    pub header: Vec<String>,
    /// Line of the header.
    pub header_line: usize,
    /// Data rows.
    pub rows: Vec<Row>,
    /// `# key: value` comment lines: (line, lower-case key, value).
    pub directives: Vec<(usize, String, String)>,
    delimiter: u8,
    /// The file's text with each part's data fields, trimmed and unquoted, moved
    /// back to back to where the part's text starts (trimming and unquoting only
    /// shorten a line, so a line's fields fit where it was), and the rest of the
    /// part's text zeroed.
    cells: String,
    /// The end in `cells` of each field, in 4 bytes (the file is under 4 GiB); each
    /// part's ends are preceded by the start of its first field, so that field `i`
    /// is `cells[ends[i - 1]..ends[i]]`.
    ends: Vec<u32>,
}

/// The fields of one line, as owned strings (the header, a preamble line).
fn line_fields(splitter: &mut Splitter, line: &str) -> Vec<String> {
    splitter.split(line);
    (0..splitter.fields.len())
        .map(|i| splitter.field(line, i).to_string())
        .collect()
}

/// Bytes of the data below the header from which a file is read in parts, and about
/// the size of each part: large enough that a part's start-up costs nothing, small
/// enough that two threads share a 20 MB file evenly.
const PART_BYTES: usize = 1 << 20;

impl Table {
    /// The error of column `c`, a second column of a kind the reader takes once
    /// (column `first` is the one it has), located at `c`'s header, with `hint`
    /// naming the columns the reader takes.
    pub fn second_column(&self, c: usize, first: usize, hint: &str) -> Error {
        Error::input(
            Location::at(&self.path, self.header_line, c + 1),
            format!(
                "a second column of the same kind, '{}' (column {} is '{}')",
                self.header[c],
                first + 1,
                self.header[first]
            ),
        )
        .with_hint(hint.to_string())
    }

    /// Read and split a file, hashing its bytes as they are read.
    pub fn read(path: &Path) -> Result<Table> {
        let (bytes, sha256) = read_hashed(path)?;
        Self::split(path, bytes).map(|t| Table { sha256, ..t })
    }

    /// Split bytes that came from `path` (and hash them, alongside).
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Table> {
        let (sha256, table) = rayon::join(
            || super::sha256_hex(bytes),
            || Self::split(path, bytes.to_vec()),
        );
        table.map(|t| Table { sha256, ..t })
    }

    /// The header, then the data below it (in parts read in parallel when large),
    /// each part's fields moved within its own text ([`Table`]'s `cells`).
    fn split(path: &Path, mut bytes: Vec<u8>) -> Result<Table> {
        // Under 4 GiB, line numbers (a byte each at least) and offsets fit in 4 bytes.
        if u32::try_from(bytes.len() + 1).is_err() {
            return Err(
                Error::input(Location::file(path), "the file is 4 GiB or larger")
                    .with_hint("split it into files of under 4 GiB"),
            );
        }
        let text = decode(path, &bytes)?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Lines end in LF or CRLF; a file without any LF may use classic-Mac CR ends.
        let end = if memchr::memchr(b'\n', text.as_bytes()).is_some() {
            b'\n'
        } else {
            b'\r'
        };
        let no_header = || {
            Error::input(Location::file(path), "the file holds no header and no data").with_hint(
                "the first non-comment line must name the columns, e.g. stretch,nominal_stress_kPa",
            )
        };
        let mut directives = Vec::new();
        let mut offset = 0;
        let mut line = 0;
        // The first content line sets the separator.
        let mut splitter: Option<Splitter> = None;
        // The header: the first line with a non-empty field, after comments and blanks.
        let (delimiter, header) = loop {
            if offset > text.len() {
                return Err(no_header());
            }
            let stop =
                memchr::memchr(end, &text.as_bytes()[offset..]).map_or(text.len(), |i| offset + i);
            let raw = &text[offset..stop];
            offset = stop + 1;
            line += 1;
            let t = raw.strip_suffix('\r').unwrap_or(raw).trim();
            if let Some(c) = t.strip_prefix('#') {
                directives.extend(directive(line, c));
                continue;
            } else if t.is_empty() {
                continue;
            }
            let splitter = splitter.get_or_insert_with(|| Splitter::new(delimiter_of(t)));
            let names = line_fields(splitter, t);
            if names.iter().all(|n| n.is_empty()) {
                continue;
            }
            break (splitter.delimiter, (line, names));
        };
        let body = text.get(offset..).unwrap_or("");
        let header_line = header.0;
        let parts = part_ranges(body, end);
        // The lines of each part: one vectorised count of line ends per part.
        let lines_of = |r: &std::ops::Range<usize>| {
            1 + memchr::memchr_iter(end, &body.as_bytes()[r.clone()]).count()
        };
        let lines: Vec<usize> = parts.par_iter().map(lines_of).collect();
        let body_start = bytes.len() - body.len();
        // Each part's stretch of the stores, sized for its lines before reading: a
        // start and the header's count of fields per line of ends, a row per line.
        let width = header.1.len();
        // A row of `width` fields has `width - 1` separators: a part stores at most
        // its bytes and lines of fields.
        let slots = |r: &std::ops::Range<usize>, n: usize| 1 + (n * width).min(r.len() + n);
        let all: usize = parts.iter().zip(&lines).map(|(r, &n)| slots(r, n)).sum();
        if u32::try_from(all).is_err() {
            return Err(Error::input(
                Location::line(path, header_line),
                "more than 4·10⁹ fields below the header",
            )
            .with_hint("split the file into files of fewer rows"));
        }
        let mut ends = vec![0u32; all];
        let mut rows = vec![Row { line: 0, first: 0 }; lines.iter().sum()];
        let mut jobs = Vec::with_capacity(parts.len());
        let (mut text_left, mut ends_left, mut rows_left) =
            (&mut bytes[body_start..], &mut ends[..], &mut rows[..]);
        let (mut first_line, mut first_end, mut cut) = (line + 1, 0, 0);
        for (r, &n) in parts.iter().zip(&lines) {
            // Parts are apart by the line end between them.
            let (c, rest) = std::mem::take(&mut text_left)[r.start - cut..].split_at_mut(r.len());
            let (e, rest_e) = std::mem::take(&mut ends_left).split_at_mut(slots(r, n));
            let (w, rest_w) = std::mem::take(&mut rows_left).split_at_mut(n);
            (text_left, ends_left, rows_left, cut) = (rest, rest_e, rest_w, r.end);
            let at = Start {
                line: first_line,
                cell: body_start + r.start,
                end: first_end,
            };
            jobs.push((c, at, e, w));
            (first_line, first_end) = (first_line + n, first_end + slots(r, n));
        }
        let read = |(c, at, e, w): (&mut [u8], Start, &mut [u32], &mut [Row])| {
            read_part(path, c, end, at, e, w, delimiter, &header)
        };
        let read: Vec<Result<(usize, Directives)>> = if parts.len() > 1 {
            jobs.into_par_iter().map(read).collect()
        } else {
            jobs.into_iter().map(read).collect()
        };
        // The rows of each part moved down to follow the previous part's.
        let (mut kept, mut from) = (0, 0);
        for (part, n) in read.into_iter().zip(&lines) {
            // The first error in file order: parts stop at their own first.
            let (used, found) = part?;
            rows.copy_within(from..from + used, kept);
            (kept, from) = (kept + used, from + n);
            directives.extend(found);
        }
        rows.truncate(kept);
        rows.shrink_to_fit();
        if rows.is_empty() {
            return Err(Error::input(
                Location::line(path, header_line),
                "the file has a header but no data rows",
            )
            .with_hint("add one line per measured point below the header"));
        }
        // The text above the body and the line ends between parts are untouched, and
        // each part holds whole fields of it and zeros (ASCII NUL): UTF-8.
        let cells = String::from_utf8(bytes).expect("text, whole fields and zeros are UTF-8");
        Ok(Table {
            path: path.to_path_buf(),
            sha256: String::new(),
            header: header.1,
            header_line,
            rows,
            directives,
            delimiter,
            cells,
            ends,
        })
    }

    /// Read a testing-machine or instrument export ([`Table::parse_export`]),
    /// hashing its bytes as they are read.
    pub fn read_export(path: &Path, is_header: &dyn Fn(&[&str]) -> bool) -> Result<Export> {
        let (bytes, sha256) = read_hashed(path)?;
        Self::export(path, bytes, sha256, is_header)
    }

    /// Split an export whose header may sit below a preamble of metadata lines and
    /// may have a row of units under it. The header is the first line (after `#`
    /// comments and blank lines) whose fields `is_header` accepts; the other lines
    /// above it (an instrument's or test program's metadata) are skipped, every line
    /// keeping its number. A file in which no line before the first all-numeric one is
    /// accepted is read as a plain table (its first line the header), so that the
    /// caller's header errors apply. A units row right under the header
    /// (`"(s)","(mm)","(N)"`, `[mm]`, `mm`: no field a number) is read into the
    /// header: `Extension` over `(mm)` becomes `Extension [mm]`. The notes say what
    /// was skipped and read.
    pub fn parse_export(
        path: &Path,
        bytes: &[u8],
        is_header: &dyn Fn(&[&str]) -> bool,
    ) -> Result<Export> {
        Self::export(path, bytes.to_vec(), super::sha256_hex(bytes), is_header)
    }

    /// [`Table::parse_export`] of the bytes of `path`, of SHA-256 `sha256`.
    fn export(
        path: &Path,
        bytes: Vec<u8>,
        sha256: String,
        is_header: &dyn Fn(&[&str]) -> bool,
    ) -> Result<Export> {
        let mut notes = Vec::new();
        let found = decode(path, &bytes)
            .ok()
            .and_then(|text| preamble(text, is_header));
        let table = match found {
            Some((line, skipped, kept)) => {
                notes.push(format!(
                    "{skipped} preamble line{} before the header on line {line} skipped",
                    if skipped == 1 { "" } else { "s" }
                ));
                drop(bytes);
                Self::split(path, kept.into_bytes())?
            }
            None => Self::split(path, bytes)?,
        };
        let mut table = Table { sha256, ..table };
        notes.extend(table.units_row()?);
        Ok(Export { table, notes })
    }

    /// Read a units row under the header into the header (see
    /// [`Table::parse_export`]) and drop it from the rows; the note saying so, or
    /// None when the first row is not a units row.
    fn units_row(&mut self) -> Result<Option<String>> {
        let Some(&row) = self.rows.first() else {
            return Ok(None);
        };
        let fields: Vec<String> = (0..self.header.len())
            .map(|c| self.field(&row, c).to_string())
            .collect();
        // A unit holds no digit unless bracketed (`(mm2)`): `1k` or `15.7p` is a value.
        let is_unit = |f: &str| {
            let bracketed = f.starts_with(['(', '[']) && f.ends_with([')', ']']);
            f.is_empty()
                || (f.chars().count() <= UNIT_CHARS
                    && (bracketed || !f.bytes().any(|b| b.is_ascii_digit())))
        };
        if fields.iter().all(|f| f.is_empty()) || !fields.iter().all(|f| is_unit(f)) {
            return Ok(None);
        }
        if self.rows.len() == 1 {
            return Err(Error::input(
                Location::line(&self.path, row.line()),
                "the file has a header and a units row but no data rows",
            )
            .with_hint("add one line per measured point below the units row"));
        }
        let mut read = Vec::new();
        for (h, f) in self.header.iter_mut().zip(&fields) {
            let unit = f
                .trim_start_matches(['(', '['])
                .trim_end_matches([')', ']'])
                .trim();
            if !unit.is_empty() {
                *h = format!("{h} [{unit}]");
                read.push(h.clone());
            }
        }
        self.rows.remove(0);
        Ok(Some(format!(
            "units row on line {} read into the header: {}",
            row.line(),
            read.join(", ")
        )))
    }

    /// The trimmed text of `row`'s field in column `col` (0-based).
    pub fn field(&self, row: &Row, col: usize) -> &str {
        let i = row.first as usize + col;
        &self.cells[self.ends[i - 1] as usize..self.ends[i] as usize]
    }

    /// The error for a header field that names no accepted column: empty, a number
    /// (the header line is missing) or an unknown name. `example` is a valid header
    /// line to suggest, `accepted` the list of column names.
    pub fn unknown_column(&self, col: usize, accepted: &str, example: &str) -> Error {
        let h = &self.header[col];
        let loc = Location::at(&self.path, self.header_line, col + 1);
        if h.trim().is_empty() {
            Error::input(loc, "empty column name in the header")
                .with_hint(format!("name every column; accepted: {accepted}"))
        } else if h.trim().parse::<f64>().is_ok() {
            Error::input(
                loc,
                format!("expected a header naming each column, found the number '{h}'"),
            )
            .with_hint(format!("add a first line such as {example}"))
        } else {
            Error::input(loc, format!("unknown column '{h}'"))
                .with_hint(format!("accepted columns: {accepted}"))
        }
    }

    /// The location of a field.
    pub fn loc(&self, row: &Row, col: usize) -> Location {
        Location::at(&self.path, row.line(), col + 1)
    }

    /// A finite number in `row`, column `col` (0-based), named `what` in errors.
    pub fn number(&self, row: &Row, col: usize, what: &str) -> Result<f64> {
        let raw = self.field(row, col);
        let text = if self.delimiter == b';' && raw.contains(',') {
            Cow::Owned(raw.replace(',', "."))
        } else {
            Cow::Borrowed(raw)
        };
        match parse_f64(text.as_bytes()) {
            Some(v) if v.is_finite() => Ok(v),
            Some(_) => Err(Error::input(
                self.loc(row, col),
                format!("{what} must be a finite number, found '{raw}'"),
            )),
            None if raw.is_empty() => Err(Error::input(
                self.loc(row, col),
                format!("{what} is empty; expected a number"),
            )),
            None => {
                let e = Error::input(
                    self.loc(row, col),
                    format!("expected a number for {what}, found '{raw}'"),
                );
                Err(if raw.contains('#') {
                    e.with_hint("comments go on their own line, starting with '#'")
                } else if raw.contains(',') {
                    e.with_hint("a decimal comma is read only in ';'-separated files: use '.' for decimals or ';' as the separator")
                } else {
                    e
                })
            }
        }
    }
}

/// The number `bytes` spell, as `str::parse::<f64>` reads it (correctly rounded), or
/// None where it refuses them. A plain decimal `[+-]digits[.digits]` of at most 15
/// digits (nearly every field of a test export) is m / 10ᵏ with m < 2⁵³ and k ≤ 15:
/// both exact in binary, so the one division is the correctly rounded value (Clinger,
/// "How to read floating point numbers accurately", PLDI 1990); anything else goes to
/// `fast_float2`, which reads it exactly as `str::parse` does.
fn parse_f64(bytes: &[u8]) -> Option<f64> {
    plain_decimal(bytes).or_else(|| fast_float2::parse::<f64, _>(bytes).ok())
}

/// [`parse_f64`]'s fast path: the value of a plain decimal of at most 15 digits.
fn plain_decimal(bytes: &[u8]) -> Option<f64> {
    const POW10: [f64; 16] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
    ];
    let (negative, digits) = match bytes.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, bytes),
    };
    // 15 digits and a point: m < 10¹⁵ < 2⁵³, k ≤ 15.
    if digits.is_empty() || digits.len() > 16 {
        return None;
    }
    let (mut m, mut count, mut point) = (0u64, 0usize, None);
    for (i, &b) in digits.iter().enumerate() {
        match b {
            b'0'..=b'9' => {
                m = 10 * m + u64::from(b - b'0');
                count += 1;
            }
            b'.' if point.is_none() => point = Some(i),
            _ => return None,
        }
    }
    if count == 0 || count > 15 {
        return None;
    }
    let k = point.map_or(0, |i| digits.len() - 1 - i);
    let v = m as f64 / POW10[k];
    Some(if negative { -v } else { v })
}

/// A table read by [`Table::parse_export`] and what was done to find its header.
#[derive(Debug, Clone)]
pub struct Export {
    /// The table (header as read, units row merged into it).
    pub table: Table,
    /// Preamble lines skipped, units row read.
    pub notes: Vec<String>,
}

/// `--columns`: which header column holds which quantity, with an optional unit
/// that overrides the header's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ColumnMap {
    /// (role, column as given, unit), in the order given.
    pub entries: Vec<(String, String, Option<String>)>,
    /// Where the map came from: `--columns` or the mapping file.
    pub origin: String,
}

impl ColumnMap {
    /// Parse `ROLE=COLUMN[:UNIT],…` or, when `spec` is an existing file, that file:
    /// one `ROLE = COLUMN[:UNIT]` per line (the value may be quoted, so a TOML table
    /// of strings reads; `#` comments and blank lines are skipped). `roles` are the
    /// roles the reader knows; each may be given once.
    pub fn parse(spec: &str, roles: &[&str]) -> Result<ColumnMap> {
        let path = Path::new(spec);
        let (text, origin, sep) = if path.is_file() {
            let t = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
            (t, path.display().to_string(), '\n')
        } else {
            (spec.to_string(), "--columns".to_string(), ',')
        };
        let mut map = ColumnMap {
            entries: Vec::new(),
            origin: origin.clone(),
        };
        for (i, item) in text.split(sep).enumerate() {
            let item = item.trim();
            if item.is_empty() || item.starts_with('#') {
                continue;
            }
            let at = |msg: String| -> Error {
                if sep == '\n' {
                    Error::input(Location::line(Path::new(&origin), i + 1), msg)
                } else {
                    Error::settings(format!("--columns: {msg}"))
                }
            };
            let example = "stretch=Extension:mm,force=Load:N";
            let Some((role, value)) = item.split_once('=') else {
                return Err(at(format!("expected ROLE=COLUMN[:UNIT], found '{item}'"))
                    .with_hint(format!("e.g. {example}")));
            };
            let role = role.trim().to_ascii_lowercase();
            if !roles.contains(&role.as_str()) {
                return Err(at(format!("unknown role '{role}'"))
                    .with_hint(format!("roles: {}", roles.join(", "))));
            }
            if map.entries.iter().any(|e| e.0 == role) {
                return Err(at(format!("role '{role}' given twice")));
            }
            let value = value.trim().trim_matches('"').trim();
            let (column, unit) = match value.rsplit_once(':') {
                Some((c, u)) if !u.trim().is_empty() && !u.contains(' ') => {
                    (c.trim(), Some(u.trim().to_string()))
                }
                _ => (value, None),
            };
            if column.is_empty() {
                return Err(at(format!("role '{role}' names no column"))
                    .with_hint(format!("e.g. {example}")));
            }
            map.entries.push((role, column.to_string(), unit));
        }
        Ok(map)
    }

    /// The role and unit the map gives header field `h`: an entry whose column is
    /// `h` as written, or `h` without its unit (`Load` names `Load [N]`), in any case.
    pub fn find(&self, h: &str) -> Option<(&str, Option<&str>)> {
        let name = split_header(h, &[]).0;
        self.entries
            .iter()
            .find(|(_, c, _)| {
                c.eq_ignore_ascii_case(h.trim()) || c.to_lowercase().replace(' ', "_") == name
            })
            .map(|(r, _, u)| (r.as_str(), u.as_deref()))
    }

    /// Every mapped column is in `table`'s header, or an error at the header.
    pub fn check(&self, table: &Table) -> Result<()> {
        for (role, column, _) in &self.entries {
            let mapped = |h: &String| self.find(h).is_some_and(|(r, _)| r == role);
            if !table.header.iter().any(mapped) {
                return Err(Error::input(
                    Location::line(&table.path, table.header_line),
                    format!(
                        "{} maps {role} to '{column}', which is not a column",
                        self.origin
                    ),
                )
                .with_hint(format!("the header's columns: {}", table.header.join(", "))));
            }
        }
        Ok(())
    }
}

/// The role of a column name as dea-fit or a testing-machine program writes it
/// (Instron Bluehill: `Extension`, `Load`, `Tensile strain (Extension)`, `Tensile
/// stress`; ZwickRoell testXpert: `Standard force`, `Standard travel`, `Strain`,
/// `Nominal strain`, `Grip to grip separation`; Shimadzu Trapezium: `Force`,
/// `Stroke`, `Strain`; German exports: `Standardkraft`, `Dehnung`, `Standardweg`).
/// `name` is lower-case with runs of other characters than letters and digits as
/// `_`; `strain_pct` is its own role (a percentage whatever the unit).
pub fn vendor_role(name: &str) -> Option<&'static str> {
    Some(match name {
        "stretch" | "lambda" | "stretch_ratio" => "stretch",
        "strain" | "tensile_strain" | "nominal_strain" | "engineering_strain" | "dehnung"
        | "nominelle_dehnung" => "strain",
        "strain_pct" | "strain_percent" => "strain_pct",
        "displacement"
        | "extension"
        | "elongation"
        | "crosshead"
        | "crosshead_displacement"
        | "crosshead_travel"
        | "stroke"
        | "standard_travel"
        | "grip_to_grip_separation"
        | "traverse"
        | "standardweg"
        | "traversenweg" => "displacement",
        "nominal_stress" | "engineering_stress" | "tensile_stress" | "stress" | "spannung" => {
            "stress"
        }
        "true_stress" | "cauchy_stress" => "true_stress",
        "force" | "load" | "standard_force" | "test_force" | "kraft" | "standardkraft" => "force",
        "weight" => "weight",
        "mode" => "mode",
        "time" | "test_time" | "elapsed_time" | "zeit" | "testzeit" | "pruefzeit" => "time",
        n if n.starts_with("tensile_strain_") => "strain",
        n if n.starts_with("tensile_stress_") => "stress",
        _ => return None,
    })
}

/// `name` lower-case, each run of characters other than ASCII letters and digits
/// one `_`, none at the ends.
pub fn normalise(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for ch in name.chars() {
        if ch.is_ascii_alphanumeric() {
            out.push(ch.to_ascii_lowercase());
        } else if !out.ends_with('_') && !out.is_empty() {
            out.push('_');
        }
    }
    out.trim_end_matches('_').to_string()
}

/// The longest field of a units row (`(mm/mm)`, `[N/mm²]`): longer text is a data
/// or name field, not a unit.
const UNIT_CHARS: usize = 16;

/// Lines of metadata above an export's header searched for it: instrument and test
/// program preambles hold a few dozen lines.
const PREAMBLE_LINES: usize = 500;

/// The header line of an export below a preamble (1-based), the number of preamble
/// lines and the text with those lines blanked (`#` comments kept, every line
/// keeping its number); None when the first content line is the header or no line
/// before the first all-numeric one is one `is_header` accepts.
fn preamble(text: &str, is_header: &dyn Fn(&[&str]) -> bool) -> Option<(usize, usize, String)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let end = if memchr::memchr(b'\n', text.as_bytes()).is_some() {
        b'\n'
    } else {
        b'\r'
    };
    let mut skipped = 0;
    for (i, raw) in split_bytes(text, end).enumerate().take(PREAMBLE_LINES) {
        let t = raw.strip_suffix('\r').unwrap_or(raw).trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let owned = line_fields(&mut Splitter::new(delimiter_of(t)), t);
        let fields: Vec<&str> = owned.iter().map(String::as_str).collect();
        if fields.iter().all(|f| f.is_empty()) {
            continue;
        }
        if is_header(&fields) {
            if skipped == 0 {
                return None;
            }
            let mut kept = String::with_capacity(text.len());
            for (j, line) in split_bytes(text, end).enumerate() {
                if j > 0 {
                    kept.push(char::from(end));
                }
                if j >= i || line.trim_start().starts_with('#') {
                    kept.push_str(line);
                }
            }
            return Some((i + 1, skipped, kept));
        }
        let number = |f: &&str| parse_f64(f.replace(',', ".").as_bytes()).is_some();
        if fields.iter().filter(|f| !f.is_empty()).all(number) {
            return None;
        }
        skipped += 1;
    }
    None
}

/// The separator of the first content line: tab, else `;`, else `,`.
fn delimiter_of(first: &str) -> u8 {
    if first.contains('\t') {
        b'\t'
    } else if first.contains(';') {
        b';'
    } else {
        b','
    }
}

/// The directive of a comment line's text after `#`, if it is `key: value`.
fn directive(line: usize, comment: &str) -> Option<(usize, String, String)> {
    let (k, v) = comment.split_once(':')?;
    Some((line, k.trim().to_ascii_lowercase(), v.trim().to_string()))
}

/// `body` split at line ends (`end`) into ranges of about [`PART_BYTES`], each
/// whole lines without the line end that follows it; one range for a small body.
fn part_ranges(body: &str, end: u8) -> Vec<std::ops::Range<usize>> {
    let bytes = body.as_bytes();
    let mut ranges = Vec::with_capacity(bytes.len() / PART_BYTES + 1);
    let mut start = 0;
    while bytes.len() - start > 2 * PART_BYTES {
        match memchr::memchr(end, &bytes[start + PART_BYTES..]) {
            Some(i) => {
                let stop = start + PART_BYTES + i;
                ranges.push(start..stop);
                start = stop + 1;
            }
            None => break,
        }
    }
    ranges.push(start..bytes.len());
    ranges
}

/// `# key: value` comment lines: (line, lower-case key, value).
type Directives = Vec<(usize, String, String)>;

/// Where a part of a file starts: its first line, the offset of its text in the
/// body (and of its fields in the table's cells), the index of its first slot in the
/// table's ends.
#[derive(Debug, Clone, Copy)]
struct Start {
    line: usize,
    cell: usize,
    end: usize,
}

/// Read `text`, whole lines of a file below its header ending in `end`, the first at
/// line `at.line`, moving each row's fields to the front of `text` (the rest zeroed),
/// their ends into `ends` (slot 0 taking the start of the first field) and the rows
/// into `rows`: comments kept as directives, blank lines skipped, every row checked
/// to have the header's field count (the first that has not is the error). The rows
/// read and the directives.
#[allow(clippy::too_many_arguments)]
fn read_part(
    path: &Path,
    text: &mut [u8],
    end: u8,
    at: Start,
    ends: &mut [u32],
    rows: &mut [Row],
    delimiter: u8,
    (header_line, header): &(usize, Vec<String>),
) -> Result<(usize, Directives)> {
    let mut splitter = Splitter::new(delimiter);
    let mut directives = Vec::new();
    // Rows and ends stored, bytes of fields moved, the next line's start.
    let (mut kept, mut stored, mut used, mut next) = (0, 1, 0, 0);
    // The caller checked that the file is under 4 GiB: offsets in it fit in 4 bytes.
    ends[0] = at.cell as u32;
    for line in at.line.. {
        if next > text.len() {
            break;
        }
        let start = next;
        let stop = memchr::memchr(end, &text[start..]).map_or(text.len(), |i| start + i);
        next = stop + 1;
        // SAFETY: `text` is whole lines of the file's text, which `decode` found UTF-8;
        // fields are moved only to before `start` (`used` ≤ `start`: a line's fields
        // are no longer than the line), so `text[start..stop]` is as decoded, and
        // `start` and `stop` sit at line ends (ASCII): it is a whole line of UTF-8.
        let raw = unsafe { std::str::from_utf8_unchecked(&text[start..stop]) };
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        let t = raw.trim();
        let lead = start + raw.len() - raw.trim_start().len();
        if let Some(c) = t.strip_prefix('#') {
            directives.extend(directive(line, c));
            continue;
        } else if t.is_empty() {
            continue;
        }
        let n = splitter.split(t);
        if splitter.fields.iter().all(|(a, b)| a == b) {
            // Every field is empty: a blank line.
            continue;
        }
        if n != header.len() {
            return Err(Error::input(
                Location::at(path, line, n.min(header.len()) + 1),
                format!(
                    "expected {} fields (as in the header on line {header_line}), found {n}",
                    header.len(),
                ),
            )
            .with_hint(field_count_hint(t, delimiter, n > header.len())));
        }
        // The caller checked that lines and fields number under 4·10⁹.
        rows[kept] = Row {
            line: line as u32,
            first: (at.end + stored) as u32,
        };
        kept += 1;
        // Each field moves down to where the row's fields so far end: no further
        // than where it was, and past no byte of the line not yet moved.
        for &(a, b) in &splitter.fields {
            if splitter.in_out {
                text[used..used + b - a].copy_from_slice(&splitter.out[a..b]);
            } else {
                text.copy_within(lead + a..lead + b, used);
            }
            used += b - a;
            ends[stored] = (at.cell + used) as u32;
            stored += 1;
        }
    }
    text[used..].fill(0);
    Ok((kept, directives))
}

/// The bytes of the file at `path` and their SHA-256 (hex), hashed a block at a time
/// as the blocks are read, while in cache: the bytes are then free to be rewritten.
fn read_hashed(path: &Path) -> Result<(Vec<u8>, String)> {
    use sha2::{Digest, Sha256};
    use std::io::Read;
    /// Bytes read and hashed at a time: a fraction of a core's cache.
    const BLOCK: u64 = 1 << 18;
    let io = |e| Error::io(path, e);
    let mut file = std::fs::File::open(path).map_err(io)?;
    let size = file.metadata().map_or(0, |m| m.len());
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    let mut hasher = Sha256::new();
    loop {
        let from = bytes.len();
        if (&mut file)
            .take(BLOCK)
            .read_to_end(&mut bytes)
            .map_err(io)?
            == 0
        {
            break;
        }
        hasher.update(&bytes[from..]);
    }
    Ok((bytes, super::hex(&hasher.finalize())))
}

/// The text of a file, or an error saying what kind of file it is instead.
fn decode<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str> {
    let hint = "save it as CSV (UTF-8) and try again";
    if bytes.starts_with(b"PK\x03\x04") {
        return Err(Error::input(
            Location::file(path),
            "this is a ZIP container (an .xlsx or .ods spreadsheet?), not a text table",
        )
        .with_hint("export the sheet as CSV (UTF-8)"));
    }
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(Error::input(
            Location::file(path),
            "the file is UTF-16 text (a spreadsheet's 'Unicode text' export?), not UTF-8",
        )
        .with_hint(hint));
    }
    std::str::from_utf8(bytes).map_err(|e| {
        let bad = e.valid_up_to();
        let line = bytes[..bad].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::input(
            Location::line(path, line),
            format!(
                "the file is not UTF-8 text: byte 0x{:02X} cannot be read (Latin-1 or Windows-1252 text, or a binary export?)",
                bytes[bad]
            ),
        )
        .with_hint(hint)
    })
}

/// Splits lines into trimmed fields (double quotes may wrap a field holding the
/// separator).
struct Splitter {
    delimiter: u8,
    /// The CSV parser for lines with quotes, reset for each line: it reads a line as
    /// `csv::Reader` would (the same parser inside), without building one per line.
    quoted: csv_core::Reader,
    /// Its output buffers, reused from line to line.
    out: Vec<u8>,
    out_ends: Vec<usize>,
    /// The fields of the last line split: byte ranges of the line, or of `out` when
    /// it had quotes (`in_out`).
    fields: Vec<(usize, usize)>,
    in_out: bool,
}

impl Splitter {
    /// A splitter at `delimiter`.
    fn new(delimiter: u8) -> Splitter {
        Splitter {
            delimiter,
            quoted: csv_core::ReaderBuilder::new()
                .delimiter(delimiter)
                // The caller split the lines: a stray CR is text, not a record end.
                .terminator(csv_core::Terminator::Any(b'\n'))
                .build(),
            out: vec![0; 256],
            out_ends: vec![0; 16],
            fields: Vec::new(),
            in_out: false,
        }
    }

    /// The fields of a line without quotes, split in one pass over its bytes (a
    /// vectorised search per field costs more than it saves on fields of a few
    /// bytes) and trimmed of ASCII whitespace; false at the first quote.
    fn split_unquoted(&mut self, line: &str) -> bool {
        let bytes = line.as_bytes();
        // `delimiter` is ASCII: field ends are character boundaries.
        let mut push = |a: usize, b: usize| {
            let f = &bytes[a..b];
            let lead = f.len() - f.trim_ascii_start().len();
            self.fields
                .push((a + lead, a + lead + f.trim_ascii().len()));
        };
        let mut start = 0;
        for (i, &b) in bytes.iter().enumerate() {
            if b == self.delimiter {
                push(start, i);
                start = i + 1;
            } else if b == b'"' {
                return false;
            }
        }
        push(start, bytes.len());
        true
    }

    /// Split `line` into [`Splitter::fields`]; their number. A line without quotes
    /// (nearly every line) is split directly, trimming ASCII whitespace; a quoted one
    /// goes through the CSV parser and its fields are trimmed as `csv::Trim::All`
    /// trims them.
    fn split(&mut self, line: &str) -> usize {
        self.fields.clear();
        self.in_out = false;
        if self.split_unquoted(line) {
            return self.fields.len();
        }
        self.fields.clear();
        self.in_out = true;
        use csv_core::ReadRecordResult as R;
        self.quoted.reset();
        let (mut input, mut nout, mut nend) = (line.as_bytes(), 0, 0);
        loop {
            let (res, nin, o, e) =
                self.quoted
                    .read_record(input, &mut self.out[nout..], &mut self.out_ends[nend..]);
            input = &input[nin..];
            nout += o;
            nend += e;
            match res {
                // All of the line read: the next call, with no input, ends the record.
                R::InputEmpty => {}
                R::OutputFull => self.out.resize(2 * self.out.len(), 0),
                R::OutputEndsFull => self.out_ends.resize(2 * self.out_ends.len(), 0),
                R::Record | R::End => break,
            }
        }
        let mut start = 0;
        for &end in &self.out_ends[..nend] {
            // The parser only drops quote bytes from UTF-8 text: the field is UTF-8.
            let f = std::str::from_utf8(&self.out[start..end]).expect("UTF-8 without quotes");
            let lead = f.len() - f.trim_start().len();
            self.fields
                .push((start + lead, start + lead + f.trim().len()));
            start = end;
        }
        nend
    }

    /// The text of field `i` of `line`, the line last split.
    fn field<'a>(&'a self, line: &'a str, i: usize) -> &'a str {
        let (a, b) = self.fields[i];
        if self.in_out {
            std::str::from_utf8(&self.out[a..b]).expect("UTF-8 without quotes")
        } else {
            &line[a..b]
        }
    }
}

/// The pieces of `text` between occurrences of the ASCII byte `sep`, as
/// `text.split(char::from(sep))` gives them, found by a vectorised byte search.
fn split_bytes(text: &str, sep: u8) -> impl Iterator<Item = &str> {
    let mut start = 0;
    memchr::memchr_iter(sep, text.as_bytes())
        .chain(std::iter::once(text.len()))
        .map(move |end| {
            // `sep` is ASCII: both ends are character boundaries.
            let piece = &text[start..end];
            start = end + 1;
            piece
        })
}

/// What to suggest when a line has the wrong number of fields.
fn field_count_hint(line: &str, delimiter: u8, too_many: bool) -> &'static str {
    let other = [b',', b';', b'\t'].into_iter().find(|&d| {
        d != delimiter && line.as_bytes().contains(&d) && !(d == b',' && delimiter == b';')
    });
    match (other, too_many) {
        (Some(_), false) => "this line uses another separator than the header: use one separator (',', ';' or tab) throughout",
        (_, true) if delimiter == b',' && decimal_comma(line) => "a decimal comma in a comma-separated file? use '.' for decimals or ';' as the separator",
        (_, true) => "is the header the real one? lines of metadata above an export's header are skipped only when the header names the columns the command reads (see its --columns)",
        _ => "every data line needs one value per header column",
    }
}

/// Whether a line reads as numbers written with a decimal comma: no point, and a
/// digit on both sides of some comma.
fn decimal_comma(line: &str) -> bool {
    let b = line.as_bytes();
    !line.contains('.')
        && (1..b.len().saturating_sub(1))
            .any(|i| b[i] == b',' && b[i - 1].is_ascii_digit() && b[i + 1].is_ascii_digit())
}

/// Split a header like `nominal_stress_kPa`, `stress [kPa]` or `time (s)` into a
/// lower-case name and a unit. `names` are the column names that take a `_unit`
/// suffix (`force_N`, but not `forces` or `timestamp`).
pub fn split_header(h: &str, names: &[&str]) -> (String, Option<String>) {
    let h = h.trim();
    // The unit is the last bracketed group (`Tensile strain (Extension) [%]`), else
    // whatever follows the first bracket.
    let last = h
        .ends_with([')', ']'])
        .then(|| h.rfind(['[', '(']))
        .flatten();
    if let Some(open) = last.or_else(|| h.find(['[', '('])) {
        let name = h[..open].trim().trim_end_matches('_');
        let unit = h[open + 1..].trim_end_matches([']', ')']).trim();
        return (
            name.to_ascii_lowercase().replace(' ', "_"),
            Some(unit.to_string()),
        );
    }
    let lower = h.to_ascii_lowercase();
    for &prefix in names {
        // `force_N` or `force`, but not `forces` or `timestamp`.
        match lower.strip_prefix(prefix) {
            Some("") => return (prefix.to_string(), None),
            Some(rest) if rest.starts_with('_') => {
                let unit = &h[prefix.len() + 1..];
                return (
                    prefix.to_string(),
                    (!unit.is_empty()).then(|| unit.to_string()),
                );
            }
            _ => {}
        }
    }
    (lower.replace(' ', "_"), None)
}

/// The SI factor of column `c`'s header unit (`unit`, as split from the header) of
/// dimension `dim`: a located error when it is missing or unknown, with the closest
/// accepted spelling as a hint.
pub fn column_unit(table: &Table, c: usize, unit: Option<&str>, dim: Dimension) -> Result<f64> {
    let h = &table.header[c];
    let loc = Location::at(&table.path, table.header_line, c + 1);
    let Some(u) = unit else {
        return Err(
            Error::input(loc, format!("column '{h}' has no unit")).with_hint(format!(
                "write it as e.g. '{}_{}'",
                h.trim(),
                dim.units()[0].0
            )),
        );
    };
    dim.factor(u).ok_or_else(|| {
        let hint = match dim.suggest(u) {
            Some(s) => format!(
                "units are case-sensitive: did you mean '{s}'? expected one of {}",
                dim.accepted()
            ),
            None => format!("expected one of {}", dim.accepted()),
        };
        Error::input(loc, format!("unknown unit '{u}' in column '{h}'")).with_hint(hint)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fields of one line as a csv reader built for that line gives them (the
    /// reader's former method, kept here as the reference).
    fn csv_fields(line: &str, delimiter: u8) -> Vec<String> {
        let mut reader = csv::ReaderBuilder::new()
            .delimiter(delimiter)
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .terminator(csv::Terminator::Any(b'\n'))
            .from_reader(line.as_bytes());
        let mut record = csv::StringRecord::new();
        match reader.read_record(&mut record) {
            Ok(true) => record.iter().map(str::to_string).collect(),
            _ => Vec::new(),
        }
    }

    const PIECES: &[&str] = &[
        "1.5", "kPa", ",", ";", "\t", "\"", "\"\"", " ", "\r", "\u{feff}", "é", "\u{a0}", "a b",
        "#", "-2e3",
    ];

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]
        /// The splitter gives, line by line, the fields a csv reader per line gave,
        /// with or without quotes, for each separator.
        #[test]
        fn splitter_agrees_with_a_csv_reader_per_line(
            picks in proptest::collection::vec(0..PIECES.len(), 1..24),
            sep in 0..3usize,
        ) {
            let line: String = picks.iter().map(|&i| PIECES[i]).collect();
            let line = line.trim();
            proptest::prop_assume!(!line.is_empty());
            let first = ["a,b", "a;b", "a\tb"][sep];
            let mut splitter = Splitter::new(delimiter_of(first));
            // A line before it, so that the splitter's buffers hold more than this line.
            splitter.split("x\"y\",z");
            let n = splitter.split(line);
            let got: Vec<&str> = (0..n).map(|i| splitter.field(line, i)).collect();
            proptest::prop_assert_eq!(n, got.len());
            let want = csv_fields(line, splitter.delimiter);
            if line.contains('"') {
                proptest::prop_assert_eq!(got, want);
            } else {
                // Unquoted lines are split directly and trimmed of ASCII whitespace only,
                // as before: compare with that.
                let direct: Vec<&str> = line
                    .split(char::from(splitter.delimiter))
                    .map(|f| f.trim_matches(|c: char| c.is_ascii_whitespace()))
                    .collect();
                proptest::prop_assert_eq!(got, direct);
            }
        }
    }

    const NUMBER_PIECES: &[&str] = &[
        "0",
        "1",
        "9",
        "12345678901234567890",
        ".",
        "e",
        "E",
        "-",
        "+",
        "inf",
        "infinity",
        "nan",
        "NaN",
        "INF",
        "x",
        " ",
        "_",
        "0x",
        "e308",
        "e-330",
        "1e400",
    ];

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(4000))]
        /// A field reads as the number `str::parse::<f64>` gives, bit for bit, or is
        /// refused where it refuses it (the fast parser changes no result).
        #[test]
        fn numbers_read_as_str_parse_reads_them(
            picks in proptest::collection::vec(0..NUMBER_PIECES.len(), 1..8),
            digits in proptest::collection::vec(0..10u32, 0..24),
        ) {
            let mut field: String = picks.iter().map(|&i| NUMBER_PIECES[i]).collect();
            field.extend(digits.iter().map(|&d| char::from_digit(d, 10).unwrap()));
            let got = parse_f64(field.as_bytes());
            let want = field.parse::<f64>().ok();
            proptest::prop_assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{}", field);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(20000))]
        /// Plain decimals of up to 16 digits with a point anywhere and any sign (the
        /// fast path and the edge where it hands over) read bit for bit as
        /// `str::parse::<f64>` reads them.
        #[test]
        fn plain_decimals_read_as_str_parse_reads_them(
            m in 0u64..10_000_000_000_000_000,
            point in 0usize..18,
            sign in 0usize..3,
            zeros in 0usize..3,
        ) {
            let digits = format!("{}{m}", "0".repeat(zeros));
            let at = point.min(digits.len());
            let field = format!("{}{}.{}", ["", "-", "+"][sign], &digits[..at], &digits[at..]);
            for f in [field.as_str(), field.trim_end_matches('.'), &digits] {
                let want = f.parse::<f64>().ok();
                proptest::prop_assert_eq!(parse_f64(f.as_bytes()).map(f64::to_bits), want.map(f64::to_bits), "{}", f);
            }
        }
    }

    /// A file of several parts: every row, field, line number and directive is where
    /// a line-by-line reading puts it, across the part boundaries, with CRLF ends,
    /// comments, blank and quoted lines among the rows.
    #[test]
    fn a_file_read_in_parts_is_the_file_read_line_by_line() {
        let mut text = String::from("# mode: planar\r\nstretch,stress_kPa\r\n");
        let mut want = Vec::new();
        let mut line = 2;
        while text.len() < 5 * PART_BYTES / 2 {
            line += 1;
            let i = want.len();
            match i % 97 {
                13 => text.push_str("\r\n"),
                29 => text.push_str(&format!("# note {i}: kept\r\n")),
                41 => {
                    text.push_str(&format!("\"{i}.5\", \" {i} \"\r\n"));
                    want.push((line, format!("{i}.5"), i.to_string()));
                }
                _ => {
                    text.push_str(&format!(" {i}.25 ,{}\r\n", 2 * i));
                    want.push((line, format!("{i}.25"), (2 * i).to_string()));
                }
            }
        }
        assert!(part_ranges(&text, b'\n').len() > 1);
        let t = Table::parse(Path::new("t.csv"), text.as_bytes()).unwrap();
        assert_eq!(
            part_ranges(&text, b'\n').len(),
            2,
            "the body is read in parts"
        );
        let got: Vec<(usize, String, String)> = t
            .rows
            .iter()
            .map(|r| {
                (
                    r.line(),
                    t.field(r, 0).to_string(),
                    t.field(r, 1).to_string(),
                )
            })
            .collect();
        assert_eq!(got, want);
        let notes: Vec<usize> = t.directives.iter().map(|d| d.0).collect();
        let want_notes: Vec<usize> = text
            .split('\n')
            .enumerate()
            .filter(|(_, l)| l.starts_with('#'))
            .map(|(i, _)| i + 1)
            .collect();
        assert_eq!(notes, want_notes);

        // A short row in the second part and one in the third: the first is reported.
        let mut lines: Vec<&str> = text.split('\n').collect();
        let (a, b) = (lines.len() * 2 / 3, lines.len() * 9 / 10);
        lines[b] = "7\r";
        lines[a] = "8\r";
        let bad = lines.join("\n");
        let e = Table::parse(Path::new("t.csv"), bad.as_bytes()).unwrap_err();
        assert!(e.to_string().contains(&format!("t.csv:{}:2", a + 1)), "{e}");
    }

    /// An export: the preamble is skipped with its lines counted (a `#` directive in
    /// it kept), the units row read into the header, line numbers those of the file;
    /// without a header the export is read as a plain table; CR-only ends work too.
    #[test]
    fn exports_skip_their_preamble_and_read_their_units_row() {
        let is_header = |f: &[&str]| f.contains(&"Load");
        let text = "\"Sample\",\"A\"\n# mode: planar\n\"Width\",\"10\",\"mm\"\n\n\"Time\",\"Extension\",\"Load\"\n\"(s)\",\"(mm)\",\"(N)\"\n\"0.5\",\"1.0\",\"2.0\"\n";
        for text in [text.to_string(), text.replace('\n', "\r")] {
            let e = Table::parse_export(Path::new("e.csv"), text.as_bytes(), &is_header).unwrap();
            let t = &e.table;
            assert_eq!(t.header, ["Time [s]", "Extension [mm]", "Load [N]"]);
            assert_eq!((t.header_line, t.rows.len(), t.rows[0].line()), (5, 1, 7));
            assert_eq!(
                t.directives,
                [(2, "mode".to_string(), "planar".to_string())]
            );
            assert_eq!(
                e.notes,
                [
                    "2 preamble lines before the header on line 5 skipped",
                    "units row on line 6 read into the header: Time [s], Extension [mm], Load [N]"
                ]
            );
            assert_eq!(t.sha256, super::super::sha256_hex(text.as_bytes()));
        }
        // No line names the columns: the first line is the header, and the hint of the
        // field-count error is not "a decimal comma?".
        let e = Table::parse_export(Path::new("e.csv"), text.as_bytes(), &|_| false).unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("e.csv:3:3") && e.contains("is the header the real one?"),
            "{e}"
        );
        // A value with a prefix (`1k`) is not a unit; a units row without data rows is
        // an error.
        let t = Table::parse(Path::new("u.csv"), b"f,c\n1k,2p\n").unwrap();
        let mut t2 = t.clone();
        assert!(t2.units_row().unwrap().is_none());
        let mut u = Table::parse(Path::new("u.csv"), b"f,c\n(Hz),(F)\n").unwrap();
        assert!(u
            .units_row()
            .unwrap_err()
            .to_string()
            .contains("no data rows"));
    }

    /// `--columns`: roles, units, quotes in a file, and its errors.
    #[test]
    fn column_maps_parse_and_find_their_columns() {
        let roles = ["stretch", "force"];
        let m = ColumnMap::parse("stretch=Extension:mm, force = Load", &roles).unwrap();
        assert_eq!(m.find("Extension [mm]"), Some(("stretch", Some("mm"))));
        assert_eq!(m.find("load"), Some(("force", None)));
        assert_eq!(m.find("Time"), None);
        for (bad, want) in [
            ("stretch", "expected ROLE=COLUMN[:UNIT]"),
            ("strain=x", "unknown role 'strain'"),
            ("stretch=a,stretch=b", "role 'stretch' given twice"),
            ("force=", "names no column"),
        ] {
            let e = ColumnMap::parse(bad, &roles).unwrap_err().to_string();
            assert!(e.contains(want), "{bad}: {e}");
        }
    }

    /// A large file's table holds its fields in the file's own bytes, with 4 bytes
    /// per field end and 8 per row (it held a copy of the fields, 8 bytes per end and
    /// 16 per row): at most the file and 16 bytes per two-column row.
    #[test]
    fn a_table_holds_its_file_and_16_bytes_per_two_column_row() {
        let n = 300_000;
        let mut text = String::from("time_s,stress_kPa\n");
        for i in 0..n {
            text.push_str(&format!("{i}.5, {}\n", 2 * i));
        }
        let t = Table::parse(Path::new("t.csv"), text.as_bytes()).unwrap();
        assert!(part_ranges(&text, b'\n').len() > 2, "read in parts");
        assert_eq!(t.rows.len(), n);
        assert_eq!(std::mem::size_of::<Row>(), 8);
        let index = t.ends.capacity() * std::mem::size_of_val(&t.ends[0])
            + t.rows.capacity() * std::mem::size_of::<Row>();
        // A start slot per part beside the two ends per row.
        assert!(
            index <= 16 * n + 4 * 64,
            "{index} bytes of index for {n} rows"
        );
        assert!(
            t.cells.capacity() <= text.len(),
            "the fields are in the file's bytes"
        );
        // The fields and lines are those of the text.
        for (i, r) in t.rows.iter().enumerate().step_by(997) {
            assert_eq!(r.line(), i + 2);
            assert_eq!(t.field(r, 0), format!("{i}.5"));
            assert_eq!(t.field(r, 1), (2 * i).to_string());
        }
    }

    /// A file read from disk (hashed a block at a time as read, then split in its own
    /// bytes) is the table its text parses to, with the SHA-256 of its bytes; exports
    /// read from disk too.
    #[test]
    fn a_file_read_from_disk_is_its_text_parsed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.csv");
        let mut text = String::from("\u{feff}# a: b\n\"Time\",\"Load\"\n\"(s)\",\"(N)\"\n");
        for i in 0..200_000 {
            text.push_str(&format!("{i}.25,\"{}\"\r\n", 3 * i));
        }
        std::fs::write(&path, &text).unwrap();
        let from_disk = Table::read(&path).unwrap();
        let parsed = Table::parse(&path, text.as_bytes()).unwrap();
        assert_eq!(from_disk.sha256, super::super::sha256_hex(text.as_bytes()));
        assert_eq!(from_disk.sha256, parsed.sha256);
        assert_eq!(from_disk.directives, parsed.directives);
        let rows = |t: &Table| -> Vec<(usize, String, String)> {
            t.rows
                .iter()
                .map(|r| (r.line(), t.field(r, 0).into(), t.field(r, 1).into()))
                .collect()
        };
        assert_eq!(rows(&from_disk), rows(&parsed));
        let is_header = |f: &[&str]| f.contains(&"Load");
        let e = Table::read_export(&path, &is_header).unwrap();
        assert_eq!(e.table.header, ["Time [s]", "Load [N]"]);
        assert_eq!(e.table.sha256, parsed.sha256);
        assert_eq!(rows(&e.table)[..], rows(&parsed)[1..]);
    }

    #[test]
    fn rows_and_fields_are_located() {
        let text = "# mode: planar\nstretch;stress_kPa\n\n1,5; 2\n ; \n\"3;0\";\"4\"\"\"\n";
        let t = Table::parse(Path::new("t.csv"), text.as_bytes()).unwrap();
        assert_eq!(t.header, ["stretch", "stress_kPa"]);
        assert_eq!(t.header_line, 2);
        assert_eq!(
            t.directives,
            [(1, "mode".to_string(), "planar".to_string())]
        );
        let lines: Vec<usize> = t.rows.iter().map(Row::line).collect();
        assert_eq!(lines, [4, 6]);
        assert_eq!(t.field(&t.rows[0], 0), "1,5");
        assert_eq!(t.number(&t.rows[0], 0, "x").unwrap(), 1.5);
        assert_eq!(t.field(&t.rows[1], 0), "3;0");
        assert_eq!(t.field(&t.rows[1], 1), "4\"");
    }
}
