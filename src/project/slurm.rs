//! `dea-fit make --slurm`: the steps that would run, as Slurm batch jobs with
//! their dependencies. Each step becomes `.dea-fit/slurm/<name>-<step>.sbatch`,
//! which runs `dea-fit make --only --jobs 1 --no-report <target>` in the project
//! folder: make itself runs the step and records it in the state file (under the
//! state file's lock, [`super::state::State::record`], so jobs ending at once keep
//! each other's records). A last job, `page.sbatch`, rebuilds the project page
//! (`dea-fit make --page-only`) once every step job has ended, well or not.
//! `submit.sh` submits them in dependency order, each with
//! `--dependency=afterok:<the jobs of the steps it reads>` (`sbatch --parsable`
//! gives the ids).

use crate::error::{Error, Result};
use crate::io::write::atomic_write;
use crate::project::file::Project;
use crate::project::graph;
use crate::project::run::{Standing, StepReport};
use std::path::{Path, PathBuf};

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
/// [`super::run::status`]) that are not up to date, the page job and
/// `submit.sh`, into `<project>/.dea-fit/slurm/` (emptied first). `exe` is the
/// program the jobs run (this one). Returns `submit.sh`'s path.
pub fn write(p: &Project, steps: &[StepReport], exe: &Path) -> Result<PathBuf> {
    let project = std::fs::canonicalize(&p.dir).map_err(|e| Error::io(&p.dir, e))?;
    let out = project.join(dir());
    if out.is_dir() {
        std::fs::remove_dir_all(&out).map_err(|e| Error::io(&out, e))?;
    }
    std::fs::create_dir_all(&out).map_err(|e| Error::io(&out, e))?;
    let runs = |t: &str| {
        steps
            .iter()
            .any(|s| s.target == t && s.state != Standing::UpToDate)
    };
    let order = graph::order(p)?;
    let mut submit = String::from(
        "#!/bin/sh\n# Submit the jobs of `dea-fit make --slurm` in dependency order.\n\
         set -eu\ncd \"$(dirname \"$0\")\"\n",
    );
    let mut ids = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        let s = &p.steps[i];
        if !runs(&s.target) {
            continue;
        }
        let name = s.target.replace('/', "-");
        let args = ["make", "--only", "--jobs", "1", "--no-report", &s.target];
        atomic_write(
            &out.join(format!("{name}.sbatch")),
            script(&project, exe, &name, &args).as_bytes(),
        )?;
        let after: Vec<String> = s
            .needs
            .iter()
            .filter(|&&j| runs(&p.steps[j].target))
            .map(|&j| {
                let at = order.iter().position(|&x| x == j).expect("in order");
                format!("$j{at}")
            })
            .collect();
        let dep = if after.is_empty() {
            String::new()
        } else {
            format!("--dependency=afterok:{} ", after.join(":"))
        };
        submit.push_str(&format!(
            "j{k}=$(sbatch --parsable {dep}{name}.sbatch); j{k}=${{j{k}%%;*}}; echo \"{} $j{k}\"\n",
            s.target
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
