//! # dea-fit
//!
//! Material constants and forward simulation for dielectric elastomer actuators.
//!
//! Data flows one way:
//! ```text
//! datasets/*.csv ──io (units→SI, file:line:col errors)──► Dataset (+ provenance)
//! Dataset + checked Settings ──fit──► Fit {params ± σ, status, warnings, report}
//! Fit ──atomic write──► fits/<name>.json (the same object is the --json output)
//! Fit ──report──► reports/<run>/{*.svg, index.md}
//! ```
//!
//! Units: SI everywhere inside (Pa, m, s, N); units appear only at the edges
//! ([`units`], CSV headers, CLI flags, fit files).
#![warn(missing_docs)]

pub mod bench;
pub mod data;
pub mod dma;
pub mod error;
pub mod export;
pub mod fit;
pub mod identify;
pub mod io;
pub mod material;
pub mod numerics;
pub mod observe;
pub mod project;
pub mod rank;
pub mod report;
pub mod sim;
pub mod units;

pub use error::{Error, Result};
