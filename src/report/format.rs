//! Number formatting for people: SI prefixes and aligned tables.

/// Format `v` in `unit` with an SI prefix (e.g. 69312 Pa → "69.31 kPa").
pub fn si(v: f64, unit: &str) -> String {
    if !v.is_finite() {
        return format!("{v} {unit}");
    }
    if unit == "1" || unit.is_empty() {
        return sig(v, 5);
    }
    let a = v.abs();
    let (f, p) = if a == 0.0 {
        (1.0, "")
    } else if a >= 1e9 {
        (1e-9, "G")
    } else if a >= 1e6 {
        (1e-6, "M")
    } else if a >= 1e3 {
        (1e-3, "k")
    } else if a >= 1.0 {
        (1.0, "")
    } else if a >= 1e-3 {
        (1e3, "m")
    } else if a >= 1e-6 {
        (1e6, "µ")
    } else {
        (1e9, "n")
    };
    format!("{} {p}{unit}", sig(v * f, 5))
}

/// A value of the constant `name` for a table: a fraction (`mass_fraction`, SI unit
/// 1) as a percentage, anything else by [`si`].
pub fn constant(name: &str, v: f64, unit: &str) -> String {
    match (name.ends_with("_fraction"), unit) {
        (true, "1") if v.is_finite() => format!("{} %", sig(100.0 * v, 5)),
        _ => si(v, unit),
    }
}

/// `v` with `n` significant digits, without exponent for moderate magnitudes.
pub fn sig(v: f64, n: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-4..=8).contains(&mag) {
        return format!("{:.*e}", n.saturating_sub(1), v);
    }
    let decimals = (n as i32 - 1 - mag).max(0) as usize;
    format!("{v:.decimals$}")
}

/// A standard deviation for a `±` column: "—" when it is zero, which is what every
/// propagation gives when no tolerance was given (a printed `± 0.0000` would claim
/// an exact value).
pub fn tolerance(std: f64, fmt: impl Fn(f64) -> String) -> String {
    if std == 0.0 {
        "—".into()
    } else {
        fmt(std)
    }
}

/// Render rows as a left-aligned text table with a header rule.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut w: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (i, c) in r.iter().enumerate() {
            w[i] = w[i].max(c.chars().count());
        }
    }
    let line = |cells: Vec<&str>| {
        cells
            .iter()
            .enumerate()
            .map(|(i, c)| format!("{c}{}", " ".repeat(w[i] - c.chars().count())))
            .collect::<Vec<_>>()
            .join("  ")
            .trim_end()
            .to_string()
    };
    let mut out = line(header.to_vec());
    out.push('\n');
    out.push_str(&"-".repeat(w.iter().sum::<usize>() + 2 * (w.len() - 1)));
    out.push('\n');
    for r in rows {
        out.push_str(&line(r.iter().map(String::as_str).collect()));
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn si_prefixes() {
        assert_eq!(si(69312.0, "Pa"), "69.312 kPa");
        assert_eq!(si(-888.0, "Pa"), "-888.00 Pa");
        assert_eq!(si(1.5e-5, "m"), "15.000 µm");
        assert_eq!(si(2.5, "1"), "2.5000");
    }

    #[test]
    fn tolerance_without_one_is_a_dash() {
        assert_eq!(tolerance(0.0, |v| format!("{v:.4}")), "—");
        assert_eq!(tolerance(0.0123, |v| format!("{v:.4}")), "0.0123");
    }
}
