//! The composite-series manifest (TOML): matrix and filler (name, density, εr),
//! default geometry and corrections, the samples (name, export file, filler
//! fraction on a weight or volume basis, per-sample geometry), claims to check and
//! an optional `[synthetic]` table with the parameters that generated the files.
//!
//! ```toml
//! name = "Sylgard 184 + BaTiO3"
//! fraction_basis = "weight"             # default basis of the samples
//! [matrix]
//! name = "Sylgard 184"
//! density = "1.03 g/cm3"
//! eps_r = 2.72
//! [filler]
//! name = "BaTiO3"
//! density = "6.02 g/cm3"
//! eps_r = 6000
//! [geometry]                            # defaults for every sample
//! diameter = "42.8mm±0.05mm"            # or area = "1.439e-3" (m²)
//! thickness = "2.2mm±0.05mm"
//! stray = "0.3pF±0.05pF"                # optional
//! edge = "none"                         # none | air | filled
//! [[sample]]
//! name = "10 wt%"
//! file = "s10.csv"                      # relative to the manifest
//! fraction = 0.10
//! thickness = "2.18mm±0.02mm"           # overrides the default
//! [[claim]]
//! fraction = 0.375
//! increase_pct = 400
//! basis = "unknown"                     # weight | volume | unknown
//! ```
//! Quantities are strings with units (bare numbers are SI). Errors point at the
//! manifest's line and column.

use crate::error::{Error, Location, Result};
use crate::fit::composite::{Basis, Phase, Synthetic};
use crate::fit::permittivity::{EdgeCorrection, Geometry, Settings};
use crate::io::lcr::LcrOptions;
use crate::material::dielectric::{volume_fraction, Pair};
use crate::units::{parse_quantity, parse_uncertain, Dimension, Quantity};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    name: Option<String>,
    fraction_basis: Option<Spanned<String>>,
    matrix: PhaseSpec,
    filler: PhaseSpec,
    #[serde(default)]
    geometry: GeometrySpec,
    #[serde(default)]
    sample: Vec<SampleSpec>,
    #[serde(default)]
    claim: Vec<ClaimSpec>,
    synthetic: Option<Spanned<Synthetic>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PhaseSpec {
    name: String,
    density: Option<Spanned<Text>>,
    eps_r: Option<Spanned<f64>>,
}

/// A quantity written as a string with unit or as a bare SI number.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Text {
    Num(f64),
    Str(String),
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct GeometrySpec {
    area: Option<Spanned<Text>>,
    diameter: Option<Spanned<Text>>,
    thickness: Option<Spanned<Text>>,
    stray: Option<Spanned<Text>>,
    edge: Option<Spanned<String>>,
    pair: Option<Spanned<String>>,
    frequencies: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SampleSpec {
    name: Spanned<String>,
    file: Spanned<String>,
    fraction: Spanned<f64>,
    basis: Option<Spanned<String>>,
    area: Option<Spanned<Text>>,
    diameter: Option<Spanned<Text>>,
    thickness: Option<Spanned<Text>>,
    format: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClaimSpec {
    fraction: Spanned<f64>,
    increase_pct: f64,
    basis: Option<Spanned<String>>,
}

/// One sample of a checked manifest.
#[derive(Debug, Clone)]
pub struct ManifestSample {
    /// Name.
    pub name: String,
    /// Export file (resolved against the manifest's directory).
    pub file: PathBuf,
    /// Filler fraction as written.
    pub fraction: f64,
    /// Its basis.
    pub basis: Basis,
    /// Filler volume fraction.
    pub volume_fraction: f64,
    /// Geometry.
    pub geometry: Geometry,
    /// Export format for synthetic generation.
    pub format: Option<String>,
}

/// A claim to check.
#[derive(Debug, Clone, Copy)]
pub struct Claim {
    /// Fraction as claimed.
    pub fraction: f64,
    /// Claimed increase (%).
    pub increase_pct: f64,
    /// Basis, if stated.
    pub basis: Option<Basis>,
}

/// A checked manifest.
#[derive(Debug, Clone)]
pub struct Manifest {
    /// Its path.
    pub path: PathBuf,
    /// SHA-256 of its bytes.
    pub sha256: String,
    /// Series name.
    pub name: String,
    /// Matrix.
    pub matrix: Phase,
    /// Filler.
    pub filler: Phase,
    /// Samples.
    pub samples: Vec<ManifestSample>,
    /// Claims.
    pub claims: Vec<Claim>,
    /// Permittivity settings (stray, edge).
    pub settings: Settings,
    /// How to read the exports.
    pub lcr: LcrOptions,
    /// Generating parameters of a synthetic series.
    pub synthetic: Option<Synthetic>,
}

/// Line and column (1-based) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rfind('\n')
        .map(|i| before[i + 1..].chars().count())
        .unwrap_or(before.chars().count())
        + 1;
    (line, col)
}

struct Ctx<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Ctx<'_> {
    fn err(&self, span: std::ops::Range<usize>, msg: impl Into<String>) -> Error {
        let (l, c) = line_col(self.text, span.start);
        Error::input(Location::at(self.path, l, c), msg)
    }

    /// The span of `key = …` in the table whose span (or header's) is `table`, up
    /// to the next table header (the table's own span if the key is not written
    /// there: a default).
    fn key_in(&self, table: std::ops::Range<usize>, key: &str) -> std::ops::Range<usize> {
        let rest = self.text.get(table.start..).unwrap_or("");
        let body = match rest.match_indices("\n[").next() {
            Some((end, _)) if end >= table.end - table.start => &rest[..end],
            _ => rest,
        };
        let at = body.match_indices(key).find(|&(i, _)| {
            let line_start = body[..i].rfind('\n').map_or(0, |n| n + 1);
            body[line_start..i].trim().is_empty()
                && body[i + key.len()..].trim_start().starts_with('=')
        });
        match at {
            Some((i, _)) => table.start + i..table.start + i + key.len(),
            None => table,
        }
    }

    /// A quantity with an optional ± standard uncertainty (geometry, stray).
    fn quantity(
        &self,
        q: &Option<Spanned<Text>>,
        dim: Dimension,
        what: &str,
    ) -> Result<Option<Quantity>> {
        let Some(q) = q else { return Ok(None) };
        let text = match q.get_ref() {
            Text::Num(v) => v.to_string(),
            Text::Str(s) => s.clone(),
        };
        parse_uncertain(&text, dim)
            .map(Some)
            .map_err(|e| self.err(q.span(), format!("{what}: {e}")))
    }

    /// A quantity whose uncertainty is not carried (a ± is refused).
    fn value(&self, q: &Option<Spanned<Text>>, dim: Dimension, what: &str) -> Result<Option<f64>> {
        let Some(q) = q else { return Ok(None) };
        match q.get_ref() {
            Text::Num(v) => Ok(Some(*v)),
            Text::Str(s) => parse_quantity(s, dim)
                .map(Some)
                .map_err(|e| self.err(q.span(), format!("{what}: {e}"))),
        }
    }

    fn basis(&self, b: &Spanned<String>, allow_unknown: bool) -> Result<Option<Basis>> {
        match b.get_ref().as_str() {
            "weight" | "wt" | "mass" => Ok(Some(Basis::Weight)),
            "volume" | "vol" => Ok(Some(Basis::Volume)),
            "unknown" | "ambiguous" if allow_unknown => Ok(None),
            other => Err(self
                .err(b.span(), format!("unknown fraction basis '{other}'"))
                .with_hint(if allow_unknown {
                    "use weight, volume or unknown"
                } else {
                    "use weight or volume"
                })),
        }
    }
}

/// Read and check a manifest.
pub fn read(path: &Path) -> Result<Manifest> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &bytes)
}

/// Parse and check manifest bytes that came from `path`.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Manifest> {
    let text = std::str::from_utf8(bytes)
        .map_err(|_| Error::input(Location::file(path), "the manifest is not UTF-8 text"))?;
    let cx = Ctx { path, text };
    let spec: Spec = toml::from_str(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(s) => cx.err(s, msg),
            None => Error::input(Location::file(path), msg),
        }
        .with_hint("see the manifest format in docs/composites.md")
    })?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let phase = |p: &PhaseSpec| -> Result<Phase> {
        let density = cx.value(&p.density, Dimension::Density, "density")?;
        if let (Some(d), Some(s)) = (density, &p.density) {
            if d <= 0.0 {
                return Err(cx.err(s.span(), format!("density must be > 0, found {d}")));
            }
        }
        if let Some(e) = &p.eps_r {
            if *e.get_ref() < 1.0 {
                return Err(cx.err(
                    e.span(),
                    format!("eps_r must be ≥ 1, found {}", e.get_ref()),
                ));
            }
        }
        Ok(Phase {
            name: p.name.clone(),
            density,
            eps_r: p.eps_r.as_ref().map(|e| *e.get_ref()),
        })
    };
    let matrix = phase(&spec.matrix)?;
    let filler = phase(&spec.filler)?;
    let g = &spec.geometry;
    let default_basis = match &spec.fraction_basis {
        Some(b) => cx.basis(b, false)?,
        None => None,
    };
    let stray = cx.quantity(&g.stray, Dimension::Capacitance, "stray")?;
    let edge = match &g.edge {
        None => EdgeCorrection::None,
        Some(e) => match e.get_ref().as_str() {
            "none" => EdgeCorrection::None,
            "air" => EdgeCorrection::Air,
            "filled" => EdgeCorrection::Filled,
            other => {
                return Err(cx
                    .err(e.span(), format!("unknown edge correction '{other}'"))
                    .with_hint("use none, air or filled"))
            }
        },
    };
    let settings = Settings {
        stray: stray.map(|s| s.value),
        stray_std: stray.and_then(|s| s.tolerance),
        edge,
    };
    let mut lcr = LcrOptions::default();
    if let Some(p) = &g.pair {
        lcr.pair = Some(Pair::parse(p.get_ref()).ok_or_else(|| {
            cx.err(p.span(), format!("unknown pair '{}'", p.get_ref()))
                .with_hint("use cp-d, cp-rp, cs-d, cs-rs, z-theta, r-x, g-b, ...")
        })?);
    }
    if let Some(f) = &g.frequencies {
        lcr.frequencies = Some(
            f.get_ref()
                .split(',')
                .map(|s| {
                    parse_quantity(s, Dimension::Frequency)
                        .map_err(|e| cx.err(f.span(), format!("frequencies: {e}")))
                })
                .collect::<Result<_>>()?,
        );
    }
    let (d_area, d_diam, d_thick) = (
        cx.quantity(&g.area, Dimension::Area, "area")?,
        cx.quantity(&g.diameter, Dimension::Length, "diameter")?,
        cx.quantity(&g.thickness, Dimension::Length, "thickness")?,
    );
    let mut samples = Vec::new();
    for s in &spec.sample {
        let name = s.name.get_ref().trim().to_string();
        if name.is_empty() {
            return Err(cx.err(s.name.span(), "empty sample name"));
        }
        if samples.iter().any(|o: &ManifestSample| o.name == name) {
            return Err(cx
                .err(s.name.span(), format!("a second sample named '{name}'"))
                .with_hint("sample names must be unique"));
        }
        let fraction = *s.fraction.get_ref();
        if !(0.0..1.0).contains(&fraction) {
            return Err(cx
                .err(
                    s.fraction.span(),
                    format!("fraction must be in [0, 1), found {fraction}"),
                )
                .with_hint("write 10 % as 0.10"));
        }
        let basis = match &s.basis {
            Some(b) => cx.basis(b, false)?,
            None => default_basis,
        }
        .ok_or_else(|| {
            cx.err(s.fraction.span(), format!("sample '{name}': the fraction basis is not stated"))
                .with_hint("set fraction_basis = \"weight\" (or \"volume\") at the top or basis = ... in the sample")
        })?;
        let phi = match basis {
            Basis::Volume => fraction,
            Basis::Weight => match (filler.density, matrix.density) {
                (Some(rf), Some(rm)) => volume_fraction(fraction, rf, rm),
                _ => {
                    return Err(cx
                        .err(s.fraction.span(), "a weight fraction needs the densities of matrix and filler to give a volume fraction")
                        .with_hint("set density under [matrix] and [filler], e.g. density = \"1.03 g/cm3\""))
                }
            },
        };
        let area = cx.quantity(&s.area, Dimension::Area, "area")?;
        let diameter = cx.quantity(&s.diameter, Dimension::Length, "diameter")?;
        let (area, diameter) = if area.is_some() || diameter.is_some() {
            (area, diameter)
        } else {
            (d_area, d_diam)
        };
        let thickness = cx
            .quantity(&s.thickness, Dimension::Length, "thickness")?
            .or(d_thick);
        let geometry = Geometry::new(area, diameter, thickness)
            .map_err(|e| cx.err(s.name.span(), format!("sample '{name}': {e}")))?;
        let file = s.file.get_ref();
        if file.trim().is_empty() {
            return Err(cx.err(s.file.span(), "empty file name"));
        }
        samples.push(ManifestSample {
            name,
            file: dir.join(file),
            fraction,
            basis,
            volume_fraction: phi,
            geometry,
            format: s.format.clone(),
        });
    }
    let mut claims = Vec::new();
    for c in &spec.claim {
        let fraction = *c.fraction.get_ref();
        if !(0.0..1.0).contains(&fraction) {
            return Err(cx.err(
                c.fraction.span(),
                format!("fraction must be in [0, 1), found {fraction}"),
            ));
        }
        claims.push(Claim {
            fraction,
            increase_pct: c.increase_pct,
            basis: match &c.basis {
                Some(b) => cx.basis(b, true)?,
                None => None,
            },
        });
    }
    if samples.is_empty() && claims.is_empty() {
        return Err(Error::input(
            Location::file(path),
            "the manifest names no sample and no claim",
        )
        .with_hint("add [[sample]] tables (name, file, fraction) or [[claim]] tables"));
    }
    if let Some(s) = &spec.synthetic {
        let phis: Vec<(&str, f64)> = samples
            .iter()
            .map(|x| (x.name.as_str(), x.volume_fraction))
            .collect();
        s.get_ref().check(&phis).map_err(|(key, e)| {
            cx.err(cx.key_in(s.span(), key), e)
                .with_hint("the [synthetic] table must generate finite, physical values at every sample and frequency (docs/composites.md)")
        })?;
    }
    Ok(Manifest {
        path: path.to_path_buf(),
        sha256: super::sha256_hex(bytes),
        name: spec.name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        }),
        matrix,
        filler,
        samples,
        claims,
        settings,
        lcr,
        synthetic: spec.synthetic.map(Spanned::into_inner),
    })
}

/// The geometry sidecar of an export: `<stem>.geometry.toml` beside it, holding
/// any of `area`, `diameter`, `thickness` (quantity strings). Returns the path and
/// (area, diameter, thickness) when the sidecar exists.
#[allow(clippy::type_complexity)]
pub fn sidecar(export: &Path) -> Result<Option<(PathBuf, [Option<Quantity>; 3])>> {
    let path = export.with_extension("geometry.toml");
    let Ok(bytes) = std::fs::read(&path) else {
        return Ok(None);
    };
    let text = std::str::from_utf8(&bytes)
        .map_err(|_| Error::input(Location::file(&path), "the sidecar is not UTF-8 text"))?;
    let cx = Ctx { path: &path, text };
    let g: GeometrySpec = toml::from_str(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(s) => cx.err(s, msg),
            None => Error::input(Location::file(&path), msg),
        }
        .with_hint(
            "a sidecar holds area or diameter, and thickness, e.g. thickness = \"2.2mm±0.05mm\"",
        )
    })?;
    if g.stray.is_some() || g.edge.is_some() || g.pair.is_some() || g.frequencies.is_some() {
        return Err(Error::input(
            Location::file(&path),
            "a geometry sidecar holds only area, diameter and thickness",
        )
        .with_hint("pass --stray, --edge, --pair and --frequencies as flags"));
    }
    let q = [
        cx.quantity(&g.area, Dimension::Area, "area")?,
        cx.quantity(&g.diameter, Dimension::Length, "diameter")?,
        cx.quantity(&g.thickness, Dimension::Length, "thickness")?,
    ];
    Ok(Some((path, q)))
}
