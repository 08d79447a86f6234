//! A lab's pipeline in one file (`dea-fit.toml`, docs/project.md): every step is
//! one command a user would type (`dea-fit hyperelastic …`, `dea-fit identify …`),
//! named by a target (`vhb4910/tensile`); `dea-fit make` runs the steps whose
//! identity changed, in dependency order, independent ones in parallel.
//!
//! - [`file`]: the project file → steps (argument lists, inputs, outputs, the
//!   targets each reads), with located errors.
//! - [`glob`]: the file patterns of the project file, expanded in sorted order.
//! - [`graph`]: dependency order, cycles, the steps a selection needs.
//! - [`identity`]: a step's identity (SHA-256 of its inputs, settings, the tool
//!   version and its upstream identities) and the stat cache that spares hashing.
//! - [`state`]: what ran, kept in `<project>/.dea-fit/state.json`, written atomically.
//! - [`run`]: what is stale and why; the job queue that runs the steps.
//! - [`refs`]: `{ target = "…" }` inside scene and design files.
//! - [`page`]: the project page, `reports/index.html`.
//! - [`slurm`]: the steps as Slurm batch jobs (`make --slurm`).

pub mod file;
pub mod glob;
pub mod graph;
pub mod identity;
pub mod page;
pub mod refs;
pub mod run;
pub mod slurm;
pub mod state;

/// The project file's name.
pub const FILE: &str = "dea-fit.toml";
/// The folder of a project's state and logs.
pub const STATE_DIR: &str = ".dea-fit";
