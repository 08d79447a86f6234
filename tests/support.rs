//! Helpers every test module that runs the real binary shares.

use dea_fit::identify::problem::{simulated, ChannelKind, Experiment};
use dea_fit::sim::scene::Scene;
use dea_fit::sim::{simulate, RunOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `[actuator]` table of the seed's stack (seed Table 4.1: 10 layers of 500 µm
/// VHB between 50 µm electrodes, 2.25 mm radius), for scenes written in tests.
pub const SEED_STACK_ACTUATOR: &str = r#"[actuator]
kind = "stack"
radius = "2.25 mm"
layer_thickness = "500 um"
electrode_thickness = "50 um"
layers = 10
electrodes = 11
"#;

/// Run `dea-fit` with `args` in `cwd` and require exit status 0 (stderr shown
/// otherwise).
pub fn run_ok(cwd: &Path, args: &[&str]) -> Output {
    let o = run(cwd, args);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Run `dea-fit` with `args` in `cwd`.
pub fn run(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dea-fit"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the dea-fit binary runs")
}

/// Copy a folder tree (files and folders) into `to`, creating it.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for e in std::fs::read_dir(from).expect("read dir") {
        let e = e.expect("entry");
        let target = to.join(e.file_name());
        if e.file_type().expect("type").is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).expect("copy");
        }
    }
}

/// Names in a directory, sorted (empty when it does not exist).
pub fn names_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// A breakdown fit as `dea-fit breakdown --out` writes it (the core's serde struct):
/// α = 30 V/µm at a 1 cm² specimen area, β = 10, 15 breakdowns, with standard
/// errors `se_alpha` (V/m) and `se_beta` and their correlation `rho`.
pub fn breakdown_fit(
    se_alpha: f64,
    se_beta: f64,
    rho: f64,
) -> dea_fit::material::file::BreakdownFit {
    use dea_fit::material::file::{BreakdownFit, BreakdownParameter, BREAKDOWN_SCHEMA};
    let p = |name: &str, unit: &str, value: f64, s: f64| BreakdownParameter {
        name: name.into(),
        unit: unit.into(),
        value,
        std_error: Some(s),
        ci95: None,
    };
    BreakdownFit {
        schema: BREAKDOWN_SCHEMA.into(),
        tool_version: "test".into(),
        status: "ok".into(),
        method: "mle".into(),
        positions: None,
        n: 15,
        failures: 15,
        survived: 0,
        parameters: vec![
            p("alpha", "V/m", 30e6, se_alpha),
            p("beta", "1", 10.0, se_beta),
        ],
        correlation: vec![vec![Some(1.0), Some(rho)], vec![Some(rho), Some(1.0)]],
        beta_unbiased: None,
        log_likelihood: -20.0,
        percentiles: Vec::new(),
        reference_area: Some(1e-4),
        reference_thickness: None,
        reference_prestretch: None,
        thickness_range: None,
        prestretch_range: None,
        bounds: "fisher".into(),
        warnings: Vec::new(),
        provenance: serde_json::Value::Null,
    }
}

/// A trace of `scene` with Gaussian noise: (quantity, σ) per channel, seeded.
pub fn trace(scene: &Scene, channels: &[(ChannelKind, f64)], seed: u64) -> Experiment {
    Experiment::synthetic(scene, channels, seed).expect("the scene runs")
}

/// Noise σ of each channel as a fraction of its peak |value| in `truth`.
pub fn relative_noise(truth: &Scene, rel: &[(ChannelKind, f64)]) -> Vec<(ChannelKind, f64)> {
    let o = simulate(truth, &RunOptions::default()).expect("runs");
    let s0 = o.samples[0];
    rel.iter()
        .map(|&(q, r)| {
            let peak = o
                .samples
                .iter()
                .map(|s| simulated(q, &s0, s).abs())
                .fold(0.0, f64::max);
            (q, r * peak)
        })
        .collect()
}

/// The binary as a command whose interrupts (SIGINT, SIGTERM, SIGHUP) have their
/// default action in the child, as when started from a terminal: a test suite run
/// as a background job of a shell without job control inherits SIGINT ignored, and
/// `dea-fit` keeps an ignored signal ignored (src/main.rs), so a test that
/// interrupts it would test nothing there.
#[cfg(unix)]
pub fn interruptible() -> Command {
    use std::os::unix::process::CommandExt;
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_dea-fit"));
    // SAFETY: signal() is async-signal-safe; it changes the child alone.
    unsafe {
        cmd.pre_exec(|| {
            for s in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                if libc::signal(s, libc::SIG_DFL) == libc::SIG_ERR {
                    return Err(std::io::Error::last_os_error());
                }
            }
            Ok(())
        });
    }
    cmd
}
