//! Subcommands, one file each.

mod bench;
mod bench_identify;
mod bench_integrators;
mod bench_make;
mod bench_rank;
mod bench_relaxation;
mod bench_scale;
mod bench_simulate;
mod breakdown;
mod completions;
mod composite;
mod dma;
mod export;
mod hyperelastic;
mod identify;
mod init;
mod make;
mod man;
mod permittivity;
mod rank;
mod relaxation;
mod simulate;
mod static_curve;
mod status;
mod synth;

use clap::{Parser, Subcommand};
use dea_fit::Result;

/// Material constants and forward simulation for dielectric elastomer actuators.
#[derive(Debug, Parser)]
#[command(name = "dea-fit", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Fit hyperelastic strain-energy coefficients to tensile-test data.
    Hyperelastic(hyperelastic::Args),
    /// Relative permittivity and loss per frequency from LCR-meter exports.
    Permittivity(permittivity::Args),
    /// Weibull breakdown strength of a specimen series: α, β, percentiles, bounds, probability plot.
    Breakdown(breakdown::Args),
    /// Fit mixing rules to a composite series described by a TOML manifest.
    Composite(composite::Args),
    /// Identify material constants from measured actuator traces (simulator in the loop).
    Identify(identify::Args),
    /// Fit Prony / Kelvin-Maxwell constants to a stress-relaxation curve.
    Relaxation(relaxation::Args),
    /// DMA isotherms → time–temperature shifts (free, WLF, Arrhenius) → master curve.
    Dma(dma::Args),
    /// Generate synthetic test data from known constants (with noise and seed).
    Synth(Box<synth::Args>),
    /// Simulate an actuator scene: trajectory CSV, charts, summary.
    Simulate(simulate::Args),
    /// Static voltage–stretch curve and pull-in of a scene's actuator.
    Static(static_curve::Args),
    /// Write the material card of a fit for an FE code (Abaqus, ANSYS, LS-DYNA, FEBio, COMSOL).
    Export(export::Args),
    /// Rank fillers and composites by what they buy an actuator (sweeps, shards, Slurm).
    Rank(rank::Args),
    /// Bring a project's fits, identifications and rankings up to date (dea-fit.toml).
    Make(make::Args),
    /// Where each step of a project stands: up to date, stale, failed or blocked, and why.
    Status(status::Args),
    /// Write dea-fit.toml from the data files in a folder, for the user to edit.
    Init(init::Args),
    /// Measure speed against accuracy and write tables and charts under reports/.
    Bench(bench::Args),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell).
    Completions(completions::Args),
    /// Write the man pages (the top page on stdout, or one per command with --out).
    Man(man::Args),
}

/// Run a parsed command line; returns the exit status.
pub fn run(cli: Cli) -> Result<i32> {
    match cli.command {
        Command::Hyperelastic(a) => hyperelastic::run(a),
        Command::Relaxation(a) => relaxation::run(a),
        Command::Dma(a) => dma::run(a),
        Command::Identify(a) => identify::run(a),
        Command::Synth(a) => synth::run(*a),
        Command::Permittivity(a) => permittivity::run(a),
        Command::Composite(a) => composite::run(a),
        Command::Breakdown(a) => breakdown::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Static(a) => static_curve::run(a),
        Command::Export(a) => export::run(a),
        Command::Rank(a) => rank::run(a),
        Command::Make(a) => make::run(a),
        Command::Status(a) => status::run(a),
        Command::Init(a) => init::run(a),
        Command::Completions(a) => completions::run(a),
        Command::Man(a) => man::run(a),
    }
}

/// The name of a run's data in default file and report names: `<folder>-<stem>`
/// of its (first) file, e.g. `treloar-uniaxial` for datasets/treloar/uniaxial.csv
/// (the stem alone for a file without a folder, `fallback` without a stem).
pub fn data_name(file: &std::path::Path, fallback: &str) -> String {
    let s = file.file_stem().map_or_else(
        || fallback.to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    match file.parent().and_then(|p| p.file_name()) {
        Some(d) => format!("{}-{s}", d.to_string_lossy()),
        None => s,
    }
}

/// Output flags every fitting command shares.
#[derive(Debug, clap::Args)]
pub struct Output {
    /// Fit file to write (default fits/<data>-<model>.json).
    #[arg(long)]
    out: Option<std::path::PathBuf>,
    /// Report directory (default reports/<data>-<model>/).
    #[arg(long)]
    report: Option<std::path::PathBuf>,
    /// Do not write a report.
    #[arg(long)]
    no_report: bool,
    /// Print the fit as JSON on stdout (the fit file's object).
    #[arg(long)]
    pub json: bool,
    /// Exit with status 1 when the fit's status is ill_posed, unstable or not_converged
    /// (`warning` never blocks).
    #[arg(long)]
    strict: bool,
}

impl Output {
    /// The fit file and report directory of a run named `name`: `--out` or
    /// fits/<name>.json, and `--report` or reports/<name>/ unless `--no-report`.
    pub fn paths(&self, name: &str) -> (std::path::PathBuf, Option<std::path::PathBuf>) {
        use std::path::Path;
        let out = self
            .out
            .clone()
            .unwrap_or_else(|| Path::new("fits").join(format!("{name}.json")));
        let dir = (!self.no_report).then(|| {
            self.report
                .clone()
                .unwrap_or_else(|| Path::new("reports").join(name))
        });
        (out, dir)
    }

    /// The common end of every fitting command: take the report directory, write the
    /// fit file (keeping an older, different fit aside, `same` tells them apart), the
    /// report, then print the summary with where both went, or the JSON; returns the
    /// exit status.
    pub fn deliver<T: serde::Serialize>(
        &self,
        name: &str,
        fit: &T,
        status: dea_fit::fit::Status,
        same: impl Fn(&str) -> bool,
        summary: impl FnOnce() -> Result<String>,
        report: impl FnOnce(&std::path::Path) -> Result<std::path::PathBuf>,
    ) -> Result<i32> {
        let (out, dir) = self.paths(name);
        let json = serde_json::to_string_pretty(fit).expect("a fit serialises");
        refuse_in_report(dir.as_deref(), &[("--out", Some(&out))])?;
        if let Some(d) = &dir {
            claim_dir(d)?;
        }
        write_fit_noted(&out, json.as_bytes(), same)?;
        let page = dir.map(|d| report(&d)).transpose()?;
        if self.json {
            println!("{json}");
        } else {
            print!("{}", summary()?);
            println!("fit: {}", out.display());
            if let Some(r) = &page {
                println!("report: {}", r.display());
            }
        }
        Ok(status.exit_code(self.strict))
    }
}

/// Write a fit or result file by the one file policy ([`dea_fit::io::write`]): a
/// different old file is kept aside, and stderr says where.
pub fn write_fit_noted(
    path: &std::path::Path,
    bytes: &[u8],
    same: impl Fn(&str) -> bool,
) -> Result<()> {
    note(
        path,
        "fit",
        &dea_fit::io::write::write_fit(path, bytes, same)?,
    );
    Ok(())
}

/// Write any other single output file (trajectory, synthetic data, generated
/// export) by the same policy: a different old file is kept aside (compared in
/// chunks, as [`commit_noted`] does).
pub fn write_noted(path: &std::path::Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let mut f = dea_fit::io::write::AtomicFile::create(path)?;
    f.write_all(bytes)
        .map_err(|e| dea_fit::Error::io(path, e))?;
    commit_noted(f)
}

/// Put a streamed single output file in place as [`write_noted`] does.
pub fn commit_noted(file: dea_fit::io::write::AtomicFile) -> Result<()> {
    let path = file.path().to_path_buf();
    note(&path, "file", &file.commit_keeping()?);
    Ok(())
}

fn note(path: &std::path::Path, what: &str, r: &dea_fit::io::write::Replaced) {
    if let dea_fit::io::write::Replaced::KeptAs(p) = r {
        eprintln!(
            "note: {} held a different {what}; it was kept as {}",
            path.display(),
            p.display()
        );
    }
}

pub use dea_fit::io::write::claim_dir;

/// Refuse an output file of a command that overlaps the command's own report
/// folder (lies in it, is it, or holds it): the report writes its files there
/// (`index.md`, `index.html`, `run.json`, charts, a trajectory) and replaces them on
/// every run, so such an output would be replaced by the report, or the report
/// refused. Called by every command with both, before anything is written;
/// `outputs` pairs each output with its flag. Paths are compared absolute, `.` and
/// `..` resolved, through the symbolic links of the part that exists.
pub fn refuse_in_report(
    report: Option<&std::path::Path>,
    outputs: &[(&str, Option<&std::path::Path>)],
) -> Result<()> {
    let Some(dir) = report else { return Ok(()) };
    let d = resolved(dir);
    for (flag, out) in outputs {
        let Some(out) = out else { continue };
        let o = resolved(out);
        if o.starts_with(&d) || d.starts_with(&o) {
            return Err(dea_fit::Error::settings(format!(
                "{flag} {} overlaps the report folder {}: the report writes its own files there (index.md, index.html, run.json, charts) and replaces them on every run",
                out.display(),
                dir.display()
            ))
            .with_hint(format!(
                "write {flag} outside {}, or choose another --report (or --no-report)",
                dir.display()
            )));
        }
    }
    Ok(())
}

/// `p` absolute, with `.` and `..` resolved, and the longest part of it that exists
/// through its symbolic links (so `rep/../rep/x` and a link to `rep` are `rep`).
fn resolved(p: &std::path::Path) -> std::path::PathBuf {
    use std::path::{Component, PathBuf};
    let abs = std::env::current_dir().map_or_else(|_| p.to_path_buf(), |c| c.join(p));
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out = out.canonicalize().unwrap_or(out);
                out.pop();
            }
            c => out.push(c),
        }
    }
    let mut head = out.clone();
    let mut tail = Vec::new();
    loop {
        if let Ok(mut real) = head.canonicalize() {
            real.extend(tail.iter().rev());
            return real;
        }
        match head.file_name() {
            Some(n) => tail.push(n.to_os_string()),
            None => return out,
        }
        head.pop();
    }
}
