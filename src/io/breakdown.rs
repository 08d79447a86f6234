//! Breakdown series (`dea-fit breakdown`): one specimen a row, units in the header.
//!
//! Columns (any order; `name_unit`, `name [unit]` or `name (unit)`, with `_per_` read
//! as `/`):
//! * the field at breakdown: `field_V_per_um`, `field_kV_per_mm`, `field_MV_per_m`
//!   (any electric-field unit), **or** `voltage_V|kV` with the film thickness,
//!   `thickness_um|mm` per row or `--thickness` for every row (E = V/h);
//! * optional `survived` (0 or 1: the specimen did not break down up to that field,
//!   e.g. at the rig's limit: right-censored), `area_mm2` (electrode area; else
//!   `--specimen-area`), `prestretch` (λ), `specimen` (a label).
//!
//! Ties are accepted (stepped ramps give them). Refused with the file, line and
//! column and a hint: a non-positive or non-finite field, voltage, thickness, area or
//! prestretch, `survived` other than 0/1, a column without its unit, two columns for
//! one quantity (a field and a voltage, two fields), a value given both by a column
//! and by its flag, fewer than two breakdowns, every specimen survived.

use super::table::{column_unit, split_header, Row, Table};
use crate::error::{Error, Location, Result};
use crate::units::Dimension;
use std::path::{Path, PathBuf};

/// Values for every row of a series that the file does not hold.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BreakdownOptions {
    /// Film thickness (m) of every specimen (`--thickness`).
    pub thickness: Option<f64>,
    /// Electrode area (m²) of every specimen (`--specimen-area`).
    pub area: Option<f64>,
}

/// One specimen, SI.
#[derive(Debug, Clone, PartialEq)]
pub struct BreakdownSpecimen {
    /// Line of the file.
    pub line: usize,
    /// Its label (`specimen` column), if any.
    pub label: Option<String>,
    /// Breakdown field, or the highest field a survivor reached (V/m).
    pub field: f64,
    /// Did not break down up to `field` (right-censored).
    pub survived: bool,
    /// Electrode area (m²).
    pub area: Option<f64>,
    /// Film thickness (m).
    pub thickness: Option<f64>,
    /// Prestretch λ (1).
    pub prestretch: Option<f64>,
}

/// A breakdown series as read.
#[derive(Debug, Clone, PartialEq)]
pub struct BreakdownSeries {
    /// The file.
    pub path: PathBuf,
    /// SHA-256 of its bytes.
    pub sha256: String,
    /// Specimens in file order.
    pub specimens: Vec<BreakdownSpecimen>,
    /// How the fields were obtained, in words (e.g. "field = voltage / thickness").
    pub conversions: Vec<String>,
}

impl BreakdownSpecimen {
    /// The specimen as the Weibull estimators take it (SI).
    pub fn weibull(&self) -> crate::fit::weibull::Specimen {
        crate::fit::weibull::Specimen {
            field: self.field,
            survived: self.survived,
            area: self.area,
            thickness: self.thickness,
            prestretch: self.prestretch,
        }
    }
}

impl BreakdownSeries {
    /// Specimens that broke down.
    pub fn failures(&self) -> usize {
        self.specimens.iter().filter(|s| !s.survived).count()
    }
}

/// The columns a series may hold, for error hints.
const ACCEPTED: &str = "field_V_per_um|field_kV_per_mm|field_MV_per_m, or voltage_V|voltage_kV with thickness_um|thickness_mm; optional survived, area_mm2, prestretch, specimen";
/// A header line to suggest.
const EXAMPLE: &str = "specimen,field_V_per_um,survived";

/// Read a breakdown series file.
pub fn read(path: &Path, opts: &BreakdownOptions) -> Result<BreakdownSeries> {
    from_table(&Table::read(path)?, opts)
}

/// A column's unit with `_per_` (and `per`) spelt `/`: `V_per_um` → `V/um`.
fn unit_text(unit: Option<String>) -> Option<String> {
    unit.map(|u| u.replace("_per_", "/"))
}

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Column {
    /// Field, SI factor.
    Field(f64),
    /// Voltage, SI factor.
    Voltage(f64),
    /// Thickness, SI factor.
    Thickness(f64),
    /// Area, SI factor.
    Area(f64),
    Survived,
    Prestretch,
    Label,
}

impl Column {
    /// The quantity it gives: a field and a voltage both give the breakdown field.
    fn quantity(self) -> &'static str {
        match self {
            Column::Field(_) | Column::Voltage(_) => "breakdown field",
            Column::Thickness(_) => "thickness",
            Column::Area(_) => "area",
            Column::Survived => "survived",
            Column::Prestretch => "prestretch",
            Column::Label => "specimen",
        }
    }
}

/// Interpret a parsed table as a breakdown series.
pub fn from_table(table: &Table, opts: &BreakdownOptions) -> Result<BreakdownSeries> {
    let path = &table.path;
    let hloc = |c: usize| Location::at(path, table.header_line, c + 1);
    let mut columns: Vec<(usize, Column)> = Vec::new();
    for (c, h) in table.header.iter().enumerate() {
        let (name, unit) = split_header(h, &["field", "voltage", "thickness", "area"]);
        let unit = unit_text(unit);
        let col = match name.as_str() {
            "field" => Column::Field(column_unit(
                table,
                c,
                unit.as_deref(),
                Dimension::ElectricField,
            )?),
            "voltage" => {
                Column::Voltage(column_unit(table, c, unit.as_deref(), Dimension::Voltage)?)
            }
            "thickness" => {
                Column::Thickness(column_unit(table, c, unit.as_deref(), Dimension::Length)?)
            }
            "area" => Column::Area(column_unit(table, c, unit.as_deref(), Dimension::Area)?),
            "survived" => Column::Survived,
            "prestretch" | "stretch" | "lambda" => Column::Prestretch,
            "specimen" | "label" | "id" => Column::Label,
            _ => return Err(table.unknown_column(c, ACCEPTED, EXAMPLE)),
        };
        if let Some((c0, _)) = columns.iter().find(|(_, k)| k.quantity() == col.quantity()) {
            let e = Error::input(
                hloc(c),
                format!(
                    "a second {} column '{h}' (column {} is '{}')",
                    col.quantity(),
                    c0 + 1,
                    table.header[*c0]
                ),
            );
            return Err(match col {
                Column::Field(_) | Column::Voltage(_) => e.with_hint(
                    "give the breakdown in one column and one unit: a field (field_V_per_um) or a voltage (voltage_kV) with the thickness",
                ),
                _ => e.with_hint("keep one of the two columns"),
            });
        }
        columns.push((c, col));
    }
    let find = |f: fn(&Column) -> bool| columns.iter().find(|(_, k)| f(k)).copied();
    let Some((fc, field)) = find(|k| matches!(k, Column::Field(_) | Column::Voltage(_))) else {
        return Err(Error::input(
            Location::line(path, table.header_line),
            "no breakdown column: expected a field or a voltage",
        )
        .with_hint(format!(
            "name one column field_V_per_um (or field_kV_per_mm, field_MV_per_m), or voltage_kV with thickness_um; accepted: {ACCEPTED}"
        )));
    };
    let thickness_col = find(|k| matches!(k, Column::Thickness(_)));
    let area_col = find(|k| matches!(k, Column::Area(_)));
    for (flag, given, col) in [
        ("--thickness", opts.thickness.is_some(), thickness_col),
        ("--specimen-area", opts.area.is_some(), area_col),
    ] {
        if let (true, Some((c, _))) = (given, col) {
            return Err(Error::input(
                hloc(c),
                format!(
                    "{flag} was given and the file has a column '{}'",
                    table.header[c]
                ),
            )
            .with_hint(format!(
                "leave out {flag} (the column holds each specimen's value) or the column"
            )));
        }
    }
    let mut conversions = Vec::new();
    if let Column::Voltage(_) = field {
        match (thickness_col, opts.thickness) {
            (Some(_), _) => conversions.push("field = voltage / thickness (per row)".to_string()),
            (None, Some(h)) => conversions.push(format!(
                "field = voltage / thickness ({h:e} m, --thickness)"
            )),
            (None, None) => {
                return Err(Error::input(
                    hloc(fc),
                    format!(
                        "column '{}' is a voltage: the field needs the film thickness",
                        table.header[fc]
                    ),
                )
                .with_hint("add a thickness_um column, or pass --thickness for every specimen (e.g. --thickness 300um)"))
            }
        }
    }
    let positive = |row: &Row, c: usize, what: &str, factor: f64| -> Result<f64> {
        let v = table.number(row, c, what)?;
        if v > 0.0 {
            Ok(v * factor)
        } else {
            Err(Error::input(
                table.loc(row, c),
                format!("{what} must be positive, found {v}"),
            )
            .with_hint(format!(
                "a specimen's {what} is a positive number in the column's unit ('{}')",
                table.header[c]
            )))
        }
    };
    let mut specimens = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let mut s = BreakdownSpecimen {
            line: row.line(),
            label: None,
            field: f64::NAN,
            survived: false,
            area: opts.area,
            thickness: opts.thickness,
            prestretch: None,
        };
        for &(c, col) in &columns {
            match col {
                Column::Field(f) => s.field = positive(row, c, "field", f)?,
                Column::Voltage(f) => s.field = positive(row, c, "voltage", f)?,
                Column::Thickness(f) => s.thickness = Some(positive(row, c, "thickness", f)?),
                Column::Area(f) => s.area = Some(positive(row, c, "area", f)?),
                Column::Prestretch => s.prestretch = Some(positive(row, c, "prestretch", 1.0)?),
                Column::Survived => {
                    s.survived = match table.field(row, c) {
                        "0" => false,
                        "1" => true,
                        other => {
                            return Err(Error::input(
                                table.loc(row, c),
                                format!("survived must be 0 or 1, found '{other}'"),
                            )
                            .with_hint("1: the specimen did not break down up to its field (e.g. the rig's limit); 0: it broke down at it"))
                        }
                    }
                }
                Column::Label => {
                    let t = table.field(row, c);
                    s.label = (!t.is_empty()).then(|| t.to_string());
                }
            }
        }
        if let Column::Voltage(_) = field {
            // Checked above: a thickness column or --thickness gives every row one.
            s.field /= s.thickness.unwrap_or(f64::NAN);
            if !(s.field.is_finite() && s.field > 0.0) {
                return Err(Error::input(
                    table.loc(row, fc),
                    format!(
                        "voltage / thickness is {} V/m, not a finite positive field",
                        s.field
                    ),
                )
                .with_hint("check the voltage and thickness columns and their units"));
            }
        }
        specimens.push(s);
    }
    let failures = specimens.iter().filter(|s| !s.survived).count();
    if failures < 2 {
        let survived = find(|k| matches!(k, Column::Survived));
        let loc =
            survived.map_or_else(|| Location::line(path, table.header_line), |(c, _)| hloc(c));
        let (msg, hint) = if failures == 0 {
            (
                format!("every one of the {} specimens survived: no breakdown to fit", specimens.len()),
                "a series needs breakdowns: raise the rig's limit, or check the survived column (1 = did not break down)",
            )
        } else {
            (
                format!(
                    "{failures} breakdown among {} specimens: a Weibull fit needs at least two",
                    specimens.len()
                ),
                "test more specimens (IEEE Std 930 asks for ten or more breakdowns)",
            )
        };
        return Err(Error::input(loc, msg).with_hint(hint));
    }
    Ok(BreakdownSeries {
        path: path.clone(),
        sha256: table.sha256.clone(),
        specimens,
        conversions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str, opts: &BreakdownOptions) -> Result<BreakdownSeries> {
        from_table(&Table::parse(Path::new("s.csv"), text.as_bytes())?, opts)
    }

    fn refused(text: &str, opts: &BreakdownOptions) -> String {
        let e = parse(text, opts).expect_err(text);
        e.to_string()
    }

    #[test]
    fn fields_voltages_and_units_read_in_si() {
        let s = parse(
            "specimen,field_V_per_um,survived,area_mm2\na,30,0,100\nb,30,0,100\nc,45.5,1,100\n",
            &BreakdownOptions::default(),
        )
        .unwrap();
        assert_eq!(s.specimens.len(), 3);
        assert_eq!(s.failures(), 2);
        assert_eq!(s.specimens[0].field, 30e6);
        assert_eq!(s.specimens[2].field, 45.5e6);
        assert!(s.specimens[2].survived);
        // 100 · 1e-6 rounds: relative 1e-15.
        assert!((s.specimens[0].area.unwrap() / 100e-6 - 1.0).abs() < 1e-15);
        assert_eq!(s.specimens[1].label.as_deref(), Some("b"));
        // kV/mm and MV/m are V/µm; a bracketed unit reads the same.
        for h in ["field_kV_per_mm", "field_MV_per_m", "field [V/um]"] {
            let s = parse(&format!("{h}\n30\n31\n"), &BreakdownOptions::default()).unwrap();
            assert_eq!(s.specimens[1].field, 31e6, "{h}");
        }
        // A voltage over the thickness, per row or from the flag (relative 1e-15:
        // one division).
        let s = parse(
            "voltage_kV,thickness_um\n9,300\n6,200\n",
            &BreakdownOptions::default(),
        )
        .unwrap();
        assert!((s.specimens[0].field / 30e6 - 1.0).abs() < 1e-15);
        assert!((s.specimens[1].thickness.unwrap() / 200e-6 - 1.0).abs() < 1e-15);
        let s = parse(
            "voltage_V\n9000\n9000\n",
            &BreakdownOptions {
                thickness: Some(300e-6),
                area: Some(1e-4),
            },
        )
        .unwrap();
        assert!((s.specimens[1].field / 30e6 - 1.0).abs() < 1e-15);
        assert_eq!(s.specimens[1].area, Some(1e-4));
        assert!(s.conversions[0].contains("--thickness"));
    }

    #[test]
    fn bad_series_are_refused_where_they_are_wrong() {
        let none = BreakdownOptions::default();
        for (text, opts, want) in [
            (
                "field_V_per_um\n30\n-2\n",
                none,
                "s.csv:3:1: field must be positive",
            ),
            (
                "field_V_per_um\n30\n0\n",
                none,
                "s.csv:3:1: field must be positive",
            ),
            (
                "field_V_per_um,survived\n30,0\n31,2\n",
                none,
                "s.csv:3:2: survived must be 0 or 1",
            ),
            (
                "field_V_per_um,survived\n30,0\n31,1\n",
                none,
                "1 breakdown among 2",
            ),
            (
                "field_V_per_um,survived\n30,1\n31,1\n",
                none,
                "s.csv:1:2: every one of the 2",
            ),
            (
                "field_V_per_um,voltage_kV\n30,9\n31,9\n",
                none,
                "s.csv:1:2: a second breakdown field",
            ),
            (
                "field_V_per_um,field_kV_per_mm\n30,30\n31,31\n",
                none,
                "s.csv:1:2: a second breakdown field",
            ),
            (
                "field\n30\n31\n",
                none,
                "s.csv:1:1: column 'field' has no unit",
            ),
            (
                "field_V_per_nm\n30\n31\n",
                none,
                "s.csv:1:1: unknown unit 'V/nm'",
            ),
            (
                "voltage_kV\n9\n9\n",
                none,
                "s.csv:1:1: column 'voltage_kV' is a voltage",
            ),
            (
                "voltage_kV,thickness_um\n9,300\n9,0\n",
                none,
                "s.csv:3:2: thickness must be positive",
            ),
            (
                "voltage_kV,thickness_um\n9,300\n9,300\n",
                BreakdownOptions {
                    thickness: Some(1e-4),
                    area: None,
                },
                "s.csv:1:2: --thickness was given",
            ),
            (
                "field_V_per_um,area_mm2\n30,1\n31,1\n",
                BreakdownOptions {
                    thickness: None,
                    area: Some(1e-4),
                },
                "--specimen-area was given",
            ),
            (
                "field_V_per_um,prestretch\n30,3\n31,-3\n",
                none,
                "s.csv:3:2: prestretch must be positive",
            ),
            (
                "field_V_per_um,colour\n30,red\n31,red\n",
                none,
                "s.csv:1:2: unknown column 'colour'",
            ),
            (
                "field_V_per_um\n30\nabc\n",
                none,
                "s.csv:3:1: expected a number",
            ),
            ("specimen,survived\na,0\nb,0\n", none, "no breakdown column"),
        ] {
            let got = refused(text, &opts);
            assert!(got.contains(want), "{text:?}: {got}");
        }
    }

    #[test]
    fn ties_are_normal() {
        let s = parse(
            "field_V_per_um\n30\n30\n30\n32\n",
            &BreakdownOptions::default(),
        )
        .unwrap();
        assert_eq!(s.failures(), 4);
    }
}
