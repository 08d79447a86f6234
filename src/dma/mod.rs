//! DMA frequency sweeps → time–temperature shifts → master curve (`dea-fit dma`).
//!
//! - [`read`]: isotherm files (CSV with units in the headers) → [`DmaData`] in SI;
//! - [`temperature`]: temperatures written as `25 C`, `-5C`, `298.15 K`;
//! - [`synth`]: isotherms made from a Prony series and a shift law (`synth dma`);
//! - [`shift`]: free horizontal (and vertical) shifts of adjacent isotherms, each
//!   with its standard error, accumulated to the reference temperature;
//! - [`law`]: WLF and Arrhenius laws fitted to the free shifts, and how well they fit;
//! - [`fit`]: the pipeline and its result ([`fit::DmaFit`]), with the one seam where the
//!   frequency-domain Prony fit enters;
//! - [`report`]: the summary and the report folder.
//!
//! Method choices and their sources: docs/dma.md.

pub mod fit;
pub mod law;
pub mod read;
pub mod report;
pub mod shift;
pub mod synth;
pub mod temperature;

/// One isotherm (or an already-shifted master curve): the complex modulus against
/// angular frequency, in SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Isotherm {
    /// Its temperature (K); None for a master curve at the reference temperature.
    pub temperature_k: Option<f64>,
    /// Angular frequencies ω (rad/s): strictly increasing in an isotherm,
    /// non-decreasing in a master curve.
    pub omega: Vec<f64>,
    /// Storage modulus E′ (Pa), > 0.
    pub storage: Vec<f64>,
    /// Loss modulus E″ (Pa), > 0.
    pub loss: Vec<f64>,
    /// Source line of each point.
    pub line: Vec<usize>,
    /// The file it came from.
    pub file: String,
}

impl Isotherm {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.omega.len()
    }

    /// Whether it holds no point.
    pub fn is_empty(&self) -> bool {
        self.omega.is_empty()
    }

    /// log10 ω of every point.
    pub fn log_omega(&self) -> Vec<f64> {
        self.omega.iter().map(|w| w.log10()).collect()
    }
}

/// Where DMA data came from: one entry per file read.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DmaSource {
    /// Path as given.
    pub path: String,
    /// SHA-256 of the file's bytes (hex).
    pub sha256: String,
    /// Points read.
    pub points: usize,
    /// Isotherms the file held (0 for a master curve).
    pub isotherms: usize,
    /// Columns as written in the header.
    pub columns: Vec<String>,
    /// What the reader did beyond reading (preamble skipped, units row read, columns
    /// not used, tan δ converted, an isotherm reversed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// DMA data in SI: isotherms sorted by temperature, or one master curve.
#[derive(Debug, Clone, PartialEq)]
pub struct DmaData {
    /// The isotherms, coldest first (one, without temperature, for a master curve).
    pub isotherms: Vec<Isotherm>,
    /// The files.
    pub sources: Vec<DmaSource>,
}

impl DmaData {
    /// Whether the data are one already-shifted master curve.
    pub fn is_master(&self) -> bool {
        self.isotherms.len() == 1 && self.isotherms[0].temperature_k.is_none()
    }
}
