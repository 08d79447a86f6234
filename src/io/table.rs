//! A located reader for delimited text tables (CSV, `;`- or tab-separated).
//!
//! Accepts `#` comment lines (a `# key: value` comment is kept as a directive),
//! blank lines, a UTF-8 BOM, LF, CRLF or CR line ends, double-quoted fields, and a
//! decimal comma when the separator is `;`. Lines whose fields are all empty count as
//! blank. Every field keeps its line and column so that errors can point at it; a
//! spreadsheet, UTF-16 or Latin-1 file is recognised and named as such.

use crate::error::{Error, Location, Result};
use crate::units::Dimension;
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// One data row: its line and where its fields start in the table's field store
/// (read them with [`Table::field`]).
#[derive(Debug, Clone, Copy)]
pub struct Row {
    /// 1-based line number in the file.
    pub line: usize,
    /// Index of the row's first field in [`Table`]'s `ends`.
    first: usize,
}

/// A parsed table: header, rows, `# key: value` directives and provenance.
///
/// The data fields are held back to back in one string (`cells`, with the end of each
/// field in `ends`), not as a string per field: a 10⁶-row file then costs three
/// allocations instead of three million.
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
    /// Every data field, trimmed, back to back.
    cells: String,
    /// The end of each field in `cells`.
    ends: Vec<usize>,
}

impl Table {
    /// Read and split a file.
    pub fn read(path: &Path) -> Result<Table> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::parse(path, &bytes)
    }

    /// Split bytes that came from `path`, in one pass over the lines.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Table> {
        let sha256 = super::sha256_hex(bytes);
        let text = decode(path, bytes)?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Lines end in LF or CRLF; a file without any LF may use classic-Mac CR ends.
        let end = if memchr::memchr(b'\n', text.as_bytes()).is_some() {
            b'\n'
        } else {
            b'\r'
        };
        let lines = split_bytes(text, end)
            .map(|l| l.strip_suffix('\r').unwrap_or(l))
            .enumerate();

        let mut directives = Vec::new();
        let mut splitter: Option<Splitter> = None;
        let mut header: Option<(usize, Vec<String>)> = None;
        // At most one row a line: reserved once, the row and field lists of a 10⁶-row
        // file are never copied to grow.
        let line_count = 1 + memchr::memchr_iter(end, text.as_bytes()).count();
        let mut rows = Vec::with_capacity(line_count);
        // The fields are a subset of the text: one allocation holds them all.
        let mut cells = String::with_capacity(text.len());
        let mut ends = Vec::new();
        for (i, line) in lines {
            let (line, t) = (i + 1, line.trim());
            if let Some(c) = t.strip_prefix('#') {
                if let Some((k, v)) = c.split_once(':') {
                    directives.push((line, k.trim().to_ascii_lowercase(), v.trim().to_string()));
                }
                continue;
            } else if t.is_empty() {
                continue;
            }
            // The first content line sets the separator.
            let splitter = splitter.get_or_insert_with(|| Splitter::new(t));
            let (first, from) = (ends.len(), cells.len());
            let n = splitter.split(t, &mut cells, &mut ends);
            if cells.len() == from {
                // Every field is empty: a blank line.
                ends.truncate(first);
                continue;
            }
            let Some((header_line, header)) = &header else {
                let mut start = from;
                let names = ends[first..]
                    .iter()
                    .map(|&e| {
                        let name = cells[start..e].to_string();
                        start = e;
                        name
                    })
                    .collect();
                ends.truncate(first);
                cells.truncate(from);
                ends.reserve(line_count * n);
                header = Some((line, names));
                continue;
            };
            if n != header.len() {
                return Err(Error::input(
                    Location::at(path, line, n.min(header.len()) + 1),
                    format!(
                        "expected {} fields (as in the header on line {header_line}), found {n}",
                        header.len(),
                    ),
                )
                .with_hint(field_count_hint(
                    t,
                    splitter.delimiter,
                    n > header.len(),
                )));
            }
            rows.push(Row { line, first });
        }
        let no_header = || {
            Error::input(Location::file(path), "the file holds no header and no data").with_hint(
                "the first non-comment line must name the columns, e.g. stretch,nominal_stress_kPa",
            )
        };
        let (Some(splitter), Some((header_line, header))) = (splitter, header) else {
            return Err(no_header());
        };
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
            delimiter: splitter.delimiter,
            cells,
            ends,
        })
    }

    /// The trimmed text of `row`'s field in column `col` (0-based).
    pub fn field(&self, row: &Row, col: usize) -> &str {
        let i = row.first + col;
        let start = if i == 0 { 0 } else { self.ends[i - 1] };
        &self.cells[start..self.ends[i]]
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
        let raw = self.field(row, col);
        let text = if self.delimiter == b';' && raw.contains(',') {
            Cow::Owned(raw.replace(',', "."))
        } else {
            Cow::Borrowed(raw)
        };
        match fast_float2::parse::<f64, _>(text.as_bytes()) {
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

/// Splits lines into trimmed fields (double quotes may wrap a field holding the
/// separator), appending each field to one store.
struct Splitter {
    delimiter: u8,
    /// The CSV parser for lines with quotes, reset for each line: it reads a line as
    /// `csv::Reader` would (the same parser inside), without building one per line.
    quoted: csv_core::Reader,
    /// Its output buffers, reused from line to line.
    out: Vec<u8>,
    out_ends: Vec<usize>,
}

impl Splitter {
    /// The separator of the first content line: tab, else `;`, else `,`.
    fn new(first: &str) -> Splitter {
        let delimiter = if first.contains('\t') {
            b'\t'
        } else if first.contains(';') {
            b';'
        } else {
            b','
        };
        Splitter {
            delimiter,
            quoted: csv_core::ReaderBuilder::new()
                .delimiter(delimiter)
                // The caller split the lines: a stray CR is text, not a record end.
                .terminator(csv_core::Terminator::Any(b'\n'))
                .build(),
            out: vec![0; 256],
            out_ends: vec![0; 16],
        }
    }

    /// Append the fields of `line` to `cells` (their ends to `ends`); the number of
    /// fields. A line without quotes (nearly every line) is split directly, trimming
    /// ASCII whitespace; a quoted one goes through the CSV parser and its fields are
    /// trimmed as `csv::Trim::All` trims them.
    fn split(&mut self, line: &str, cells: &mut String, ends: &mut Vec<usize>) -> usize {
        if memchr::memchr(b'"', line.as_bytes()).is_none() {
            let mut n = 0;
            for f in split_bytes(line, self.delimiter) {
                cells.push_str(f.trim_matches(|c: char| c.is_ascii_whitespace()));
                ends.push(cells.len());
                n += 1;
            }
            return n;
        }
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
            cells.push_str(String::from_utf8_lossy(&self.out[start..end]).trim());
            ends.push(cells.len());
            start = end;
        }
        nend
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
            let mut splitter = Splitter::new(first);
            let (mut cells, mut ends) = (String::new(), Vec::new());
            // A line before it, so that the store holds more than this line.
            splitter.split("x\"y\",z", &mut cells, &mut ends);
            let (from, first_end) = (cells.len(), ends.len());
            let n = splitter.split(line, &mut cells, &mut ends);
            let mut start = from;
            let got: Vec<&str> = ends[first_end..]
                .iter()
                .map(|&e| {
                    let f = &cells[start..e];
                    start = e;
                    f
                })
                .collect();
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
            let got = fast_float2::parse::<f64, _>(field.as_bytes()).ok();
            let want = field.parse::<f64>().ok();
            proptest::prop_assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{}", field);
        }
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
        let lines: Vec<usize> = t.rows.iter().map(|r| r.line).collect();
        assert_eq!(lines, [4, 6]);
        assert_eq!(t.field(&t.rows[0], 0), "1,5");
        assert_eq!(t.number(&t.rows[0], 0, "x").unwrap(), 1.5);
        assert_eq!(t.field(&t.rows[1], 0), "3;0");
        assert_eq!(t.field(&t.rows[1], 1), "4\"");
    }
}
