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
    /// Capacitance (SI: F).
    Capacitance,
    /// Frequency (SI: Hz).
    Frequency,
    /// Resistance, reactance, impedance (SI: Ω).
    Resistance,
    /// Conductance, susceptance, admittance (SI: S).
    Conductance,
    /// Inductance (SI: H).
    Inductance,
    /// Plane angle (SI: rad).
    Angle,
    /// Mass density (SI: kg/m³).
    Density,
    /// Voltage (SI: V).
    Voltage,
    /// Electric current (SI: A).
    Current,
    /// Mass (SI: kg).
    Mass,
    /// Dynamic viscosity (SI: Pa·s).
    Viscosity,
    /// A dimensionless fraction (SI: 1), e.g. `0.5 %`.
    Fraction,
    /// A pure number without a unit (a relative permittivity, a loss tangent):
    /// `2.72 ± 2 %` would read as an absolute 0.02, so no unit is taken.
    Number,
    /// Electric field strength (SI: V/m), e.g. a breakdown field `80 V/um`.
    ElectricField,
}

impl Dimension {
    /// The units accepted for this dimension, with their factor to SI.
    pub fn units(self) -> &'static [(&'static str, f64)] {
        match self {
            Dimension::Stress => &[
                ("Pa", 1.0),
                ("kPa", 1e3),
                ("MPa", 1e6),
                ("GPa", 1e9),
                ("N/mm2", 1e6),
                ("N/mm^2", 1e6),
                ("N/mm²", 1e6),
            ],
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
            Dimension::Capacitance => &[
                ("F", 1.0),
                ("mF", 1e-3),
                ("uF", 1e-6),
                ("µF", 1e-6),
                ("nF", 1e-9),
                ("pF", 1e-12),
                ("fF", 1e-15),
            ],
            Dimension::Frequency => &[
                ("Hz", 1.0),
                ("mHz", 1e-3),
                ("kHz", 1e3),
                ("MHz", 1e6),
                ("GHz", 1e9),
            ],
            Dimension::Resistance => &[
                ("Ohm", 1.0),
                ("ohm", 1.0),
                ("Ω", 1.0),
                ("mOhm", 1e-3),
                ("mohm", 1e-3),
                ("mΩ", 1e-3),
                ("kOhm", 1e3),
                ("kohm", 1e3),
                ("kΩ", 1e3),
                ("MOhm", 1e6),
                ("Mohm", 1e6),
                ("MΩ", 1e6),
                ("GOhm", 1e9),
                ("Gohm", 1e9),
                ("GΩ", 1e9),
            ],
            Dimension::Conductance => &[
                ("S", 1.0),
                ("mS", 1e-3),
                ("uS", 1e-6),
                ("µS", 1e-6),
                ("nS", 1e-9),
                ("pS", 1e-12),
            ],
            Dimension::Inductance => &[
                ("H", 1.0),
                ("mH", 1e-3),
                ("uH", 1e-6),
                ("µH", 1e-6),
                ("nH", 1e-9),
            ],
            Dimension::Angle => &[
                ("rad", 1.0),
                ("deg", std::f64::consts::PI / 180.0),
                ("°", std::f64::consts::PI / 180.0),
            ],
            Dimension::Voltage => &[("V", 1.0), ("kV", 1e3), ("mV", 1e-3)],
            Dimension::Current => &[
                ("A", 1.0),
                ("mA", 1e-3),
                ("uA", 1e-6),
                ("µA", 1e-6),
                ("nA", 1e-9),
            ],
            Dimension::Mass => &[("kg", 1.0), ("g", 1e-3)],
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
            Dimension::Number => &[],
            Dimension::ElectricField => &[
                ("V/m", 1.0),
                ("kV/m", 1e3),
                ("V/mm", 1e3),
                ("kV/mm", 1e6),
                ("V/um", 1e6),
                ("V/µm", 1e6),
                ("MV/m", 1e6),
                ("kV/cm", 1e5),
            ],
            Dimension::Density => &[
                ("kg/m3", 1.0),
                ("kg/m^3", 1.0),
                ("kg/m³", 1.0),
                ("g/cm3", 1e3),
                ("g/cm^3", 1e3),
                ("g/cm³", 1e3),
                ("g/cc", 1e3),
                ("g/mL", 1e3),
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
            Dimension::Capacitance => "F",
            Dimension::Frequency => "Hz",
            Dimension::Resistance => "Ω",
            Dimension::Conductance => "S",
            Dimension::Inductance => "H",
            Dimension::Angle => "rad",
            Dimension::Density => "kg/m³",
            Dimension::Voltage => "V",
            Dimension::Current => "A",
            Dimension::Mass => "kg",
            Dimension::Viscosity => "Pa·s",
            Dimension::Fraction | Dimension::Number => "1",
            Dimension::ElectricField => "V/m",
        }
    }

    /// Factor from `unit` to SI, or `None` if the unit is not one of this dimension's.
    pub fn factor(self, unit: &str) -> Option<f64> {
        self.units()
            .iter()
            .find(|(u, _)| *u == unit)
            .map(|(_, f)| *f)
    }

    /// The accepted unit that `unit` would be if case did not matter (`mpa` → `MPa`),
    /// for a "did you mean" hint. SI prefixes are case-sensitive (mPa ≠ MPa), so
    /// this is a suggestion, never a silent correction.
    pub fn suggest(self, unit: &str) -> Option<&'static str> {
        self.units()
            .iter()
            .find(|(u, _)| u.eq_ignore_ascii_case(unit))
            .map(|(u, _)| *u)
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

/// Parse a quantity of dimension `dim` that takes no uncertainty: `2.2mm`,
/// `0.5 N/mm²`, or a bare number taken as SI. A `±` is refused, not dropped: where a
/// value's σ is carried, the reader calls [`parse_uncertain`].
pub fn parse_quantity(text: &str, dim: Dimension) -> Result<f64, String> {
    if split_pm(text.trim()).is_some() {
        return Err(format!(
            "'{}' has a ± uncertainty, which this value does not take (it would be dropped); write the value alone",
            text.trim()
        ));
    }
    parse_one(text.trim(), dim, None)
}

/// The largest σ / |value| [`parse_uncertain`] takes: a σ a hundred times its
/// value leaves not even the value's order of magnitude, and one of 1e300 would
/// overflow every uncertainty propagated from it (σ² is +∞), which then reads as
/// "exact". (A value of exactly 0, a stray capacitance of 0 ± 0.05 pF, takes any
/// finite σ.)
pub const MAX_RELATIVE_SIGMA: f64 = 100.0;

/// Parse a quantity of dimension `dim` with an optional standard uncertainty:
/// `2.2 mm ± 0.05 mm`, `2.2 mm ± 0.05` (the value's unit), `250 ± 12 kPa` (the
/// uncertainty's unit for both, as in (250 ± 12) kPa); `+-` and `+/-` for `±`.
pub fn parse_uncertain(text: &str, dim: Dimension) -> Result<Quantity, String> {
    let text = text.trim();
    let Some((main, tol)) = split_pm(text) else {
        return Ok(Quantity {
            value: parse_one(text, dim, None)?,
            tolerance: None,
        });
    };
    let unit_of = |s: &str| split_number(s).1.trim().to_string();
    let (unit_main, unit_tol) = (unit_of(main), unit_of(tol));
    let value = match unit_main.is_empty() {
        true => parse_one(main, dim, Some(&unit_tol))?,
        false => parse_one(main, dim, None)?,
    };
    let t = parse_one(tol, dim, Some(&unit_main))?;
    if t < 0.0 {
        return Err(format!("the uncertainty in '{text}' must not be negative"));
    }
    if value != 0.0 && t > MAX_RELATIVE_SIGMA * value.abs() {
        return Err(format!(
            "the uncertainty in '{text}' is more than {MAX_RELATIVE_SIGMA} times the value: such a σ says the value is unknown, and it would overflow what is propagated from it (a σ is one standard uncertainty, in the value's unit)"
        ));
    }
    Ok(Quantity {
        value,
        tolerance: Some(t),
    })
}

/// The two sides of `a ± b` (also `+/-`, `+-`), trimmed.
fn split_pm(text: &str) -> Option<(&str, &str)> {
    ["±", "+/-", "+-"]
        .iter()
        .find_map(|pm| text.split_once(pm))
        .map(|(a, b)| (a.trim(), b.trim()))
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
    let si = dim
        .factor(unit)
        .map(|f| v * f)
        .ok_or_else(|| match dim.suggest(unit) {
            Some(u) => format!(
                "unknown unit '{unit}' in '{s}'; units are case-sensitive: did you mean '{u}'?"
            ),
            None if dim.units().is_empty() => {
                format!("'{s}': this is a pure number and takes no unit ('{unit}')")
            }
            None => format!(
                "unknown unit '{unit}' in '{s}'; expected one of {}",
                dim.accepted()
            ),
        })?;
    match si.is_finite() {
        true => Ok(si),
        false => Err(format!("'{s}' is not a finite number in SI ({})", dim.si())),
    }
}

/// Factor of an SI prefix letter (`p`, `n`, `u`, `µ`, `m`, `k`, `M`, `G`, `T`, `f`).
pub fn si_prefix(c: char) -> Option<f64> {
    Some(match c {
        'f' => 1e-15,
        'p' => 1e-12,
        'n' => 1e-9,
        'u' | 'µ' | 'μ' => 1e-6,
        'm' => 1e-3,
        'k' | 'K' => 1e3,
        'M' => 1e6,
        'G' => 1e9,
        'T' => 1e12,
        _ => return None,
    })
}

/// A number as instruments print it, in SI: plain or engineering notation
/// (`+2.00000000000e+001`, `1.5E-11`), or with an SI prefix and optionally the
/// unit symbol `unit` (`15.75p`, `15.75pF`, `1.2k`, `3 MΩ`). `None` if unreadable
/// or not finite.
pub fn parse_engineering(text: &str, unit: &str) -> Option<f64> {
    let t = text.trim();
    let (num, rest) = split_number(t);
    let v: f64 = num.parse().ok()?;
    let rest = rest.trim();
    let rest = if unit.is_empty() {
        rest
    } else {
        rest.strip_suffix(unit).unwrap_or(rest)
    };
    let mut chars = rest.chars();
    let f = match (chars.next(), chars.next()) {
        (None, _) => 1.0,
        (Some(c), None) => si_prefix(c)?,
        _ => return None,
    };
    Some(v * f).filter(|x| x.is_finite())
}

/// Most points one series a command makes may hold (a sweep, a curve, a set of
/// sample times): 10⁶ rows is about 20 MB of CSV and some 50 MB in memory; a larger
/// count is a typo or an overflowed value, not an experiment.
pub const MAX_POINTS: usize = 1_000_000;

/// The range of a count a user gives (a flag's value, a file's integer), checked as
/// a whole number inside `min..=max` before anything is sized by it, so that a
/// wrapped or absurd value (2⁶⁴ − 1, 10⁹, −1, `1e8`) is refused with the bound and
/// its reason instead of becoming an empty result, an abort or gigabytes.
///
/// ```
/// use dea_fit::units::CountRange;
/// const POINTS: CountRange = CountRange::new(10, 100_000, "points of one curve");
/// assert_eq!(POINTS.parse("200"), Ok(200));
/// assert!(POINTS.parse("18446744073709551615").unwrap_err().contains("from 10 to 100000"));
/// assert!(POINTS.parse("1e8").is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CountRange {
    /// Smallest count accepted.
    pub min: usize,
    /// Largest count accepted.
    pub max: usize,
    /// What the count is and why the bound, for the error (e.g. "points of one
    /// curve; 10⁵ resolve λ to 1e-5").
    pub why: &'static str,
}

impl CountRange {
    /// A range `min..=max` with the reason of its bounds.
    pub const fn new(min: usize, max: usize, why: &'static str) -> CountRange {
        CountRange { min, max, why }
    }

    fn expected(&self) -> String {
        format!(
            "expected a whole number from {} to {} ({})",
            self.min, self.max, self.why
        )
    }

    /// A count written as text: an optional sign and decimal digits only (no
    /// exponent, no fraction), inside the range.
    pub fn parse(&self, text: &str) -> Result<usize, String> {
        let t = text.trim();
        let digits = t.strip_prefix(['+', '-']).unwrap_or(t);
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return Err(format!("'{t}' is not a whole number; {}", self.expected()));
        }
        // More digits than an i128 holds is out of range all the same.
        let n = t.parse::<i128>().unwrap_or(match t.starts_with('-') {
            true => i128::MIN,
            false => i128::MAX,
        });
        self.check(n)
            .map_err(|_| format!("{t} is out of range; {}", self.expected()))
    }

    /// A count read as an integer of any width (a TOML integer, a `u64` flag),
    /// inside the range.
    pub fn check(&self, n: impl Into<i128>) -> Result<usize, String> {
        let n: i128 = n.into();
        match usize::try_from(n) {
            Ok(c) if (self.min..=self.max).contains(&c) => Ok(c),
            _ => Err(format!("{n} is out of range; {}", self.expected())),
        }
    }

    /// A count computed in floating point (the points of a log sweep: decades ×
    /// points per decade), rounded and checked while still a float, so that an
    /// infinite or huge value never reaches an integer cast.
    pub fn check_real(&self, x: f64) -> Result<usize, String> {
        let r = x.round();
        match r.is_finite() && r >= self.min as f64 && r <= self.max as f64 {
            true => Ok(r as usize),
            false => Err(format!("{x:.6e} is out of range; {}", self.expected())),
        }
    }
}

/// The product of counts (sweep dimensions, samples × points), checked against
/// `budget` without overflowing: `Err` names each factor, the budget and why.
pub fn count_product(factors: &[(&str, usize)], budget: usize, why: &str) -> Result<usize, String> {
    let total = factors
        .iter()
        .try_fold(1usize, |acc, (_, n)| acc.checked_mul(*n))
        .filter(|&t| t <= budget);
    total.ok_or_else(|| {
        let parts: Vec<String> = factors.iter().map(|(w, n)| format!("{n} {w}")).collect();
        format!("{} is more than {budget} in all ({why})", parts.join(" × "))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_values_units_and_tolerances() {
        let q = parse_uncertain("2.2mm±0.05mm", Dimension::Length).unwrap();
        assert!((q.value - 2.2e-3).abs() < 1e-15);
        assert!((q.tolerance.unwrap() - 5e-5).abs() < 1e-15);
        let q = parse_uncertain("2.2 mm ± 0.05", Dimension::Length).unwrap();
        assert!((q.tolerance.unwrap() - 5e-5).abs() < 1e-15);
        // (250 ± 12) kPa: the uncertainty's unit is the value's too
        for t in [
            "250 ± 12 kPa",
            "250 +- 12 kPa",
            "250 +/- 12 kPa",
            "250 kPa ± 12",
        ] {
            let q = parse_uncertain(t, Dimension::Stress).unwrap();
            assert!((q.value - 250e3).abs() < 1e-9, "{t}");
            assert!((q.tolerance.unwrap() - 12e3).abs() < 1e-9, "{t}");
        }
        assert_eq!(
            parse_uncertain("2.72", Dimension::Fraction)
                .unwrap()
                .tolerance,
            None
        );
        assert!(parse_uncertain("1 ± -2", Dimension::Fraction).is_err());
        // a σ that is not finite, or absurd beside its value, is refused, never
        // dropped as "exact"; 0 ± σ (a stray capacitance) takes a finite σ
        for t in [
            "0.0012 ± 1e300",
            "0.0012 ± 0.121",
            "2 mm ± 1e308 mm",
            "1 ± inf",
            "1 ± nan",
        ] {
            let e = parse_uncertain(t, Dimension::Number)
                .or_else(|_| parse_uncertain(t, Dimension::Length));
            assert!(e.is_err(), "{t}");
        }
        assert!(parse_uncertain("0.0012 ± 1e300", Dimension::Number)
            .unwrap_err()
            .contains("more than 100 times the value"));
        let q = parse_uncertain("0.0012 ± 0.12", Dimension::Number).unwrap();
        assert_eq!(q.tolerance, Some(0.12));
        let q = parse_uncertain("0 ± 0.05pF", Dimension::Capacitance).unwrap();
        assert!((q.tolerance.unwrap() - 5e-14).abs() < 1e-26);
        // a finite number that overflows in SI is refused, not +∞
        assert!(parse_quantity("1e308 kPa", Dimension::Stress)
            .unwrap_err()
            .contains("not a finite number"));
        // where no σ is carried, a ± is refused rather than dropped
        assert!(parse_quantity("250 kPa ± 12 kPa", Dimension::Stress)
            .unwrap_err()
            .contains("does not take"));
        assert_eq!(
            parse_quantity("1.439e-3", Dimension::Area).unwrap(),
            1.439e-3
        );
        assert!((parse_quantity("22 mm^2", Dimension::Area).unwrap() - 22e-6).abs() < 1e-18);
        assert!(parse_quantity("3 ksi", Dimension::Stress)
            .unwrap_err()
            .contains("unknown unit 'ksi'"));
        assert!(parse_quantity("abc", Dimension::Length).is_err());
        assert!((parse_quantity("0.5 N/mm²", Dimension::Stress).unwrap() - 5e5).abs() < 1e-9);
        assert!(parse_quantity("22 MM2", Dimension::Area)
            .unwrap_err()
            .contains("did you mean 'mm2'?"));
        assert_eq!(Dimension::Stress.suggest("mpa"), Some("MPa"));
        assert_eq!(Dimension::Stress.suggest("ksi"), None);
    }

    #[test]
    fn counts_are_whole_numbers_in_range_before_use() {
        let r = CountRange::new(2, 1000, "points of a test");
        assert_eq!(r.parse(" 25 "), Ok(25));
        assert_eq!(r.parse("+2"), Ok(2));
        // wrapped, huge, negative, zero and non-integer values are refused with the
        // range and its reason
        for t in [
            "18446744073709551615",
            "9223372036854775807",
            "99999999999999999999999999999999999999999",
            "-1",
            "0",
            "1001",
        ] {
            let e = r.parse(t).unwrap_err();
            assert!(e.contains("from 2 to 1000 (points of a test)"), "{t}: {e}");
        }
        for t in ["1e8", "2.5", "inf", "nan", "", "ten", "0x10"] {
            assert!(
                r.parse(t).unwrap_err().contains("not a whole number"),
                "{t}"
            );
        }
        assert_eq!(r.check(1000u64), Ok(1000));
        assert!(r.check(i64::MIN).is_err());
        assert!(r.check(u64::MAX).is_err());
        assert_eq!(r.check_real(24.4), Ok(24));
        for x in [f64::INFINITY, f64::NAN, 1e19, -3.0, 1000.6] {
            assert!(r.check_real(x).is_err(), "{x}");
        }
        assert_eq!(
            count_product(&[("a", 1000), ("b", 1000)], 1_000_000, "t"),
            Ok(1_000_000)
        );
        let e = count_product(&[("a", 1000), ("b", 1001)], 1_000_000, "why").unwrap_err();
        assert!(e.contains("1000 a × 1001 b") && e.contains("why"), "{e}");
        // a product that overflows usize is refused, not wrapped
        assert!(count_product(&[("a", usize::MAX), ("b", 2)], usize::MAX, "t").is_err());
    }

    #[test]
    fn parses_instrument_numbers() {
        assert_eq!(parse_engineering("+2.00000000000e+001", ""), Some(20.0));
        assert!((parse_engineering("15.75p", "F").unwrap() - 15.75e-12).abs() < 1e-24);
        assert!((parse_engineering("15.75pF", "F").unwrap() - 15.75e-12).abs() < 1e-24);
        assert_eq!(parse_engineering("1.2k", "Ohm"), Some(1200.0));
        assert_eq!(parse_engineering("3 MOhm", "Ohm"), Some(3e6));
        assert_eq!(parse_engineering("2.5 F", "F"), Some(2.5));
        assert_eq!(parse_engineering("1e999", ""), None);
        assert_eq!(parse_engineering("1.0xy", ""), None);
        assert_eq!(parse_engineering("abc", ""), None);
        let q = parse_quantity("1.03 g/cm3", Dimension::Density).unwrap();
        assert!((q - 1030.0).abs() < 1e-9);
        let q = parse_uncertain("0.3pF±0.05pF", Dimension::Capacitance).unwrap();
        assert!((q.tolerance.unwrap() - 5e-14).abs() < 1e-26);
    }
}
