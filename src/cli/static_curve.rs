//! `dea-fit static`: static voltage–stretch curve of a scene's actuator and its peak.

use dea_fit::sim::{full_plant, scene::Scene, static_curve};
use dea_fit::Result;
use std::path::PathBuf;

/// Static (fully relaxed) voltage–stretch curve and pull-in of a scene's actuator.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Print JSON (`curve`, `pull_in`).
    #[arg(long)]
    json: bool,
    /// Number of curve points.
    #[arg(long, default_value_t = 200)]
    points: usize,
    /// Smallest stretch examined.
    #[arg(long, default_value_t = 0.3)]
    stretch_min: f64,
}

/// Run the subcommand.
pub fn run(a: Args) -> Result<i32> {
    let scene = Scene::read(&a.scene)?;
    if !(a.stretch_min > 0.0 && a.stretch_min < 1.0) {
        return Err(dea_fit::Error::settings("--stretch-min must be in (0, 1)"));
    }
    let p = full_plant(&scene);
    let c = static_curve::static_curve(&p, a.points, a.stretch_min);
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&c).expect("serialisable")
        );
    } else {
        match c.pull_in {
            Some(pi) => println!(
                "{}: pull-in at stretch {:.6}, {:.1} V (rest stretch {:.6})",
                scene.name, pi.stretch, pi.voltage_v, p.lam0
            ),
            None => println!(
                "{}: no pull-in down to stretch {} (V rises monotonically)",
                scene.name, a.stretch_min
            ),
        }
    }
    Ok(0)
}
