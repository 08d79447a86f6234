//! Targets inside scene and design files: a value `{ target = "vhb4910/tensile" }`
//! in a scene (docs/scenes.md) or a design manifest (docs/rank.md) names a step of
//! the project the file belongs to (the nearest `dea-fit.toml` in its folder or
//! above), and stands for that step's fit file:
//!
//! - as a table of a fit: `hyperelastic = { target = "vhb4910/tensile" }` is
//!   `hyperelastic = { fit = "<the fit file>" }`, and `breakdown = { target = "…",
//!   prestretch = 3 }` keeps its other keys;
//! - in place of a path: a table holding `target` alone under a key that takes a
//!   fit file's path (`fit`, `composite`, `identified`) is that path:
//!   `permittivity = { composite = { target = "sylgard_batio3/composite" } }`.
//!
//! [`resolve`] rewrites the text that way before the scene or manifest reader
//! reads it (the path relative to the file, as a path written there would be);
//! `make` finds the references with [`scan`] and runs the step after the targets
//! it names ([`super::file`]). A file without the word `target` is not parsed
//! twice.

use crate::error::{Error, Location, Result};
use std::borrow::Cow;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue};

/// Keys whose value is a fit file's path: a lone `{ target = "…" }` there is the path.
const PATH_KEYS: [&str; 3] = ["fit", "composite", "identified"];

/// One `{ target = "…" }` of a TOML text.
#[derive(Debug, Clone, PartialEq)]
pub struct Ref {
    /// The target's name.
    pub target: String,
    /// Byte offset of the name (its opening quote), for errors.
    pub at: usize,
    /// The bytes to replace, and whether with the path alone (in place of a
    /// path) or with `fit = <path>` (the `target = "…"` pair of a fit table).
    replace: Range<usize>,
    path_only: bool,
}

/// What a TOML text names: its target references and its string values (with
/// their byte offsets), in the text's order; nothing for a text that is not TOML
/// (its reader says why).
#[derive(Debug, Default)]
pub struct Scan {
    /// The `{ target = "…" }` values.
    pub refs: Vec<Ref>,
    /// Every other string value, with the offset of its opening quote.
    pub strings: Vec<(String, usize)>,
}

/// The references and strings of `text`.
pub fn scan(text: &str) -> Scan {
    let mut s = Scan::default();
    if let Ok(root) = DeTable::parse(text) {
        table(text, root.get_ref(), &mut s);
    }
    s.refs.sort_by_key(|r| r.at);
    s.strings.sort_by_key(|x| x.1);
    s
}

fn table(text: &str, t: &DeTable<'_>, s: &mut Scan) {
    for (k, v) in t.iter() {
        value(text, k.get_ref(), v, s);
    }
}

fn value(text: &str, key: &str, v: &toml::Spanned<DeValue<'_>>, s: &mut Scan) {
    match v.get_ref() {
        DeValue::String(x) => s.strings.push((x.to_string(), v.span().start)),
        DeValue::Array(a) => a.iter().for_each(|x| value(text, key, x, s)),
        DeValue::Table(t) => {
            let target = t
                .iter()
                .find(|(k, _)| k.get_ref() == "target")
                .and_then(|(k, x)| x.get_ref().as_str().map(|name| (k, x, name)));
            match target {
                Some((k, x, name)) => {
                    let span = v.span();
                    let inline = text
                        .get(span.clone())
                        .is_some_and(|b| b.starts_with('{') && b.ends_with('}'));
                    let path_only = inline && t.len() == 1 && PATH_KEYS.contains(&key);
                    s.refs.push(Ref {
                        target: name.to_string(),
                        at: x.span().start,
                        replace: if path_only {
                            span
                        } else {
                            k.span().start..x.span().end
                        },
                        path_only,
                    });
                    // its other keys (a prestretch) are plain values
                    for (k2, x2) in t.iter().filter(|(k2, _)| k2.get_ref() != "target") {
                        value(text, k2.get_ref(), x2, s);
                    }
                }
                None => table(text, t, s),
            }
        }
        _ => {}
    }
}

/// 1-based line and column (in characters) of a byte offset of `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, text[start..offset].chars().count() + 1)
}

/// The nearest folder holding a project file, from the folder of `file` up, and
/// how many levels up it is (0: the file's own folder).
pub fn project_above(file: &Path) -> Option<(PathBuf, usize)> {
    let dir = match file.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let abs = std::fs::canonicalize(dir).ok()?;
    abs.ancestors()
        .enumerate()
        .find(|(_, d)| d.join(super::FILE).is_file())
        .map(|(up, d)| (d.to_path_buf(), up))
}

/// `text` (read from `file`) with its target references replaced by the paths of
/// the fit files they name, relative to `file`'s folder; `text` itself when it
/// has none. A reference outside a project, to a target the project does not
/// have, or to one that writes no fit file, is a located error.
pub fn resolve<'t>(text: &'t str, file: &Path) -> Result<Cow<'t, str>> {
    if !text.contains("target") {
        return Ok(Cow::Borrowed(text));
    }
    let refs = scan(text).refs;
    let Some(first) = refs.first() else {
        return Ok(Cow::Borrowed(text));
    };
    let at = |r: &Ref| {
        let (l, c) = line_col(text, r.at);
        Location::at(file, l, c)
    };
    let Some((dir, up)) = project_above(file) else {
        return Err(Error::input(
            at(first),
            format!(
                "target '{}': no project file ({}) in this file's folder or above",
                first.target,
                super::FILE
            ),
        )
        .with_hint("a { target = \"<name>/<step>\" } names a step of the project the file belongs to (docs/project.md); outside a project, give the fit file's path: { fit = \"fits/x.json\" }"));
    };
    let fits = super::file::fit_files(&dir)?;
    let names: Vec<&str> = fits.iter().map(|(t, _)| t.as_str()).collect();
    let project = dir.join(super::FILE);
    let mut out = String::with_capacity(text.len());
    let mut from = 0;
    for r in &refs {
        let fit = match fits.iter().find(|(t, _)| *t == r.target) {
            Some((_, Some(f))) => f,
            Some((_, None)) => {
                return Err(Error::input(
                    at(r),
                    format!("target '{}' writes no fit file to read", r.target),
                )
                .with_hint(format!(
                    "name a step that writes a fit ({})",
                    project.display()
                )))
            }
            None => {
                return Err(Error::input(
                    at(r),
                    format!(
                        "no target '{}' in the project {}",
                        r.target,
                        project.display()
                    ),
                )
                .with_hint(format!(
                    "{}targets: {}",
                    super::file::near(&r.target, &names),
                    names.join(", ")
                )))
            }
        };
        let path = format!("{}{fit}", "../".repeat(up));
        let quoted = toml::Value::String(path).to_string();
        out.push_str(&text[from..r.replace.start]);
        if r.path_only {
            out.push_str(&quoted);
        } else {
            out.push_str("fit = ");
            out.push_str(&quoted);
        }
        from = r.replace.end;
    }
    out.push_str(&text[from..]);
    Ok(Cow::Owned(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fit table's target becomes its fit key, a lone target under a path key
    /// the path, other keys stay; files without targets are left alone.
    #[test]
    fn targets_resolve_to_fit_paths() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(
            d.path().join(super::super::FILE),
            "[materials.vhb.tensile]\nfiles = \"a.csv\"\n[materials.vhb.breakdown]\nfiles = \"b.csv\"\n[designs.x.rank]\ndesign = \"d.toml\"\n",
        )
        .unwrap();
        std::fs::create_dir_all(d.path().join("scenes")).unwrap();
        let scene = d.path().join("scenes/s.toml");
        let text = "[material]\nhyperelastic = { target = \"vhb/tensile\" }\nbreakdown = { target = \"vhb/breakdown\", prestretch = 3 }\np = { composite = { target = \"vhb/tensile\" }, rule = \"x\" }\n";
        let out = resolve(text, &scene).unwrap();
        assert_eq!(
            out,
            "[material]\nhyperelastic = { fit = \"../fits/vhb-tensile.json\" }\nbreakdown = { fit = \"../fits/vhb-breakdown.json\", prestretch = 3 }\np = { composite = \"../fits/vhb-tensile.json\", rule = \"x\" }\n"
        );
        let plain = "[material]\nhyperelastic = { fit = \"x.json\" }\n";
        assert!(matches!(resolve(plain, &scene).unwrap(), Cow::Borrowed(_)));
        // a misspelt target: located, with the near miss
        let e = resolve("h = { target = \"vhb/tensil\" }\n", &scene).unwrap_err();
        let m = e.to_string();
        assert!(m.contains("s.toml:1:"), "{m}");
        assert!(m.contains("did you mean 'vhb/tensile'"), "{m}");
        // one that writes no fit
        let e = resolve("h = { target = \"x/rank\" }\n", &scene).unwrap_err();
        assert!(e.to_string().contains("writes no fit"), "{e}");
        // outside any project
        let o = tempfile::tempdir().unwrap();
        let e = resolve(
            "h = { target = \"vhb/tensile\" }\n",
            &o.path().join("s.toml"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("no project file"), "{e}");
    }
}
