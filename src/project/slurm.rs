//! `dea-fit make --slurm`: the steps that would run, as Slurm batch jobs with
//! their dependencies. A job runs `dea-fit make --only --jobs 1 --no-report
//! <targets…>` in the project folder: make itself runs the steps (in dependency
//! order within the job) and records them in the state (under the state file's
//! lock, [`super::state::State::record`], so jobs ending at once keep each other's
//! records). A last job, `page.sbatch`, rebuilds the project page (`dea-fit make
//! --page-only`) once every step job has ended. `submit.sh` submits them in
//! dependency order, each with `--dependency=afterany:<the jobs of the steps it
//! reads>` (`sbatch --parsable` gives the ids): a job starts once those ended,
//! well or not, and make blocks a step whose need is not up to date, so a failed
//! step blocks only what depends on it (keep-going, as a local make) and no job is
//! left pending on a dependency that can never be met.
//!
//! Small steps share a job: the steps of a quick kind ([`QUICK`], the fits of
//! coupon files, seconds each) are batched, up to `batch` steps a job
//! (`batch-<k>.sbatch`), the others get a job each (`<name>-<step>.sbatch`).
//! Quick steps are grouped by the set of slow steps to run they come after
//! (directly or not), and each group is cut in dependency order: a path from one
//! job to another never comes back, so the jobs' dependencies have no cycle.

use crate::error::{Error, Result};
use crate::io::write::atomic_write;
use crate::project::file::Project;
use crate::project::graph;
use crate::project::run::{Standing, StepReport};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The commands whose steps are quick (a fit of a few coupon files: seconds),
/// batched into shared jobs; `identify` and `rank` get a job each.
pub const QUICK: [&str; 6] = [
    "hyperelastic",
    "relaxation",
    "permittivity",
    "breakdown",
    "dma",
    "composite",
];

/// The jobs of the steps to run (`run[i]`), in submission order: each the steps
/// it runs, in dependency order (`order`), at most `batch` quick steps together.
fn jobs(p: &Project, order: &[usize], run: &[bool], batch: usize) -> Vec<Vec<usize>> {
    let n = p.steps.len();
    let quick = |i: usize| QUICK.contains(&p.steps[i].kind.as_str());
    // the slow steps to run each step comes after, directly or not
    let mut slow: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    for &i in order {
        let mut s = BTreeSet::new();
        for &j in &p.steps[i].needs {
            s.extend(slow[j].iter().copied());
            if run[j] && !quick(j) {
                s.insert(j);
            }
        }
        slow[i] = s;
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    // the open batch of each group of quick steps
    let mut open: std::collections::BTreeMap<&BTreeSet<usize>, usize> = Default::default();
    for &i in order.iter().filter(|&&i| run[i]) {
        if !quick(i) || batch <= 1 {
            out.push(vec![i]);
            continue;
        }
        match open.get(&slow[i]) {
            Some(&k) if out[k].len() < batch => out[k].push(i),
            _ => {
                open.insert(&slow[i], out.len());
                out.push(vec![i]);
            }
        }
    }
    out
}

/// The folder of the scripts, relative to the project.
pub fn dir() -> String {
    format!("{}/slurm", super::STATE_DIR)
}

/// `s` quoted for a POSIX shell.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// One batch script: a job named after `name`, its output in the scripts' folder,
/// running `exe args…` in the project folder.
fn script(project: &Path, exe: &Path, name: &str, args: &[&str]) -> String {
    let mut cmd = quote(&exe.display().to_string());
    for a in args {
        cmd.push(' ');
        cmd.push_str(&quote(a));
    }
    format!(
        "#!/bin/sh\n#SBATCH --job-name=dea-fit-{name}\n#SBATCH --chdir={}\n\
         #SBATCH --output={}/{name}.out\n#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n\
         exec {cmd}\n",
        project.display(),
        dir()
    )
}

/// Write the scripts of the steps of `steps` (where the selected steps stand,
/// [`super::run::status`]) that are not up to date, at most `batch` quick steps a
/// job, the page job and `submit.sh`, into `<project>/.dea-fit/slurm/` (emptied
/// first). `exe` is the program the jobs run (this one). Returns `submit.sh`'s
/// path.
pub fn write(p: &Project, steps: &[StepReport], exe: &Path, batch: usize) -> Result<PathBuf> {
    let project = std::fs::canonicalize(&p.dir).map_err(|e| Error::io(&p.dir, e))?;
    let out = project.join(dir());
    if out.is_dir() {
        std::fs::remove_dir_all(&out).map_err(|e| Error::io(&out, e))?;
    }
    std::fs::create_dir_all(&out).map_err(|e| Error::io(&out, e))?;
    let to_run: BTreeSet<&str> = steps
        .iter()
        .filter(|s| s.state != Standing::UpToDate)
        .map(|s| s.target.as_str())
        .collect();
    let run: Vec<bool> = p
        .steps
        .iter()
        .map(|s| to_run.contains(s.target.as_str()))
        .collect();
    let order = graph::order(p)?;
    let jobs = jobs(p, &order, &run, batch);
    // the job of each step
    let mut job_of = vec![usize::MAX; p.steps.len()];
    for (k, j) in jobs.iter().enumerate() {
        for &i in j {
            job_of[i] = k;
        }
    }
    let mut submit = String::from(
        "#!/bin/sh\n# Submit the jobs of `dea-fit make --slurm` in dependency order.\n\
         set -eu\ncd \"$(dirname \"$0\")\"\n",
    );
    let mut ids = Vec::new();
    let mut batches = 0;
    for (k, j) in jobs.iter().enumerate() {
        let name = if j.len() == 1 && !(batch > 1 && QUICK.contains(&p.steps[j[0]].kind.as_str())) {
            p.steps[j[0]].target.replace('/', "-")
        } else {
            batches += 1;
            format!("batch-{batches}")
        };
        let mut args = vec!["make", "--only", "--jobs", "1", "--no-report"];
        args.extend(j.iter().map(|&i| p.steps[i].target.as_str()));
        atomic_write(
            &out.join(format!("{name}.sbatch")),
            script(&project, exe, &name, &args).as_bytes(),
        )?;
        let after: BTreeSet<usize> = j
            .iter()
            .flat_map(|&i| &p.steps[i].needs)
            .filter(|&&x| run[x] && job_of[x] != k)
            .map(|&x| job_of[x])
            .collect();
        let after: Vec<String> = after.iter().map(|a| format!("$j{a}")).collect();
        let dep = if after.is_empty() {
            String::new()
        } else {
            format!("--dependency=afterany:{} ", after.join(":"))
        };
        let what: Vec<&str> = j.iter().map(|&i| p.steps[i].target.as_str()).collect();
        submit.push_str(&format!(
            "j{k}=$(sbatch --parsable {dep}{name}.sbatch); j{k}=${{j{k}%%;*}}; echo \"{} $j{k}\"\n",
            what.join(" ")
        ));
        ids.push(format!("$j{k}"));
    }
    atomic_write(
        &out.join("page.sbatch"),
        script(&project, exe, "page", &["make", "--page-only"]).as_bytes(),
    )?;
    let dep = if ids.is_empty() {
        String::new()
    } else {
        format!("--dependency=afterany:{} ", ids.join(":"))
    };
    submit.push_str(&format!(
        "j=$(sbatch --parsable {dep}page.sbatch); echo \"page ${{j%%;*}}\"\n"
    ));
    let path = out.join("submit.sh");
    atomic_write(&path, submit.as_bytes())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
            .map_err(|e| Error::io(&path, e))?;
    }
    Ok(path)
}
