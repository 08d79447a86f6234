//! The static voltage–stretch curve for people and for files: its shape as a table,
//! and the whole curve as CSV.

use super::format::{si_column, table};
use crate::sim::static_curve::{Point, StaticCurve};
use std::fmt::Write;

/// Rows of the shape table spanning the curve (the pull-in is added to them).
pub const SHAPE_ROWS: usize = 10;

/// The curve's shape: [`SHAPE_ROWS`] points evenly spaced along it (first and last
/// included) and the pull-in in its place by stretch, marked; voltage and
/// capacitance with one SI prefix per column.
pub fn shape_table(c: &StaticCurve) -> String {
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
    table(
        &[
            &format!("voltage ({vu})"),
            "stretch",
            &format!("capacitance ({cu})"),
            "",
        ],
        &cells,
    )
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
