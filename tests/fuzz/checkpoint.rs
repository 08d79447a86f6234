//! The `checkpoint` surface (docs/fuzzing.md): mutated checkpoint files of
//! `dea-fit identify`, resumed through the library (`identify::identify_with` with
//! `--resume`'s control). Seeds are made at run time from repository files: the
//! checkpoint of start 0 after one iteration on the worked example's step trace
//! (problem A, `a.0`) and on the same trace with its contraction 10 % larger
//! (problem B, `b.0`: same length, another problem). Every case resumes problem
//! A. Besides no panic, hang or abort: a case seeded from B must be refused (an
//! accepted one returns another problem's state as A's), and an accepted case
//! seeded from A must end as the uninterrupted run of A does (its constants bit
//! for bit: a mutation that leaves the content alike, such as white space).

use super::readers::Verdict;
use dea_fit::fit::lm::{Checkpoint, Control};
use dea_fit::identify::problem::{ChannelKind, Experiment};
use dea_fit::identify::{identify, identify_with, Run, Settings};
use dea_fit::sim::scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The worked example's trace and scene (problem A).
const TRACE: &str = "datasets/identify/step.csv";
const SCENE: &str = "datasets/identify/stack.toml";

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// One free constant, one start: a case resumes in tens of milliseconds.
fn settings() -> Settings {
    Settings {
        free: Some(vec!["eps_r".into()]),
        starts: 1,
        ..Settings::default()
    }
}

/// Problems A and B, and A's constants uninterrupted.
struct Fixture {
    a: Vec<Experiment>,
    b: Vec<Experiment>,
    reference: Vec<u64>,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let base = Scene::read(&repo(SCENE)).expect("the worked example's scene");
        let t = dea_fit::io::trace::read(&repo(TRACE)).expect("the worked example's trace");
        let a = vec![Experiment::from_trace(&t, &base).expect("its experiment")];
        let mut b = a.clone();
        for c in &mut b[0].channels {
            if c.kind == ChannelKind::Contraction {
                c.values.iter_mut().for_each(|v| *v *= 1.1);
            }
        }
        let reference = constants(identify(a.clone(), &settings()).expect("problem A runs"))
            .expect("problem A is identified");
        Fixture { a, b, reference }
    })
}

/// The identified constants' bits, or why there are none.
fn constants(run: Run) -> Result<Vec<u64>, String> {
    match run {
        Run::Identified(id) => Ok(id.parameters.iter().map(|p| p.value.to_bits()).collect()),
        Run::Failed(f) => Err(format!("status {}", f.status)),
    }
}

/// `--checkpoint base` (`base.0`, `base.1`, …), resumed or not.
fn control(base: &Path, resume: bool) -> impl Fn(usize) -> Control + Sync + '_ {
    move |i| Control {
        checkpoint: Some(
            Checkpoint {
                file: base.to_path_buf(),
                every: 1,
                problem: Vec::new(),
            }
            .for_start(i),
        ),
        resume,
        ..Control::default()
    }
}

/// The seeds: `a.0` (problem A's checkpoint of start 0 after one iteration) and
/// `b.0` (problem B's).
pub fn seeds() -> Vec<Vec<(String, Vec<u8>)>> {
    let f = fixture();
    let dir = tempfile::tempdir().expect("a temporary directory");
    let one = Settings {
        lm: dea_fit::fit::lm::LmSettings {
            max_iterations: 1,
            ..settings().lm
        },
        ..settings()
    };
    [("a", &f.a), ("b", &f.b)]
        .into_iter()
        .map(|(name, exps)| {
            let base = dir.path().join(name);
            identify_with(exps.clone(), &one, &control(&base, false)).expect("a seed run");
            let file = format!("{name}.0");
            let bytes = std::fs::read(dir.path().join(&file)).expect("start 0 checkpointed");
            vec![(file, bytes)]
        })
        .collect()
}

/// Resume problem A from the case's file (`a.0` or `b.0` in `path`'s directory).
pub fn run(path: &Path) -> Verdict {
    let f = fixture();
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    let foreign = name.as_deref() == Some("b.0");
    let base = path.with_file_name(if foreign { "b" } else { "a" });
    let run = match identify_with(f.a.clone(), &settings(), &control(&base, true)) {
        Err(_) => return Verdict::Refused,
        Ok(run) => run,
    };
    if foreign {
        return Verdict::Failed {
            class: "checkpoint: another problem's checkpoint accepted".into(),
            detail: format!("{:?}", constants(run)),
        };
    }
    match constants(run) {
        Ok(c) if c == f.reference => Verdict::Accepted,
        got => Verdict::Failed {
            class: "checkpoint: an accepted checkpoint changed the result".into(),
            detail: format!("{got:?}, uninterrupted {:?}", f.reference),
        },
    }
}

/// The command that replays a case written to `dir`.
pub fn replay(file: &str, dir: &Path) -> String {
    let base = file.trim_end_matches(".0");
    format!(
        "dea-fit identify {} --scene {} --free eps_r --starts 1 --checkpoint {} --resume --no-report --out {}",
        repo(TRACE).display(),
        repo(SCENE).display(),
        dir.join(base).display(),
        dir.join("out.json").display()
    )
}
