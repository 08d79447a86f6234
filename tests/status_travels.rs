//! Issue 34, "the status travels": the identified material file stores the
//! identification's status and each constant's identifiability (an old file without
//! the status still reads: status unknown); a scene that uses a constant its file
//! calls not identifiable warns whenever it runs (`simulate`, `static`), naming the
//! constant and the file; `export` reports the blocking status of the fit it exports
//! (`--strict` exits 1); `static` says when the scene's stretch leaves the range the
//! material was identified over, as `simulate` does (one function).

use crate::material_file::{material, scene_with, write};
use crate::support::{repo, run, run_ok};
use dea_fit::export;
use dea_fit::material::file::{self, IdentifiedMaterial};
use dea_fit::sim::scene::Scene;
use dea_fit::sim::{simulate, RunOptions};
use serde_json::Value;
use std::path::PathBuf;

const OLD: &str = "tests/data/identified/stack-step-identified.json";

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The status written is the status read; a file written before the status was
/// recorded reads, with its status unknown.
#[test]
fn the_identified_file_stores_its_status_and_an_old_one_reads_as_unknown() {
    let dir = tempfile::tempdir().unwrap();
    let m = material();
    let text = m.to_json().unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["status"], "ill_posed");
    let back = IdentifiedMaterial::read(&write(dir.path(), "id.json", &text)).unwrap();
    assert_eq!(back.status.as_deref(), Some("ill_posed"));
    assert_eq!(back.status_text(), "ill_posed");
    let c20 = back.uncertainty.iter().find(|u| u.name == "C20").unwrap();
    assert!(!c20.identifiable);
    let old = IdentifiedMaterial::read(&repo().join(OLD)).unwrap();
    assert_eq!(old.status, None);
    assert_eq!(old.status_text(), "unknown");
    // what a reader is told: the constants called not identifiable, by part, and
    // the blocking status
    let p = dir.path().join("id.json");
    let d = file::doubts(&p, &["hyperelastic"]).unwrap().unwrap();
    assert_eq!(d.names, ["C20"]);
    assert_eq!(d.status.as_deref(), Some("ill_posed"));
    let d = file::doubts(&p, &["viscous"]).unwrap().unwrap();
    assert_eq!(d.names, ["arm1.tau"]);
    // the old file states no constant not identifiable and no status
    assert_eq!(
        file::doubts(&repo().join(OLD), &["hyperelastic", "viscous"]).unwrap(),
        None
    );
}

/// A scene that takes constants its file calls not identifiable warns when it runs,
/// naming them and the file, for the parts it takes: the whole file, or the
/// hyperelastic or the viscous part alone.
#[test]
fn a_scene_using_a_constant_its_file_calls_not_identifiable_warns_when_it_runs() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = material();
    m.status = Some("ok".into());
    write(dir.path(), "id.json", &m.to_json().unwrap());
    let s =
        |material: &str| Scene::parse(&scene_with(material), &dir.path().join("s.toml")).unwrap();
    let file = dir.path().join("id.json").display().to_string();
    let cases = [
        ("identified = \"id.json\"\n", "C20, arm1.tau"),
        (
            "hyperelastic = { fit = \"id.json\" }\nviscous = { preset = \"elatrache2021-table-4.2\" }\nrelative_permittivity = 4.7\n",
            "C20",
        ),
        (
            "hyperelastic = { preset = \"vhb4910-yeoh\" }\nviscous = { fit = \"id.json\" }\nrelative_permittivity = 4.7\n",
            "arm1.tau",
        ),
    ];
    for (material, names) in cases {
        let scene = s(material);
        let o = simulate(&scene, &RunOptions::default()).unwrap();
        let want =
            format!("{file}: it calls {names} not identifiable from the data it was fitted to");
        let said: Vec<&String> = o.warnings.iter().filter(|w| w.starts_with(&want)).collect();
        assert_eq!(said.len(), 1, "{material}: {:?}", o.warnings);
    }
    // constants from presets and inline: nothing to say
    let plain = s("hyperelastic = { preset = \"vhb4910-yeoh\" }\nviscous = { preset = \"elatrache2021-table-4.2\" }\nrelative_permittivity = 4.7\n");
    assert!(plain.doubts.is_empty());
}

/// `simulate` and `static` of one scene say the same things about its material:
/// the constants its file calls not identifiable, and a stretch outside the range
/// the material was identified over (here 0.999–1.001 uniaxial: the scene's 5 kV
/// step contracts the stack below it, statically and in the run).
#[test]
fn static_and_simulate_warn_alike_on_the_material_of_a_scene() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = material();
    let r = &mut m.hyperelastic.ranges.as_mut().unwrap().per_mode[0];
    (r.stretch_min, r.stretch_max) = (0.999, 1.001);
    write(dir.path(), "id.json", &m.to_json().unwrap());
    std::fs::write(
        dir.path().join("s.toml"),
        scene_with("identified = \"id.json\"\n"),
    )
    .unwrap();
    // (a contraction below the uniaxial range is equibiaxial tension, for which the
    // identification, uniaxial only, had no data)
    let range =
        "needs equibiaxial behaviour, for which the fit had no data: the model is extrapolated";
    let named = "calls C20, arm1.tau not identifiable";
    let o = run_ok(
        dir.path(),
        &[
            "simulate",
            "s.toml",
            "--json",
            "--no-report",
            "--out",
            "run.csv",
        ],
    );
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    let sim: Vec<String> = serde_json::from_value(v["warnings"].clone()).unwrap();
    let o = run_ok(dir.path(), &["static", "s.toml", "--json", "--no-report"]);
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    let stat: Vec<String> = serde_json::from_value(v["warnings"].clone()).unwrap();
    for (what, w) in [("simulate", &sim), ("static", &stat)] {
        assert!(w.iter().any(|x| x.contains(range)), "{what}: {w:?}");
        assert!(w.iter().any(|x| x.contains(named)), "{what}: {w:?}");
    }
    // and in the text output
    let o = run_ok(dir.path(), &["static", "s.toml", "--no-report"]);
    let text = stdout(&o).replace('\n', " ").replace("  ", " ");
    assert!(
        text.contains("warning:") && text.contains("not identifiable"),
        "{text}"
    );
}

fn card(files: &[PathBuf]) -> export::Card {
    export::card(
        &export::read(files).unwrap(),
        export::Target::Abaqus,
        &export::Options::default(),
    )
    .unwrap()
}

/// `export` of an identified file carries its status: a blocking one is the card's
/// status and a warning naming the constants not identifiable, and `--strict`
/// exits 1; an old file without a status says `status unknown`.
#[test]
fn export_reports_the_blocking_status_of_an_identified_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "id.json", &material().to_json().unwrap());
    let c = card(std::slice::from_ref(&p));
    assert_eq!(c.status, "ill_posed");
    assert!(
        c.warnings.iter().any(|w| w.contains("has status ill_posed")
            && w.contains("it calls C20, arm1.tau not identifiable")),
        "{:?}",
        c.warnings
    );
    assert!(c.sources[0]
        .describe()
        .ends_with("(identified material, status ill_posed)"));
    assert_eq!(c.exit_code(true), 1);
    let o = run(
        dir.path(),
        &[
            "export", "id.json", "--to", "abaqus", "--strict", "--out", "c.inp",
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    let text = stdout(&o);
    assert!(text.contains("status: ill_posed"), "{text}");
    assert!(
        text.contains("source: id.json (identified material, status ill_posed)"),
        "{text}"
    );
    let o = run(
        dir.path(),
        &["export", "id.json", "--to", "abaqus", "--out", "d.inp"],
    );
    assert_eq!(
        o.status.code(),
        Some(0),
        "without --strict a status does not fail"
    );
    // an old file: status unknown, not blocking by itself
    let c = card(&[repo().join(OLD)]);
    assert!(
        c.sources[0]
            .describe()
            .ends_with("(identified material, status unknown)"),
        "{:?}",
        c.sources
    );
    assert_ne!(c.status, "ill_posed");
}

/// A hyperelastic fit written by `dea-fit hyperelastic` states each parameter's
/// identifiability; `export` of the Treloar Ogden-3 fit (μ1, μ3, α3 not
/// identifiable) names them, carries `ill_posed`, and `--strict` exits 1.
#[test]
fn export_reports_the_constants_a_hyperelastic_fit_calls_not_identifiable() {
    let dir = tempfile::tempdir().unwrap();
    let t = |m: &str| {
        repo()
            .join(format!("datasets/treloar/{m}.csv"))
            .display()
            .to_string()
    };
    let o = run(
        dir.path(),
        &[
            "hyperelastic",
            &t("uniaxial"),
            "--equibiaxial",
            &t("equibiaxial"),
            "--planar",
            &t("planar"),
            "--model",
            "ogden3",
            "--no-report",
            "--out",
            "o3.json",
        ],
    );
    assert_eq!(o.status.code(), Some(0));
    let o = run(
        dir.path(),
        &[
            "export", "o3.json", "--to", "abaqus", "--strict", "--out", "o3.inp",
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    let text = stdout(&o).replace('\n', " ").replace("  ", " ");
    assert!(text.contains("has status ill_posed"), "{text}");
    assert!(
        text.contains("it calls mu1, mu3, alpha3 not identifiable"),
        "{text}"
    );
}
