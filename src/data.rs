//! Test data in SI, built only through [`crate::io`], with provenance.

use crate::material::hyperelastic::Mode;
use serde::{Deserialize, Serialize};

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
