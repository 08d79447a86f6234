//! The static voltage–stretch curve for people and for files: its shape as a table,
//! the whole curve as CSV, and a report page (the table and the voltage–stretch
//! chart with the pull-in marked and, where the scene states breakdown, the
//! breakdown voltage V_b(λ) = Eb·h(λ) and the point where the curve meets it).

use super::format::{si, si_column, table};
use super::page::{code, text, Page, Tone};
use super::plot::{Chart, Series, Style};
use super::runs::Run;
use crate::error::Result;
use crate::sim::breakdown::{v_per_um, Check};
use crate::sim::scene::Actuator;
use crate::sim::static_curve::{Point, StaticCurve};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Rows of the shape table spanning the curve (the pull-in is added to them).
pub const SHAPE_ROWS: usize = 10;

/// The breakdown a static curve is checked against: the breakdown voltage
/// V_b(λ) = Eb·h(λ) of the actuator's electrode gap h (`Actuator::gap`), and the
/// point of the stable branch where the curve meets it, if any.
pub struct BreakdownLine<'a> {
    /// The actuator (its gap).
    pub actuator: &'a Actuator,
    /// Breakdown field Eb (V/m).
    pub field: f64,
    /// Where the curve's field reaches Eb on the stable branch.
    pub point: Option<Point>,
}

impl BreakdownLine<'_> {
    /// V_b(λ) = Eb·h(λ) (V).
    pub fn voltage(&self, lam: f64) -> f64 {
        self.field * self.actuator.gap(lam)
    }
}

/// The curve's shape: [`SHAPE_ROWS`] points evenly spaced along it (first and last
/// included) and the pull-in in its place by stretch, marked; voltage and
/// capacitance with one SI prefix per column. With a breakdown line, a column of
/// the breakdown voltage V_b(λ) and the point where the curve meets it, marked.
pub fn shape_table(c: &StaticCurve, b: Option<&BreakdownLine>) -> String {
    let (header, cells) = shape_rows(c, b);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    table(&header, &cells)
}

/// The header and rows of [`shape_table`].
fn shape_rows(c: &StaticCurve, b: Option<&BreakdownLine>) -> (Vec<String>, Vec<Vec<String>>) {
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
    for (q, note) in [
        (c.pull_in, "pull-in"),
        (b.and_then(|b| b.point), "breakdown"),
    ] {
        if let Some(q) = q {
            let at = rows.partition_point(|(p, _)| p.stretch > q.stretch);
            rows.insert(at, (q, note));
        }
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
    let breakdown = b.map(|b| {
        si_column(
            &rows
                .iter()
                .map(|r| b.voltage(r.0.stretch))
                .collect::<Vec<_>>(),
            "V",
            5,
        )
    });
    let cells: Vec<Vec<String>> = rows
        .iter()
        .zip(vs.into_iter().zip(cs))
        .enumerate()
        .map(|(i, ((p, note), (v, cap)))| {
            let mut row = vec![v, format!("{:.6}", p.stretch), cap];
            if let Some((_, bv)) = &breakdown {
                row.push(bv[i].clone());
            }
            row.push(note.to_string());
            row
        })
        .collect();
    let mut header = vec![
        format!("voltage ({vu})"),
        "stretch".into(),
        format!("capacitance ({cu})"),
    ];
    if let Some((bu, _)) = &breakdown {
        header.push(format!("breakdown V_b ({bu})"));
    }
    header.push(String::new());
    (header, cells)
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
    /// The breakdown line, where the scene states breakdown.
    pub breakdown: Option<&'a BreakdownLine<'a>>,
    /// The field under the input against breakdown (or that none was checked).
    pub check: &'a Check,
    /// Which of breakdown and pull-in comes first, in words.
    pub order: Option<&'a str>,
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
    if let Some(b) = o.breakdown {
        // V_b(λ) where it is on the chart's scale (a strong film's line would
        // squash the curve): up to 1.25× the largest voltage drawn.
        let top = 1.25
            * c.curve
                .iter()
                .map(|p| p.voltage_v)
                .fold(o.input_peak_v, f64::max);
        let line: Vec<(f64, f64)> = c
            .curve
            .iter()
            .map(|p| (b.voltage(p.stretch), p.stretch))
            .filter(|&(v, _)| v <= top)
            .collect();
        if !line.is_empty() {
            series.push(Series {
                label: format!("breakdown V_b(λ) = Eb·h(λ), Eb {}", v_per_um(b.field)),
                points: line,
                color: 3,
                style: Style::Dashed,
            });
        }
        if let Some(q) = b.point {
            series.push(Series {
                label: format!(
                    "field reaches Eb: λ {:.4} at {}",
                    q.stretch,
                    si(q.voltage_v, "V")
                ),
                points: vec![(q.voltage_v, q.stretch)],
                color: 3,
                style: Style::Points,
            });
        }
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
    if let Some(order) = o.order {
        page.text(format!("{order}."));
    }
    page.text(format!("{}.", o.check.message));
    for n in &o.check.notes {
        page.text(format!("Breakdown strength: {n}."));
    }
    page.chart(dir, "curve.svg", "static voltage–stretch curve", &chart)?;
    page.heading("Shape of the curve");
    let (header, rows) = shape_rows(c, o.breakdown);
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
    headline.push(match o.check.margin {
        Some(m) => format!("breakdown margin {:.0} %", 100.0 * m),
        None => "breakdown not checked".into(),
    });
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
