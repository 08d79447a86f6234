//! The static voltage–stretch curve for people and for files: its shape as a table,
//! the whole curve as CSV, and a report page (the table and the voltage–stretch
//! chart with the pull-in marked).

use super::format::{si, si_column, table};
use super::page::{code, text, Page, Tone};
use super::plot::{Chart, Series, Style};
use super::runs::Run;
use crate::error::Result;
use crate::sim::static_curve::{Point, StaticCurve};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Rows of the shape table spanning the curve (the pull-in is added to them).
pub const SHAPE_ROWS: usize = 10;

/// The curve's shape: [`SHAPE_ROWS`] points evenly spaced along it (first and last
/// included) and the pull-in in its place by stretch, marked; voltage and
/// capacitance with one SI prefix per column.
pub fn shape_table(c: &StaticCurve) -> String {
    let (header, cells) = shape_rows(c);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    table(&header, &cells)
}

/// The header and rows of [`shape_table`].
fn shape_rows(c: &StaticCurve) -> (Vec<String>, Vec<Vec<String>>) {
    let n = c.curve.len();
    let mut rows: Vec<(Point, &str)> = match n {
        0 => Vec::new(),
        1 => vec![(c.curve[0], "")],
        _ => {
            let k = SHAPE_ROWS.min(n);
            let mut idx: Vec<usize> = (0..k).map(|i| i * (n - 1) / (k - 1)).collect();
            idx.dedup();
            idx.into_iter().map(|i| (c.curve[i], "")).collect()
        }
    };
    if let Some(pi) = c.pull_in {
        let at = rows.partition_point(|(p, _)| p.stretch > pi.stretch);
        rows.insert(at, (pi, "pull-in"));
    }
    let (vu, vs) = si_column(
        &rows.iter().map(|r| r.0.voltage_v).collect::<Vec<_>>(),
        "V",
        5,
    );
    let (cu, cs) = si_column(
        &rows.iter().map(|r| r.0.capacitance_f).collect::<Vec<_>>(),
        "F",
        5,
    );
    let cells: Vec<Vec<String>> = rows
        .iter()
        .zip(vs.into_iter().zip(cs))
        .map(|((p, note), (v, cap))| vec![v, format!("{:.6}", p.stretch), cap, note.to_string()])
        .collect();
    (
        vec![
            format!("voltage ({vu})"),
            "stretch".into(),
            format!("capacitance ({cu})"),
            String::new(),
        ],
        cells,
    )
}

/// What a static run found, for its report.
pub struct Outcome<'a> {
    /// The scene's name.
    pub scene: &'a str,
    /// The scene file as given.
    pub input: &'a str,
    /// The curve and its peak.
    pub curve: &'a StaticCurve,
    /// `ok`, `pull_in` or `failed`.
    pub status: &'a str,
    /// The one-line verdict (the pull-in and the scene's input against it).
    pub message: &'a str,
    /// The scene's largest input voltage (V).
    pub input_peak_v: f64,
}

/// Write `curve.svg` (voltage against stretch, the pull-in marked, the scene's
/// largest input as a dashed line) and the page (`index.md`, `index.html`,
/// `run.json`: the verdict, the chart and the shape table) into `dir`; returns the
/// HTML page.
pub fn write(o: &Outcome, dir: &Path) -> Result<PathBuf> {
    let c = o.curve;
    let mut series = vec![Series {
        label: "static equilibrium V(λ)".into(),
        points: c.curve.iter().map(|p| (p.voltage_v, p.stretch)).collect(),
        color: 0,
        style: Style::Line,
    }];
    if let Some(pi) = c.pull_in {
        series.push(Series {
            label: format!("pull-in: λ {:.4} at {}", pi.stretch, si(pi.voltage_v, "V")),
            points: vec![(pi.voltage_v, pi.stretch)],
            color: 1,
            style: Style::Points,
        });
    }
    let (lo, hi) = c
        .curve
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.stretch), b.max(p.stretch))
        });
    if o.input_peak_v.is_finite() && lo < hi {
        series.push(Series {
            label: format!("the scene's largest input, {}", si(o.input_peak_v, "V")),
            points: vec![(o.input_peak_v, lo), (o.input_peak_v, hi)],
            color: 2,
            style: Style::Dashed,
        });
    }
    let chart = Chart {
        title: format!("{}: static voltage–stretch curve", o.scene),
        x_label: "voltage".into(),
        y_label: "stretch λ".into(),
        series,
        log_x: false,
        x_unit: Some("V".into()),
        y_unit: None,
    };
    let mut page = Page::new(format!("Static curve: {}", o.scene));
    page.para(vec![text("Scene: "), code(o.input)]);
    page.status_line(o.status, Tone::of(o.status));
    page.text(format!("{}.", o.message));
    page.chart(dir, "curve.svg", "static voltage–stretch curve", &chart)?;
    page.heading("Shape of the curve");
    let (header, rows) = shape_rows(c);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    page.table(&header, rows);
    let mut headline = match c.pull_in {
        Some(pi) => vec![
            format!("pull-in {}", si(pi.voltage_v, "V")),
            format!("λ {:.4}", pi.stretch),
        ],
        None => vec!["no pull-in found".into()],
    };
    headline.push(format!("input peak {}", si(o.input_peak_v, "V")));
    let run = Run::new("static", o.input, "static curve").headline(headline);
    page.write(dir, "index", run)
}

/// The whole curve as CSV, SI units in the headers (`voltage_V,stretch,capacitance_F`),
/// values at full precision (shortest text that reads back to the same number).
pub fn curve_csv(c: &StaticCurve) -> String {
    let mut s = String::from("voltage_V,stretch,capacitance_F\n");
    for p in &c.curve {
        let _ = writeln!(s, "{},{},{:e}", p.voltage_v, p.stretch, p.capacitance_f);
    }
    s
}
