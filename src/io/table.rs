//! A located reader for delimited text tables (CSV, `;`- or tab-separated).
//!
//! Accepts `#` comment lines (a `# key: value` comment is kept as a directive),
//! blank lines, a UTF-8 BOM, LF, CRLF or CR line ends, double-quoted fields, and a
//! decimal comma when the separator is `;`. Lines whose fields are all empty count as
//! blank. Every field keeps its line and column so that errors can point at it; a
//! spreadsheet, UTF-16 or Latin-1 file is recognised and named as such.

use crate::error::{Error, Location, Result};
use crate::units::Dimension;
use std::path::{Path, PathBuf};

/// One data row.
#[derive(Debug, Clone)]
pub struct Row {
    /// 1-based line number in the file.
    pub line: usize,
    /// Trimmed fields.
    pub fields: Vec<String>,
}

/// A parsed table: header, rows, `# key: value` directives and provenance.
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
}

impl Table {
    /// Read and split a file.
    pub fn read(path: &Path) -> Result<Table> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::parse(path, &bytes)
    }

    /// Split bytes that came from `path`.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Table> {
        let sha256 = super::sha256_hex(bytes);
        let text = decode(path, bytes)?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Lines end in LF or CRLF; a file without any LF may use classic-Mac CR ends.
        let lines: Vec<&str> = if text.contains('\n') {
            text.split('\n')
                .map(|l| l.strip_suffix('\r').unwrap_or(l))
                .collect()
        } else {
            text.split('\r').collect()
        };

        let mut directives = Vec::new();
        let mut content = Vec::new();
        for (i, line) in lines.iter().enumerate() {
            let t = line.trim();
            if let Some(c) = t.strip_prefix('#') {
                if let Some((k, v)) = c.split_once(':') {
                    directives.push((i + 1, k.trim().to_ascii_lowercase(), v.trim().to_string()));
                }
            } else if !t.is_empty() {
                content.push((i + 1, t));
            }
        }
        let no_header = || {
            Error::input(Location::file(path), "the file holds no header and no data").with_hint(
                "the first non-comment line must name the columns, e.g. stretch,nominal_stress_kPa",
            )
        };
        let &(_, first) = content.first().ok_or_else(no_header)?;
        let delimiter = if first.contains('\t') {
            b'\t'
        } else if first.contains(';') {
            b';'
        } else {
            b','
        };

        let mut header: Option<(usize, Vec<String>)> = None;
        let mut rows = Vec::new();
        for (line, text) in content {
            let fields = split_fields(text, delimiter);
            if fields.iter().all(String::is_empty) {
                continue;
            }
            let Some((header_line, header)) = &header else {
                header = Some((line, fields));
                continue;
            };
            if fields.len() != header.len() {
                return Err(Error::input(
                    Location::at(path, line, fields.len().min(header.len()) + 1),
                    format!(
                        "expected {} fields (as in the header on line {header_line}), found {}",
                        header.len(),
                        fields.len()
                    ),
                )
                .with_hint(field_count_hint(
                    text,
                    delimiter,
                    fields.len() > header.len(),
                )));
            }
            rows.push(Row { line, fields });
        }
        let (header_line, header) = header.ok_or_else(no_header)?;
        if rows.is_empty() {
            return Err(Error::input(
                Location::line(path, header_line),
                "the file has a header but no data rows",
            )
            .with_hint("add one line per measured point below the header"));
        }
        Ok(Table {
            path: path.to_path_buf(),
            sha256,
            header,
            header_line,
            rows,
            directives,
            delimiter,
        })
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
        Location::at(&self.path, row.line, col + 1)
    }

    /// A finite number in `row`, column `col` (0-based), named `what` in errors.
    pub fn number(&self, row: &Row, col: usize, what: &str) -> Result<f64> {
        let raw = &row.fields[col];
        let text = if self.delimiter == b';' {
            raw.replace(',', ".")
        } else {
            raw.clone()
        };
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(Error::input(
                self.loc(row, col),
                format!("{what} must be a finite number, found '{raw}'"),
            )),
            Err(_) if raw.is_empty() => Err(Error::input(
                self.loc(row, col),
                format!("{what} is empty; expected a number"),
            )),
            Err(_) => {
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

/// Trimmed fields of one line (double quotes may wrap a field holding the separator).
/// A line without quotes (nearly every line) is split directly: building a csv
/// reader per line took 30 µs, 90 % of the time of reading a 10⁶-row file.
fn split_fields(line: &str, delimiter: u8) -> Vec<String> {
    if !line.contains('"') {
        return line
            .split(char::from(delimiter))
            .map(|f| {
                f.trim_matches(|c: char| c.is_ascii_whitespace())
                    .to_string()
            })
            .collect();
    }
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        // The caller split the lines: a stray CR is text, not a record end.
        .terminator(csv::Terminator::Any(b'\n'))
        .buffer_capacity(line.len() + 1)
        .from_reader(line.as_bytes());
    let mut record = csv::StringRecord::new();
    match reader.read_record(&mut record) {
        Ok(true) => record.iter().map(str::to_string).collect(),
        // A &str holds valid UTF-8 and cannot fail to read; an empty line has no fields.
        _ => Vec::new(),
    }
}

/// What to suggest when a line has the wrong number of fields.
fn field_count_hint(line: &str, delimiter: u8, too_many: bool) -> &'static str {
    let other = [b',', b';', b'\t'].into_iter().find(|&d| {
        d != delimiter && line.as_bytes().contains(&d) && !(d == b',' && delimiter == b';')
    });
    match (other, too_many) {
        (Some(_), false) => "this line uses another separator than the header: use one separator (',', ';' or tab) throughout",
        (_, true) if delimiter == b',' => "a decimal comma in a comma-separated file? use '.' for decimals or ';' as the separator",
        _ => "every data line needs one value per header column",
    }
}

/// Split a header like `nominal_stress_kPa`, `stress [kPa]` or `time (s)` into a
/// lower-case name and a unit. `names` are the column names that take a `_unit`
/// suffix (`force_N`, but not `forces` or `timestamp`).
pub fn split_header(h: &str, names: &[&str]) -> (String, Option<String>) {
    let h = h.trim();
    if let Some(open) = h.find(['[', '(']) {
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
