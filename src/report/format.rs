//! Number formatting for people: SI prefixes and aligned tables.

/// Format `v` in `unit` with an SI prefix (e.g. 69312 Pa → "69.31 kPa").
pub fn si(v: f64, unit: &str) -> String {
    if !v.is_finite() {
        return format!("{v} {unit}");
    }
    if unit == "1" || unit.is_empty() {
        return sig(v, 5);
    }
    let (f, p) = prefix(v.abs());
    format!("{} {p}{unit}", sig(v * f, 5))
}

/// The SI prefix for a magnitude `a` (≥ 0): the factor to multiply by and the prefix.
pub(crate) fn prefix(a: f64) -> (f64, &'static str) {
    if a == 0.0 {
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
    } else if a >= 1e-9 {
        (1e9, "n")
    } else if a >= 1e-12 {
        (1e12, "p")
    } else {
        (1e15, "f")
    }
}

/// How a value with a standard error is printed: one scale for both (an SI prefix,
/// or a power of ten for a bare number far from 1), and the decimals that show σ to
/// two significant digits.
struct Scale {
    /// Multiply SI values by this.
    factor: f64,
    /// Written after the numbers: " kPa", " %", "e7", "".
    suffix: String,
    /// Rounding step of both numbers (10^(place of σ's second digit)).
    step: f64,
    /// Decimals that step needs.
    decimals: usize,
}

impl Scale {
    fn new(v: f64, std: f64, unit: &str) -> Scale {
        let big = v.abs().max(std);
        let (factor, suffix) = match unit {
            "1" | "" => {
                // A bare number: plain from 1e-3 to 1e6, else a shared power of ten.
                let k = if big > 0.0 {
                    big.log10().floor() as i32
                } else {
                    0
                };
                if (-3..6).contains(&k) {
                    (1.0, String::new())
                } else {
                    (10f64.powi(-k), format!("e{k}"))
                }
            }
            "%" => (1.0, " %".to_string()),
            u => {
                let (f, p) = prefix(big);
                (f, format!(" {p}{u}"))
            }
        };
        let place = (std * factor).log10().floor() as i32 - 1;
        Scale {
            factor,
            suffix,
            step: 10f64.powi(place),
            decimals: (-place).max(0) as usize,
        }
    }

    fn num(&self, x: f64) -> String {
        let r = (x * self.factor / self.step).round() * self.step;
        // −0.0 would print as "-0.00"
        let r = if r == 0.0 { 0.0 } else { r };
        format!("{r:.*}", self.decimals)
    }
}

/// A usable standard error: finite and > 0.
fn usable(std: Option<f64>) -> Option<f64> {
    std.filter(|s| s.is_finite() && *s > 0.0)
}

/// `v ± σ` in the value's own unit: one SI prefix for both (the larger's), σ to two
/// significant digits and `v` to the same decimal place, the unit once:
/// 17.328 Pa ± 0.79063 Pa → "17.33 ± 0.79 Pa", 69338 Pa ± 349 Pa → "69.34 ± 0.35 kPa".
/// Without a usable σ (none, zero, not finite) the value by [`si`] and "(σ n/a)".
/// Unit `"1"` is a bare number (a shared power of ten far from 1), `"%"` takes no
/// prefix.
pub fn si_pm(v: f64, std: Option<f64>, unit: &str) -> String {
    let Some(s) = usable(std).filter(|_| v.is_finite()) else {
        return format!("{} (σ n/a)", plain(v, unit));
    };
    let sc = Scale::new(v, s, unit);
    let suffix = sc.suffix.trim_start();
    match unit {
        "1" | "" if !suffix.is_empty() => {
            format!("({} ± {}){suffix}", sc.num(v), sc.num(s))
        }
        _ => format!("{} ± {}{}", sc.num(v), sc.num(s), sc.suffix),
    }
}

/// The interval [lo, hi] printed with the prefix and decimals [`si_pm`] gives
/// `v ± σ`, the unit once: "[68.63, 70.05] kPa". Without a usable σ, each end by [`si`].
pub fn si_interval(lo: f64, hi: f64, v: f64, std: Option<f64>, unit: &str) -> String {
    match usable(std).filter(|_| v.is_finite() && lo.is_finite() && hi.is_finite()) {
        Some(s) => {
            let sc = Scale::new(v, s, unit);
            format!("[{}, {}]{}", sc.num(lo), sc.num(hi), sc.suffix)
        }
        None => format!("[{}, {}]", plain(lo, unit), plain(hi, unit)),
    }
}

/// `v` by [`si`], a percentage with its sign.
fn plain(v: f64, unit: &str) -> String {
    match unit {
        "%" => format!("{} %", sig(v, 5)),
        u => si(v, u),
    }
}

/// The table cells of a fitted parameter: value ± standard error (in the value's
/// unit) and the 95 % interval, for the header [`PARAMETER_HEADER`].
pub fn parameter_cells(p: &crate::fit::Parameter) -> [String; 2] {
    [
        si_pm(p.value, p.std_error, &p.unit),
        p.ci95
            .map(|[a, b]| si_interval(a, b, p.value, p.std_error, &p.unit))
            .unwrap_or("n/a".into()),
    ]
}

/// Column titles of [`parameter_cells`] (after the parameter's name).
pub const PARAMETER_HEADER: [&str; 2] = ["value ± std. error", "95 % interval"];

/// A value of the constant `name` for a table: a fraction (`mass_fraction`, SI unit
/// 1) as a percentage, anything else by [`si`].
pub fn constant(name: &str, v: f64, unit: &str) -> String {
    match (name.ends_with("_fraction"), unit) {
        (true, "1") if v.is_finite() => format!("{} %", sig(100.0 * v, 5)),
        _ => si(v, unit),
    }
}

/// [`constant`] with its standard error, as [`si_pm`] writes it (a fraction in %),
/// and its 95 % interval in the same scale (None: "—").
pub fn constant_pm(
    name: &str,
    v: f64,
    std: Option<f64>,
    ci95: Option<[f64; 2]>,
    unit: &str,
) -> [String; 2] {
    let (k, unit) = match (name.ends_with("_fraction"), unit) {
        (true, "1") => (100.0, "%"),
        _ => (1.0, unit),
    };
    let std = std.map(|s| k * s);
    [
        si_pm(k * v, std, unit),
        ci95.map(|[a, b]| si_interval(k * a, k * b, k * v, std, unit))
            .unwrap_or("—".into()),
    ]
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

/// A standard deviation for a `±` column: "—" when it is unknown (no tolerance was
/// given: a printed `± 0.0000` would claim an exact value).
pub fn tolerance(std: Option<f64>, fmt: impl Fn(f64) -> String) -> String {
    std.map_or("—".into(), fmt)
}

/// A table column of values in `unit` with one SI prefix for all (the largest
/// magnitude's), `n` significant digits on the largest and the same decimals on the
/// rest: the prefixed unit ("kV") and the cells.
pub fn si_column(values: &[f64], unit: &str, n: usize) -> (String, Vec<String>) {
    let max = values
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let (f, p) = prefix(max);
    let mag = if max == 0.0 {
        0
    } else {
        (max * f).log10().floor() as i32
    };
    let decimals = (n as i32 - 1 - mag).max(0) as usize;
    let cells = values
        .iter()
        .map(|v| format!("{:.decimals$}", v * f))
        .collect();
    (format!("{p}{unit}"), cells)
}

/// The width (characters) every text table and every line printed for people fits.
pub const WIDTH: usize = 100;

/// Narrowest a table column is made to fit [`WIDTH`].
const MIN_COLUMN: usize = 8;

/// `text` broken into lines of at most `width` characters, at spaces where it can
/// (a longer word is cut); no lines for blank text.
pub fn wrap(text: &str, width: usize) -> Vec<String> {
    let width = width.max(1);
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let mut word: Vec<char> = word.chars().collect();
        while !word.is_empty() {
            let used = line.chars().count();
            let room = match used {
                0 => width,
                _ => width.saturating_sub(used + 1),
            };
            if word.len() <= room {
                if used > 0 {
                    line.push(' ');
                }
                line.extend(word.drain(..));
            } else if used > 0 {
                lines.push(std::mem::take(&mut line));
            } else {
                line.extend(word.drain(..width));
                lines.push(std::mem::take(&mut line));
            }
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// A table cell broken into lines of at most `width` characters: a list of values
/// ("1.2 s, 3.4 s": every item at most two words, a number and its unit) between
/// its items, so that a value stays with its unit; prose (a reason with commas in
/// it) and anything longer than `width` by [`wrap`], so a sentence fills its lines
/// instead of breaking at every comma.
fn wrap_list(cell: &str, width: usize) -> Vec<String> {
    if cell
        .split(", ")
        .any(|item| item.split_whitespace().count() > 2)
    {
        return wrap(cell, width);
    }
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    let items: Vec<&str> = cell.split(", ").collect();
    for (k, item) in items.iter().enumerate() {
        let item = match k + 1 < items.len() {
            true => format!("{item},"),
            false => item.to_string(),
        };
        let used = line.chars().count();
        let len = item.chars().count();
        if used > 0 && used + 1 + len <= width {
            line.push(' ');
            line.push_str(&item);
            continue;
        }
        if used > 0 {
            lines.push(std::mem::take(&mut line));
        }
        match len <= width {
            true => line = item,
            false => {
                let mut parts = wrap(&item, width);
                line = parts.pop().unwrap_or_default();
                lines.extend(parts);
            }
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// `text` with every line longer than [`WIDTH`] wrapped at spaces, its continuation
/// lines indented by two spaces; shorter lines (tables, which [`table`] fits) as
/// they are.
pub fn fit_width(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.split_inclusive('\n') {
        let body = line.trim_end_matches('\n');
        if body.chars().count() <= WIDTH {
            out.push_str(line);
            continue;
        }
        let indent = body.len() - body.trim_start().len();
        let lead = &body[..indent];
        for (k, part) in wrap(body, WIDTH.saturating_sub(indent + 2))
            .iter()
            .enumerate()
        {
            out.push_str(lead);
            if k > 0 {
                out.push_str("  ");
            }
            out.push_str(part);
            out.push('\n');
        }
        if !line.ends_with('\n') {
            out.pop();
        }
    }
    out
}

/// Render rows as a left-aligned text table with a header rule, at most [`WIDTH`]
/// characters wide: while wider, the widest column is narrowed (first not below its
/// longest word, then not below 8 characters) and its cells wrap onto continuation
/// lines.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut w: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (i, c) in r.iter().enumerate() {
            w[i] = w[i].max(c.chars().count());
        }
    }
    // A column is narrowed first down to its longest word (no word is cut), and
    // only then, if the table is still too wide, down to MIN_COLUMN.
    let longest = |c: &str| c.split_whitespace().map(|t| t.chars().count()).max();
    let mut word: Vec<usize> = header.iter().map(|h| longest(h).unwrap_or(1)).collect();
    for r in rows {
        for (i, c) in r.iter().enumerate() {
            word[i] = word[i].max(longest(c).unwrap_or(0));
        }
    }
    let gaps = 2 * w.len().saturating_sub(1);
    for floor in [word, vec![MIN_COLUMN; w.len()]] {
        while w.iter().sum::<usize>() + gaps > WIDTH {
            let Some(i) = (0..w.len())
                .filter(|&i| w[i] > floor[i])
                .max_by_key(|&i| w[i])
            else {
                break;
            };
            w[i] -= 1;
        }
    }
    let line = |cells: &[&str]| -> String {
        let wrapped: Vec<Vec<String>> = cells
            .iter()
            .enumerate()
            .map(|(i, c)| match c.chars().count() <= w[i] {
                true => vec![c.to_string()],
                false => wrap_list(c, w[i]),
            })
            .collect();
        let height = wrapped.iter().map(Vec::len).max().unwrap_or(0).max(1);
        let mut out = String::new();
        for k in 0..height {
            let text: Vec<String> = wrapped
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let c = c.get(k).map_or("", String::as_str);
                    format!("{c}{}", " ".repeat(w[i].saturating_sub(c.chars().count())))
                })
                .collect();
            out.push_str(text.join("  ").trim_end());
            out.push('\n');
        }
        out
    };
    let mut out = line(header);
    out.push_str(&"-".repeat(w.iter().sum::<usize>() + gaps));
    out.push('\n');
    for r in rows {
        let cells: Vec<&str> = r.iter().map(String::as_str).collect();
        out.push_str(&line(&cells));
    }
    out
}

/// `x` with `digits` decimals: the same text as `format!("{x:.digits$}")` (no width
/// or fill), without the standard library's exact-digit fallback. The standard
/// library tries Grisu's exact mode first and falls back to Dragon4 (big-integer
/// arithmetic, some 1.5 k instructions a number) whenever Grisu cannot decide the
/// last digit, which is the case for every number with fewer significant digits
/// than asked (4.00). Here, for |x| < 2⁵³ and at most 9 decimals, x = m·2^e (m an
/// integer below 2⁵³) gives x·10^digits = m·10^digits·2^e, an exact integer below
/// 2⁸³ shifted right by −e: rounded to nearest, ties to even, as the standard
/// library rounds the exact value (test `fixed_is_the_standard_format`); other
/// numbers go to the standard library.
pub struct Fixed(pub f64, pub usize);

impl Fixed {
    /// |x|·10^digits rounded to an integer (module notes), None outside the range.
    fn scaled(&self) -> Option<u128> {
        let (x, digits) = (self.0.abs(), self.1);
        if x.is_nan() || x >= 9_007_199_254_740_992.0 || digits > 9 {
            return None;
        }
        let bits = x.to_bits();
        let (biased, fraction) = ((bits >> 52) as i32, u128::from(bits & ((1 << 52) - 1)));
        let (m, e) = if biased == 0 {
            (fraction, -1074)
        } else {
            (fraction | 1 << 52, biased - 1075)
        };
        let n = m * 10u128.pow(digits as u32);
        if e >= 0 {
            return Some(n << e);
        }
        let shift = e.unsigned_abs();
        if shift >= 100 {
            // n < 2⁸³ is below half a unit.
            return Some(0);
        }
        let (q, rem, half) = (n >> shift, n & ((1 << shift) - 1), 1u128 << (shift - 1));
        Some(if rem > half || (rem == half && q & 1 == 1) {
            q + 1
        } else {
            q
        })
    }
}

impl std::fmt::Display for Fixed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (x, digits) = (self.0, self.1);
        let Some(q) = self.scaled() else {
            return write!(f, "{x:.digits$}");
        };
        let sign = if x.is_sign_negative() { "-" } else { "" };
        if digits == 0 {
            return write!(f, "{sign}{q}");
        }
        // In 64 bits where it fits: 128-bit division and printing are library calls.
        match u64::try_from(q) {
            Ok(q) => {
                let unit = 10u64.pow(digits as u32);
                write!(f, "{sign}{}.{:0digits$}", q / unit, q % unit)
            }
            Err(_) => {
                let unit = 10u128.pow(digits as u32);
                write!(f, "{sign}{}.{:0digits$}", q / unit, q % unit)
            }
        }
    }
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
        assert_eq!(si(1.3056e-11, "F"), "13.056 pF");
    }

    /// One prefix per column, from its largest value.
    #[test]
    fn column_shares_one_prefix() {
        let (u, c) = si_column(&[0.0, 5000.0, 20997.4], "V", 5);
        assert_eq!(u, "kV");
        assert_eq!(c, ["0.000", "5.000", "20.997"].map(String::from));
        let (u, c) = si_column(&[1.2e-10, 3.456e-10], "F", 4);
        assert_eq!(u, "pF");
        assert_eq!(c, ["120.0", "345.6"].map(String::from));
    }

    /// The example, and σ in the value's own prefix whatever its size.
    #[test]
    fn value_and_error_share_the_unit() {
        assert_eq!(si_pm(17.328, Some(0.79063), "Pa"), "17.33 ± 0.79 Pa");
        assert_eq!(si_pm(69338.0, Some(349.18), "Pa"), "69.34 ± 0.35 kPa");
        assert_eq!(si_pm(-904.18, Some(30.548), "Pa"), "-904 ± 31 Pa");
        assert_eq!(si_pm(0.1579, Some(0.0060446), "s"), "157.9 ± 6.0 ms");
        assert_eq!(si_pm(221.83, Some(28.399), "s"), "222 ± 28 s");
        // σ larger than the value: the larger's prefix, the value still shown.
        assert_eq!(si_pm(12.0, Some(3400.0), "Pa"), "0.0 ± 3.4 kPa");
        // σ of the hundreds: rounded to its two digits.
        assert_eq!(si_pm(812.3, Some(134.0), "Pa"), "810 ± 130 Pa");
        // bare numbers, and far from 1 a shared power of ten
        assert_eq!(si_pm(2.6993, Some(0.0028), "1"), "2.6993 ± 0.0028");
        assert_eq!(si_pm(1e7, Some(2.5e11), "1"), "(0.0 ± 2.5)e11");
        assert_eq!(si_pm(20.0, Some(1.26), "%"), "20.0 ± 1.3 %");
        assert_eq!(si_pm(69338.0, None, "Pa"), "69.338 kPa (σ n/a)");
        assert_eq!(si_pm(69338.0, Some(0.0), "Pa"), "69.338 kPa (σ n/a)");
        assert_eq!(
            si_interval(68631.0, 70046.0, 69338.0, Some(349.18), "Pa"),
            "[68.63, 70.05] kPa"
        );
        let [v, ci] = constant_pm("mass_fraction", 0.2, Some(0.0126), Some([0.17, 0.23]), "1");
        assert_eq!(
            (v.as_str(), ci.as_str()),
            ("20.0 ± 1.3 %", "[17.0, 23.0] %")
        );
    }

    /// A table wider than 100 characters is narrowed at its widest column, whose
    /// cells wrap; a narrow one is unchanged; long prose lines wrap with an indent.
    #[test]
    fn text_fits_the_width() {
        let long = "word ".repeat(40);
        let rows = vec![
            vec!["1".to_string(), long.trim().to_string(), "x".to_string()],
            vec!["2".to_string(), "short".to_string(), "y".to_string()],
        ];
        let t = table(&["#", "text", "z"], &rows);
        assert!(t.lines().all(|l| l.chars().count() <= WIDTH), "{t}");
        // every word kept, in order
        let words: usize = t.lines().map(|l| l.matches("word").count()).sum();
        assert_eq!(words, 40);
        assert_eq!(
            table(&["a", "b"], &[vec!["1".into(), "2".into()]]),
            "a  b\n----\n1  2\n"
        );
        let prose = format!("warning: {long}\nshort\n");
        let fitted = fit_width(&prose);
        assert!(
            fitted.lines().all(|l| l.chars().count() <= WIDTH),
            "{fitted}"
        );
        assert!(fitted
            .lines()
            .skip(1)
            .take_while(|l| *l != "short")
            .all(|l| l.starts_with("  ")));
        assert!(fitted.ends_with("\nshort\n"));
        assert_eq!(wrap("a bb ccc", 4), ["a bb", "ccc"]);
        assert_eq!(
            wrap_list("172.86 ms, 827.35 ms, 69.510 s", 20),
            ["172.86 ms,", "827.35 ms, 69.510 s"]
        );
        assert_eq!(
            wrap_list("no: the search stopped", 10),
            ["no: the", "search", "stopped"]
        );
        // prose with commas fills its lines (it broke after every comma before)
        assert_eq!(
            wrap_list("no: at the bound, not the trace, holds it there, so", 24),
            ["no: at the bound, not", "the trace, holds it", "there, so"]
        );
        assert_eq!(wrap("abcdefghij", 4), ["abcd", "efgh", "ij"]);
        assert!(wrap("", 10).is_empty());
    }

    #[test]
    fn tolerance_without_one_is_a_dash() {
        assert_eq!(tolerance(None, |v| format!("{v:.4}")), "—");
        assert_eq!(tolerance(Some(0.0123), |v| format!("{v:.4}")), "0.0123");
    }

    /// `Fixed` writes what `format!("{x:.n$}")` writes, character for character: on
    /// random numbers over 40 decades of both signs, on numbers with few significant
    /// digits (where the standard library's Grisu pass gives up), on exact ties at
    /// every digit count (k/2^j, half of a unit in the last place kept), on ±0,
    /// subnormals, the ends of the exact range and beyond (the fallback), NaN and ±∞.
    #[test]
    fn fixed_is_the_standard_format() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let mut xs: Vec<f64> = (0..20_000)
            .map(|_| {
                let v = 10f64.powf(rng.gen_range(-20.0..20.0));
                if rng.gen_bool(0.5) {
                    -v
                } else {
                    v
                }
            })
            .collect();
        xs.extend((0..2000).map(|_| f64::from(rng.gen_range(-100_000..100_000)) / 100.0));
        xs.extend((0..2000).map(|_| f64::from(rng.gen_range(-4096..4096)) / 1024.0));
        xs.extend((1..60).map(|j| 0.5f64.powi(j)));
        xs.extend((1..60).map(|j| 3.0 * 0.5f64.powi(j)));
        xs.extend([
            0.0,
            -0.0,
            0.5,
            1.5,
            2.5,
            0.125,
            0.375,
            1.005,
            4.0,
            9.995,
            999.9995,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            9_007_199_254_740_991.0,
            9_007_199_254_740_992.0,
            1e300,
            -1e300,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ]);
        for x in xs {
            for n in 0..=11 {
                assert_eq!(Fixed(x, n).to_string(), format!("{x:.n$}"), "{x:e} .{n}");
            }
        }
    }
}
