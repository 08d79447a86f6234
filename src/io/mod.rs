//! Reading and writing files: a located delimited-table reader, the tensile-test
//! reader, and atomic writes.

pub mod breakdown;
pub mod lcr;
pub mod manifest;
pub mod relaxation;
pub mod table;
pub mod tensile;
pub mod trace;
pub mod write;

use sha2::{Digest, Sha256};

/// Hex SHA-256 of bytes.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lower-case hex of a digest's bytes.
pub fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// The one guard of the values a command writes (synthetic files, curves, result
/// rows): every value finite, or an error saying which and that nothing was
/// written, so that no file holds `inf` or `NaN` under a good status. `what` names
/// the output (e.g. "the synthetic sweep"), `values` are (column, value) pairs in
/// the order written.
pub fn finite_output<'a>(
    what: &str,
    values: impl IntoIterator<Item = (&'a str, f64)>,
) -> crate::error::Result<()> {
    match values.into_iter().enumerate().find(|(_, (_, v))| !v.is_finite()) {
        None => Ok(()),
        Some((i, (column, v))) => Err(crate::error::Error::settings(format!(
            "{what}: {column} would be {v} (value {} of the output), not a finite number; nothing was written",
            i + 1
        ))
        .with_hint(
            "the inputs are outside the range where the model gives numbers: check their values and units",
        )),
    }
}

/// The start of a synthetic file of a Prony series: the `preamble` lines and the
/// series (`what` says in which reading) as `#` lines, and the seeded relative
/// noise, each call a standard normal draw (ChaCha8 from `seed`: the same file on
/// every machine).
pub fn synthetic_start(
    seed: u64,
    preamble: &[&str],
    what: &str,
    prony: &crate::material::viscoelastic::Prony,
) -> (String, impl FnMut() -> f64) {
    use rand::SeedableRng;
    use rand_distr::Distribution;
    use std::fmt::Write as _;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let unit = rand_distr::Normal::new(0.0, 1.0).expect("valid");
    let mut s = String::new();
    for p in preamble {
        let _ = writeln!(s, "# {p}");
    }
    let _ = writeln!(
        s,
        "# prony {what}: E_inf = {:e} Pa; (tau, E) = {}",
        prony.e_inf,
        prony.terms_text()
    );
    (s, move || unit.sample(&mut rng))
}
