//! A located reader for delimited text tables (CSV, `;`- or tab-separated).
//!
//! Accepts `#` comment lines (a `# key: value` comment is kept as a directive),
//! blank lines, a UTF-8 BOM, CRLF line ends, and a decimal comma when the separator
//! is `;`. Every field keeps its line and column so that errors can point at it.

use crate::error::{Error, Location, Result};
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
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let line = bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
                + 1;
            Error::input(
                Location::line(path, line),
                "the file is not UTF-8 text (is it a spreadsheet or a binary export?)",
            )
            .with_hint("save it as CSV (UTF-8) and try again")
        })?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);

        let mut directives = Vec::new();
        let mut first_data_line: Option<&str> = None;
        for (i, line) in text.lines().enumerate() {
            let t = line.trim();
            if let Some(c) = t.strip_prefix('#') {
                if let Some((k, v)) = c.split_once(':') {
                    directives.push((i + 1, k.trim().to_ascii_lowercase(), v.trim().to_string()));
                }
            } else if !t.is_empty() && first_data_line.is_none() {
                first_data_line = Some(t);
            }
        }
        let Some(first) = first_data_line else {
            return Err(Error::input(
                Location::file(path),
                "the file holds no header and no data",
            )
            .with_hint("the first non-comment line must name the columns, e.g. stretch,nominal_stress_kPa"));
        };
        let delimiter = if first.contains('\t') {
            b'\t'
        } else if first.contains(';') {
            b';'
        } else {
            b','
        };

        let mut reader = csv::ReaderBuilder::new()
            .delimiter(delimiter)
            .has_headers(false)
            .flexible(true)
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let mut header: Option<(usize, Vec<String>)> = None;
        let mut rows = Vec::new();
        for rec in reader.records() {
            let rec = rec.map_err(|e| {
                let line = e.position().map(|p| p.line() as usize).unwrap_or(0);
                Error::input(
                    Location::line(path, line.max(1)),
                    format!("unreadable line: {e}"),
                )
            })?;
            let line = rec.position().map(|p| p.line() as usize).unwrap_or(0);
            let fields: Vec<String> = rec.iter().map(str::to_string).collect();
            if fields.iter().all(String::is_empty) {
                continue;
            }
            if header.is_none() {
                header = Some((line, fields));
            } else {
                rows.push(Row { line, fields });
            }
        }
        let (header_line, header) = header.expect("a non-comment line exists");
        let table = Table {
            path: path.to_path_buf(),
            sha256,
            header,
            header_line,
            rows,
            directives,
            delimiter,
        };
        for row in &table.rows {
            if row.fields.len() != table.header.len() {
                return Err(Error::input(
                    Location::at(path, row.line, row.fields.len().min(table.header.len()) + 1),
                    format!(
                        "expected {} fields (as in the header on line {}), found {}",
                        table.header.len(),
                        table.header_line,
                        row.fields.len()
                    ),
                )
                .with_hint(if table.delimiter == b',' && row.fields.len() > table.header.len() {
                    "a decimal comma in a comma-separated file? use '.' for decimals or ';' as the separator"
                } else {
                    "every data line needs one value per header column"
                }));
            }
        }
        if table.rows.is_empty() {
            return Err(Error::input(
                Location::line(path, table.header_line),
                "the file has a header but no data rows",
            ));
        }
        Ok(table)
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
            Err(_) => Err(Error::input(
                self.loc(row, col),
                format!("expected a number for {what}, found '{raw}'"),
            )),
        }
    }
}
