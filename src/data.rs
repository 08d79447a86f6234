//! Test data in SI, built only through [`crate::io`], with provenance, and the domain
//! every tensile point must lie in ([`Sample::check`], [`Dataset::check`]).

use crate::error::{Error, Location, Result};
use crate::fit::problem::PARALLEL_ROWS;
use crate::material::hyperelastic::Mode;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Plausible stretches of a tensile test, (smallest, largest).
///
/// * Above: elastomers break below λ ≈ 10 in uniaxial tension (VHB 4910 near 8–10, the
///   most extensible ones near 20–30); 100 leaves an order of magnitude, and a larger
///   "stretch" is a displacement or a force read as one.
/// * Below: uniaxial compression to λ is equibiaxial tension at λ^-1/2, so 0.01 is the
///   state of an equibiaxial stretch of 10, beyond what any elastomer survives; a
///   smaller stretch is a strain (≈ 0 at the start of a test) read as a stretch.
pub const STRETCH_RANGE: (f64, f64) = (0.01, 100.0);

/// Largest plausible |nominal stress| (Pa): 1 GPa is more than ten times the tensile
/// strength of the strongest elastomers (polyurethanes, ≈ 50–70 MPa); a larger value is
/// a unit error (Pa written as MPa reads 10⁶ times too large).
pub const STRESS_MAX: f64 = 1e9;

/// Stretches closer to 1 than this are the reference state: every model gives zero
/// stress there, so such a point carries no information about the parameters.
pub const REFERENCE_TOL: f64 = 1e-9;

/// Which value of a sample is outside the domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// The stretch (or the deformation column it came from).
    Stretch,
    /// The nominal stress (or the stress or force column it came from).
    Stress,
    /// The weight.
    Weight,
}

/// A sample outside the domain: which value, what is wrong, what to do.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    /// The value at fault.
    pub field: Field,
    /// What was expected and found.
    pub message: String,
    /// What to do.
    pub hint: String,
}

/// One measured point of a homogeneous test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Deformation mode.
    pub mode: Mode,
    /// Stretch λ in the loading direction.
    pub stretch: f64,
    /// Nominal stress (Pa).
    pub stress: f64,
    /// Relative weight (> 0; 1 when the file has no weight column).
    pub weight: f64,
    /// Index of the source file in [`Dataset::sources`].
    pub source: usize,
    /// Line of the source file the point came from.
    pub line: usize,
}

/// A number as an error message shows it: plain for everyday magnitudes, in
/// exponent form for huge and tiny ones (1e200, not 201 digits).
fn short(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e6 || v.abs() < 1e-3) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

impl Sample {
    /// The domain of a tensile point: a finite stretch in [`STRETCH_RANGE`] (≥ 1 in
    /// equibiaxial and planar tests, which stretch the coupon), a finite stress with
    /// |P| ≤ [`STRESS_MAX`], a finite weight > 0.
    pub fn check(&self) -> std::result::Result<(), Fault> {
        let fault = |field, message: String, hint: &str| {
            Err(Fault {
                field,
                message,
                hint: hint.to_string(),
            })
        };
        let (lam, (lo, hi)) = (self.stretch, STRETCH_RANGE);
        if lam.is_nan() || lam <= 0.0 {
            return fault(
                Field::Stretch,
                format!("stretch must be > 0, found {}", short(lam)),
                "is this column a strain? name it 'strain' or 'strain_pct'",
            );
        }
        if !lam.is_finite() || lam > hi {
            return fault(
                Field::Stretch,
                format!("stretch {}: a stretch above {hi} is not a tensile test", short(lam)),
                "is this column a displacement? name it e.g. 'displacement_mm' and pass --gauge-length",
            );
        }
        if lam < lo {
            return fault(
                Field::Stretch,
                format!(
                    "stretch {}: a stretch below {lo} would squeeze the coupon to under 1 % of its length",
                    short(lam)
                ),
                "is this column a strain? name it 'strain' or 'strain_pct'",
            );
        }
        if matches!(self.mode, Mode::Equibiaxial | Mode::Planar) && lam < 1.0 {
            return fault(
                Field::Stretch,
                format!(
                    "{} tests stretch the coupon: stretch must be ≥ 1, found {lam}",
                    self.mode
                ),
                "compression of a layer is uniaxial compression (stretch < 1 in a uniaxial file)",
            );
        }
        let p = self.stress;
        if !p.is_finite() {
            return fault(
                Field::Stress,
                format!("nominal stress must be a finite number, found {p}"),
                "is the unit right? check the stress column and its conversion",
            );
        }
        if p.abs() > STRESS_MAX {
            return fault(
                Field::Stress,
                format!(
                    "nominal stress {} Pa: no elastomer test reaches 1 GPa",
                    short(p)
                ),
                "is the unit right? a column in Pa labelled MPa reads 10⁶ times too large",
            );
        }
        let w = self.weight;
        if !w.is_finite() {
            return fault(
                Field::Weight,
                format!("weight must be a finite number, found {w}"),
                "weights are relative: e.g. 1 for every point",
            );
        }
        if w <= 0.0 {
            return fault(
                Field::Weight,
                format!("weight must be > 0, found {}", short(w)),
                "drop the point instead of giving it weight 0",
            );
        }
        Ok(())
    }

    /// True if the point lies in the reference state (λ = 1 within [`REFERENCE_TOL`]).
    pub fn is_reference(&self) -> bool {
        (self.stretch - 1.0).abs() <= REFERENCE_TOL
    }
}

/// Where a set of samples came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Source {
    /// Path as given by the user.
    pub path: String,
    /// SHA-256 of the file's bytes (hex).
    pub sha256: String,
    /// Modes found in the file.
    pub modes: Vec<Mode>,
    /// Number of points read.
    pub points: usize,
    /// Smallest stretch.
    pub stretch_min: f64,
    /// Largest stretch.
    pub stretch_max: f64,
    /// Columns as written in the header.
    pub columns: Vec<String>,
    /// Conversions applied on reading (e.g. true → nominal stress).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub conversions: Vec<String>,
    /// What the reader did beyond reading (preamble skipped, units row read, columns
    /// not used, which of two deformation columns was used).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// What the reader found wrong without refusing the file (two deformation or
    /// stress columns that disagree): each makes the fit's status a warning.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Samples of one or several files.
#[derive(Debug, Clone, Default)]
pub struct Dataset {
    /// All samples, in file order.
    pub samples: Vec<Sample>,
    /// The files they came from.
    pub sources: Vec<Source>,
}

impl Dataset {
    /// Append another dataset, renumbering its sources.
    pub fn extend(&mut self, other: Dataset) {
        if self.sources.is_empty() && self.samples.is_empty() {
            // The first file: its sources are numbered from 0 already.
            *self = other;
            return;
        }
        let off = self.sources.len();
        self.samples.extend(other.samples.into_iter().map(|mut s| {
            s.source += off;
            s
        }));
        self.sources.extend(other.sources);
    }

    /// Modes present, in [`Mode::ALL`] order.
    pub fn modes(&self) -> Vec<Mode> {
        Mode::ALL
            .into_iter()
            .filter(|m| self.samples.iter().any(|s| s.mode == *m))
            .collect()
    }

    /// Check every sample ([`Sample::check`]) and the data as a whole: at least one
    /// point, some load (not every stress 0) and some deformation (not every stretch
    /// 1). The estimators call it, so data built without the reader are checked too.
    pub fn check(&self) -> Result<()> {
        let whole = |msg: &str, hint: &str| match self.sources.as_slice() {
            [one] => Error::input(Location::file(&one.path), msg).with_hint(hint),
            _ => Error::settings(msg).with_hint(hint),
        };
        if self.samples.is_empty() {
            return Err(whole(
                "the data hold no points",
                "give at least one tensile-test file with data rows",
            ));
        }
        // The first sample in order that fails (a large dataset searched in parallel).
        let bad = |s: &Sample| s.check().is_err();
        let first = if self.samples.len() < PARALLEL_ROWS {
            self.samples.iter().position(bad)
        } else {
            self.samples.par_iter().position_first(bad)
        };
        if let Some((s, Err(f))) = first.map(|i| (&self.samples[i], self.samples[i].check())) {
            let loc = match self.sources.get(s.source) {
                Some(src) => Location::line(&src.path, s.line),
                None => Location::line("<data>", s.line),
            };
            return Err(Error::input(loc, f.message).with_hint(f.hint));
        }
        if self.samples.iter().all(|s| s.stress == 0.0) {
            return Err(whole(
                "every stress is 0: the data hold no load to fit",
                "is the stress column the right one?",
            ));
        }
        if self.samples.iter().all(Sample::is_reference) {
            return Err(whole(
                "every stretch is 1: the data hold no deformation to fit",
                "is the stretch column the right one? a test must stretch the coupon",
            ));
        }
        Ok(())
    }

    /// Points away from the reference state λ = 1 ([`Sample::is_reference`]): the
    /// ones that carry information about a model's parameters.
    pub fn informative_points(&self) -> usize {
        self.samples.iter().filter(|s| !s.is_reference()).count()
    }

    /// (min, max) stretch of the samples in `mode`.
    pub fn stretch_range(&self, mode: Mode) -> Option<(f64, f64)> {
        self.samples
            .iter()
            .filter(|s| s.mode == mode)
            .fold(None, |acc, s| match acc {
                None => Some((s.stretch, s.stretch)),
                Some((a, b)) => Some((a.min(s.stretch), b.max(s.stretch))),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The check names the first failing sample in order, also when a large dataset is
    /// searched in parallel (two bad samples, the later one in an earlier-finishing
    /// block would be found first by an unordered search).
    #[test]
    fn the_first_bad_sample_is_reported() {
        for n in [100, 4 * PARALLEL_ROWS] {
            let mut samples: Vec<Sample> = (0..n)
                .map(|i| Sample {
                    mode: Mode::Uniaxial,
                    stretch: 1.0 + i as f64 / n as f64,
                    stress: 1e3 * i as f64,
                    weight: 1.0,
                    source: 0,
                    line: i + 2,
                })
                .collect();
            samples[n - 3].stretch = -1.0;
            samples[n / 2].weight = 0.0;
            let data = Dataset {
                samples,
                sources: Vec::new(),
            };
            let e = data.check().unwrap_err().to_string();
            assert!(e.contains(&format!("<data>:{}", n / 2 + 2)), "{e}");
            assert!(e.contains("weight"), "{e}");
        }
    }
}
