//! Temperatures at the edges: `25 C`, `25C`, `25 °C`, `-5C`, `298.15 K`. Inside,
//! kelvin. A bare number is refused (is it °C or K?).

/// Offset of the Celsius scale (K): T/K = t/°C + 273.15 (BIPM, SI Brochure 9th ed.).
pub const CELSIUS_ZERO_K: f64 = 273.15;

/// The temperatures a DMA measures (K): above absolute zero, at most 1000 K (no
/// polymer is tested hotter; 1000 is read as a unit slip).
pub const TEMPERATURE_RANGE_K: (f64, f64) = (1.0, 1000.0);

/// The unit of a temperature column or value: Celsius or kelvin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// °C.
    Celsius,
    /// K.
    Kelvin,
}

impl Scale {
    /// The scale a unit names: `C`, `°C`, `degC`, `celsius`; `K`, `kelvin`.
    pub fn of(unit: &str) -> Option<Scale> {
        match unit.trim() {
            "C" | "°C" | "degC" | "deg C" | "celsius" | "Celsius" | "℃" => Some(Scale::Celsius),
            "K" | "kelvin" | "Kelvin" => Some(Scale::Kelvin),
            _ => None,
        }
    }

    /// `v` in this scale, in kelvin.
    pub fn kelvin(self, v: f64) -> f64 {
        match self {
            Scale::Celsius => v + CELSIUS_ZERO_K,
            Scale::Kelvin => v,
        }
    }
}

/// Parse `25 C`, `-5C`, `25 °C` or `298.15 K` into kelvin, within
/// [`TEMPERATURE_RANGE_K`].
pub fn parse(text: &str) -> Result<f64, String> {
    let t = text.trim();
    // the longest leading part that reads as a number is the value, the rest its unit
    let split = t
        .char_indices()
        .map(|(i, _)| i)
        .chain([t.len()])
        .filter(|&i| i > 0)
        .rev()
        .find(|&i| t[..i].trim().parse::<f64>().is_ok())
        .unwrap_or(0);
    let (num, unit) = t.split_at(split);
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("expected a temperature such as 25C, -5C or 298.15K, found '{t}'"))?;
    let scale = match unit.trim() {
        "" => {
            return Err(format!(
                "'{t}' has no unit: write {v}C (Celsius) or {v}K (kelvin)"
            ))
        }
        u => Scale::of(u).ok_or_else(|| {
            format!("unknown temperature unit '{u}' in '{t}': expected C (°C) or K")
        })?,
    };
    let k = scale.kelvin(v);
    check(k).map(|_| k)
}

/// `k` (K) is a temperature a DMA measures, or why not.
pub fn check(k: f64) -> Result<(), String> {
    let (lo, hi) = TEMPERATURE_RANGE_K;
    if k.is_finite() && (lo..=hi).contains(&k) {
        Ok(())
    } else {
        Err(format!(
            "temperature {k} K ({} °C) is outside {lo} … {hi} K: is the unit right (C or K)?",
            k - CELSIUS_ZERO_K
        ))
    }
}

/// `k` (K) written in °C for people, e.g. `25 °C`.
pub fn celsius(k: f64) -> String {
    let c = k - CELSIUS_ZERO_K;
    let r = (c * 100.0).round() / 100.0;
    format!("{} °C", if r == 0.0 { 0.0 } else { r })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_celsius_and_kelvin() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(close(parse("25C").unwrap(), 298.15));
        assert!(close(parse("-5C").unwrap(), 268.15));
        assert!(close(parse("-5 °C").unwrap(), 268.15));
        assert!(close(parse("25 C").unwrap(), 298.15));
        assert!(close(parse("298.15 K").unwrap(), 298.15));
        assert!(close(parse("2.5e1C").unwrap(), 298.15));
        assert!(parse("25").unwrap_err().contains("no unit"));
        assert!(parse("25F").unwrap_err().contains("unknown"));
        assert!(parse("-300C").is_err());
        assert_eq!(celsius(268.15), "-5 °C");
    }
}
