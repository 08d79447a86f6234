//! Units at the edges. Everything inside dea-fit is SI (Pa, m, m², s, N, F, V);
//! this module turns the units written in CSV headers, flags and scene files into SI
//! factors, and nothing else in the crate multiplies by 1e3 or 1e-6.

/// A physical dimension that a header or a flag can carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Stress / pressure (SI: Pa).
    Stress,
    /// Force (SI: N).
    Force,
    /// Length (SI: m).
    Length,
    /// Area (SI: m²).
    Area,
    /// Time (SI: s).
    Time,
    /// Voltage (SI: V).
    Voltage,
    /// Mass (SI: kg).
    Mass,
    /// Frequency (SI: Hz).
    Frequency,
    /// Dynamic viscosity (SI: Pa·s).
    Viscosity,
    /// Mass density (SI: kg/m³).
    Density,
    /// A dimensionless fraction (SI: 1), e.g. `0.5 %`.
    Fraction,
}

impl Dimension {
    /// The units accepted for this dimension, with their factor to SI.
    pub fn units(self) -> &'static [(&'static str, f64)] {
        match self {
            Dimension::Stress => &[("Pa", 1.0), ("kPa", 1e3), ("MPa", 1e6), ("GPa", 1e9)],
            Dimension::Force => &[("N", 1.0), ("mN", 1e-3), ("kN", 1e3)],
            Dimension::Length => &[
                ("m", 1.0),
                ("cm", 1e-2),
                ("mm", 1e-3),
                ("um", 1e-6),
                ("µm", 1e-6),
            ],
            Dimension::Area => &[
                ("m2", 1.0),
                ("cm2", 1e-4),
                ("mm2", 1e-6),
                ("m^2", 1.0),
                ("cm^2", 1e-4),
                ("mm^2", 1e-6),
                ("m²", 1.0),
                ("cm²", 1e-4),
                ("mm²", 1e-6),
            ],
            Dimension::Time => &[
                ("s", 1.0),
                ("ms", 1e-3),
                ("us", 1e-6),
                ("µs", 1e-6),
                ("min", 60.0),
                ("h", 3600.0),
            ],
            Dimension::Voltage => &[("V", 1.0), ("kV", 1e3), ("mV", 1e-3)],
            Dimension::Mass => &[("kg", 1.0), ("g", 1e-3)],
            Dimension::Frequency => &[("Hz", 1.0), ("kHz", 1e3), ("mHz", 1e-3)],
            Dimension::Viscosity => &[
                ("Pa s", 1.0),
                ("Pa*s", 1.0),
                ("Pa·s", 1.0),
                ("kPa s", 1e3),
                ("MPa s", 1e6),
                ("MPa*s", 1e6),
                ("MPa·s", 1e6),
            ],
            Dimension::Fraction => &[("%", 0.01)],
            Dimension::Density => &[
                ("kg/m3", 1.0),
                ("kg/m^3", 1.0),
                ("kg/m³", 1.0),
                ("g/cm3", 1e3),
                ("g/cm^3", 1e3),
                ("g/cm³", 1e3),
            ],
        }
    }

    /// The SI unit's symbol.
    pub fn si(self) -> &'static str {
        match self {
            Dimension::Stress => "Pa",
            Dimension::Force => "N",
            Dimension::Length => "m",
            Dimension::Area => "m²",
            Dimension::Time => "s",
            Dimension::Voltage => "V",
            Dimension::Mass => "kg",
            Dimension::Frequency => "Hz",
            Dimension::Viscosity => "Pa·s",
            Dimension::Density => "kg/m³",
            Dimension::Fraction => "1",
        }
    }

    /// Factor from `unit` to SI, or `None` if the unit is not one of this dimension's.
    pub fn factor(self, unit: &str) -> Option<f64> {
        self.units()
            .iter()
            .find(|(u, _)| *u == unit)
            .map(|(_, f)| *f)
    }

    /// The accepted unit names, for error messages.
    pub fn accepted(self) -> String {
        let mut names: Vec<&str> = self.units().iter().map(|(u, _)| *u).collect();
        names.dedup();
        names.join(", ")
    }
}

/// A value in SI with an optional ± tolerance (also SI), parsed from text such as
/// `2.2mm`, `2.2 mm±0.05mm`, `22 mm^2` or a bare SI number `1.439e-3`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantity {
    /// Value in SI.
    pub value: f64,
    /// Tolerance (one standard uncertainty) in SI, if given.
    pub tolerance: Option<f64>,
}

/// Parse a quantity of dimension `dim`. A bare number is taken as SI.
pub fn parse_quantity(text: &str, dim: Dimension) -> Result<Quantity, String> {
    let text = text.trim();
    let (main, tol) = match text.split_once('±').or_else(|| text.split_once("+-")) {
        Some((a, b)) => (a.trim(), Some(b.trim())),
        None => (text, None),
    };
    let value = parse_one(main, dim, None)?;
    let unit_of_main = split_number(main).1.trim().to_string();
    let tolerance = match tol {
        Some(t) => Some(parse_one(t, dim, Some(&unit_of_main))?),
        None => None,
    };
    if let Some(t) = tolerance {
        if t < 0.0 {
            return Err(format!("tolerance in '{text}' must not be negative"));
        }
    }
    Ok(Quantity { value, tolerance })
}

fn split_number(s: &str) -> (&str, &str) {
    let end = s
        .char_indices()
        .find(|&(i, c)| {
            !(c.is_ascii_digit()
                || c == '.'
                || c == '+'
                || c == '-'
                || ((c == 'e' || c == 'E')
                    && s[i + 1..]
                        .chars()
                        .next()
                        .is_some_and(|n| n.is_ascii_digit() || n == '-' || n == '+')))
        })
        .map(|(i, _)| i)
        .unwrap_or(s.len());
    (&s[..end], &s[end..])
}

fn parse_one(s: &str, dim: Dimension, default_unit: Option<&str>) -> Result<f64, String> {
    let (num, unit) = split_number(s.trim());
    let unit = unit.trim();
    let v: f64 = num
        .parse()
        .map_err(|_| format!("expected a number with a unit, found '{s}'"))?;
    if !v.is_finite() {
        return Err(format!("'{s}' is not a finite number"));
    }
    let unit = if unit.is_empty() {
        default_unit.unwrap_or("")
    } else {
        unit
    };
    if unit.is_empty() {
        return Ok(v);
    }
    dim.factor(unit).map(|f| v * f).ok_or_else(|| {
        format!(
            "unknown unit '{unit}' in '{s}'; expected one of {}",
            dim.accepted()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_values_units_and_tolerances() {
        let q = parse_quantity("2.2mm±0.05mm", Dimension::Length).unwrap();
        assert!((q.value - 2.2e-3).abs() < 1e-15);
        assert!((q.tolerance.unwrap() - 5e-5).abs() < 1e-15);
        let q = parse_quantity("2.2 mm ± 0.05", Dimension::Length).unwrap();
        assert!((q.tolerance.unwrap() - 5e-5).abs() < 1e-15);
        assert_eq!(
            parse_quantity("1.439e-3", Dimension::Area).unwrap().value,
            1.439e-3
        );
        assert!((parse_quantity("22 mm^2", Dimension::Area).unwrap().value - 22e-6).abs() < 1e-18);
        assert!(parse_quantity("3 ksi", Dimension::Stress)
            .unwrap_err()
            .contains("unknown unit 'ksi'"));
        assert!(parse_quantity("abc", Dimension::Length).is_err());
    }
}
