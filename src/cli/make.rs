//! `dea-fit make`: bring a project's steps up to date (docs/project.md).

use dea_fit::project::file::{Flag, Project, KINDS};
use dea_fit::project::run::{self, Standing, StepReport};
use dea_fit::project::state::State;
use dea_fit::Result;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The `-C DIR` of `make`, `status` and `init`.
#[derive(Debug, clap::Args)]
pub struct ProjectDir {
    /// The project folder (the one holding dea-fit.toml)
    #[arg(
        short = 'C',
        long = "directory",
        value_name = "DIR",
        default_value = "."
    )]
    pub dir: PathBuf,
}

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Targets to bring up to date, with the steps they need: names
    /// (vhb4910/tensile), patterns (vhb4910/*) or output patterns (fits/vhb4910-*);
    /// default every step
    targets: Vec<String>,
    #[command(flatten)]
    dir: ProjectDir,
    /// List what would run and why (which input, setting or upstream step changed), run nothing
    #[arg(long)]
    dry_run: bool,
    /// Steps run at once (default: the number of CPUs)
    #[arg(long, short = 'j', value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    jobs: Option<u16>,
    /// Print every step as JSON (target, kind, state, reason, outputs, command)
    #[arg(long)]
    json: bool,
    /// Run every step with --strict (as `strict = true` in the project file): a
    /// blocking status fails the step and blocks what depends on it
    #[arg(long)]
    strict: bool,
    /// Do not write the project page (reports/index.html and index.md)
    #[arg(long)]
    no_report: bool,
    /// Run the named targets only, not the steps they need (a need that is not up
    /// to date blocks them): what each Slurm job runs
    #[arg(long)]
    only: bool,
    /// Run nothing: write the project page from where the steps stand (the last
    /// Slurm job)
    #[arg(long, conflicts_with_all = ["dry_run", "no_report", "slurm"])]
    page_only: bool,
    /// Write the steps that would run as Slurm batch jobs with their dependencies
    /// (.dea-fit/slurm/*.sbatch and submit.sh), run nothing here
    #[arg(long, conflicts_with = "dry_run")]
    slurm: bool,
    /// With --slurm: submit the jobs (sh .dea-fit/slurm/submit.sh)
    #[arg(long, requires = "slurm")]
    submit: bool,
    /// With --slurm: quick steps (fits of coupon files) run up to N to a job; 1 is
    /// one job a step
    #[arg(long, value_name = "N", default_value_t = 8, requires = "slurm",
          value_parser = clap::value_parser!(u16).range(1..))]
    batch: u16,
}

/// The project in `dir`, its steps' flags checked against the commands' own.
pub fn read_project(dir: &Path, strict: bool) -> Result<Project> {
    use clap::CommandFactory;
    let cli = super::Cli::command();
    let flags: HashMap<&str, Vec<Flag>> = KINDS
        .iter()
        .filter_map(|k| {
            let c = cli.find_subcommand(k.1)?;
            let f = c
                .get_arguments()
                .filter_map(|a| {
                    Some(Flag {
                        long: a.get_long()?.to_string(),
                        takes_value: a.get_action().takes_values(),
                    })
                })
                .collect();
            Some((k.1, f))
        })
        .collect();
    Project::read(dir, &|k| flags.get(k).cloned(), strict)
}

pub fn run(a: Args) -> Result<i32> {
    let p = read_project(&a.dir.dir, a.strict)?;
    let jobs = a.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        usize::from,
    );
    let exe = std::env::current_exe().map_err(|e| dea_fit::Error::io("dea-fit", e))?;
    if a.page_only {
        write_page(&p, None, a.json)?;
        return Ok(0);
    }
    if a.slurm {
        return slurm(&p, &a, &exe);
    }
    let opts = run::Options {
        jobs,
        dry_run: a.dry_run,
        targets: a.targets,
        only: a.only,
    };
    let every = opts.targets.is_empty() && !opts.only;
    let (steps, state) = run::make(&p, &opts, &exe)?;
    let what = if a.dry_run { "make --dry-run" } else { "make" };
    print(&a.dir.dir, what, &steps, a.json, a.dry_run);
    if !a.dry_run && !a.no_report {
        // every step up to date: make's own report is what status would say
        let known = every && steps.iter().all(|s| s.state == Standing::UpToDate);
        write_page(&p, known.then_some((steps.as_slice(), &state)), a.json)?;
    }
    let bad = steps
        .iter()
        .any(|s| matches!(s.state, Standing::Failed | Standing::Blocked));
    Ok(i32::from(bad))
}

/// `make --slurm [--submit]`: the selected steps that would run as batch jobs;
/// with `--submit`, submitted. Exit status 0, or 1 when sbatch failed.
fn slurm(p: &Project, a: &Args, exe: &Path) -> Result<i32> {
    let chosen = if a.only {
        dea_fit::project::graph::matched(p, &a.targets)?
    } else {
        dea_fit::project::graph::select(p, &a.targets)?
    };
    let sel: Vec<StepReport> = run::status(p)?
        .0
        .into_iter()
        .filter(|s| {
            p.steps
                .iter()
                .zip(&chosen)
                .any(|(x, &c)| c && x.target == s.target)
        })
        .collect();
    let submit = dea_fit::project::slurm::write(p, &sel, exe, usize::from(a.batch))?;
    print(&a.dir.dir, "make --slurm", &sel, a.json, true);
    let say = |s: String| {
        if a.json {
            eprintln!("{s}");
        } else {
            println!("{s}");
        }
    };
    if !a.submit {
        say(format!(
            "slurm: the jobs of the steps to run are in {}; submit them with: sh {}",
            submit
                .parent()
                .map_or(submit.clone(), Path::to_path_buf)
                .display(),
            submit.display()
        ));
        return Ok(0);
    }
    let o = std::process::Command::new("sh")
        .arg(&submit)
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| dea_fit::Error::io(&submit, e))?;
    for l in String::from_utf8_lossy(&o.stdout).lines() {
        say(format!("submitted {l}"));
    }
    eprint!("{}", String::from_utf8_lossy(&o.stderr));
    Ok(i32::from(!o.status.success()))
}

/// Write the project page from where every step stands now (`known`, or what
/// [`run::status`] says); say where (on stderr with `--json`, which keeps stdout
/// one document), or why not.
fn write_page(p: &Project, known: Option<(&[StepReport], &State)>, json: bool) -> Result<()> {
    use dea_fit::project::page::{self, Wrote};
    let read;
    let (all, state) = match known {
        Some(k) => k,
        None => {
            read = run::status(p)?;
            (read.0.as_slice(), &read.1)
        }
    };
    let said = match page::write(p, all, state)? {
        Wrote::Written(path) => format!("project page: {}", path.display()),
        Wrote::Unchanged(path) => format!("project page: {} (unchanged)", path.display()),
        Wrote::Refused(why) => format!("note: {why}"),
    };
    if json {
        eprintln!("{said}");
    } else {
        println!("{said}");
    }
    Ok(())
}

/// Print a report: one line a step and the summary, or the JSON.
pub fn print(dir: &Path, what: &str, steps: &[StepReport], json: bool, dry_run: bool) {
    let count = |x: Standing| steps.iter().filter(|s| s.state == x).count();
    let counts: Vec<(Standing, usize)> = [
        Standing::Ran,
        Standing::Stale,
        Standing::UpToDate,
        Standing::Failed,
        Standing::Blocked,
    ]
    .into_iter()
    .map(|x| (x, count(x)))
    .collect();
    if json {
        let c: serde_json::Map<String, serde_json::Value> = counts
            .iter()
            .map(|(x, n)| {
                let k = serde_json::to_value(x).expect("a standing serialises");
                (k.as_str().unwrap_or_default().to_string(), (*n).into())
            })
            .collect();
        let v = serde_json::json!({
            "project": dir.display().to_string(),
            "command": what,
            "counts": c,
            "steps": steps,
        });
        println!("{}", serde_json::to_string_pretty(&v).expect("json"));
        return;
    }
    use dea_fit::report::format::{wrap, WIDTH};
    let w = steps
        .iter()
        .map(|s| s.target.chars().count())
        .max()
        .unwrap_or(0);
    for s in steps {
        let word = if dry_run && s.state == Standing::Stale {
            "would run"
        } else {
            s.state.word()
        };
        let head = format!("{word:<10}  {:<w$}  {:<12}  ", s.target, s.kind);
        // the reason fills the rest of a 100-column line, continued under itself
        let indent = head.chars().count().min(WIDTH / 2);
        let lines = wrap(&s.reason, WIDTH - indent);
        let first = lines.first().map_or("", |l| l.as_str());
        println!("{}", format!("{head}{first}").trim_end());
        for l in lines.iter().skip(1) {
            println!("{:indent$}{l}", "");
        }
    }
    let parts: Vec<String> = counts
        .iter()
        .filter(|(_, n)| *n > 0)
        .map(|(x, n)| match (x, dry_run) {
            (Standing::Stale, true) => format!("{n} would run"),
            _ => format!("{n} {}", x.word()),
        })
        .collect();
    let parts = if parts.is_empty() {
        "no steps".to_string()
    } else {
        parts.join(", ")
    };
    println!("{what}: {parts}");
    if counts
        .iter()
        .any(|(x, n)| *n > 0 && matches!(x, Standing::Failed | Standing::Blocked))
    {
        println!(
            "keep-going: a failed step blocks only what depends on it, the rest went on; logs in {}/logs/",
            dea_fit::project::STATE_DIR
        );
    }
}
