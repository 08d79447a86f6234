//! Line-and-scatter charts as SVG (plotters), shared by every report.

use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// One series of a chart.
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
    /// Colour index into the palette.
    pub color: usize,
    /// How to draw it.
    pub style: Style,
}

/// Drawing style of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Markers only (data).
    Points,
    /// Solid line (model).
    Line,
    /// Dashed line (model outside its data).
    Dashed,
    /// Filled band: the points trace its outline, lower edge forward and upper edge
    /// back ([`band`]).
    Band,
    /// Error bars: the points come in pairs (x, lo), (x, hi), each pair drawn as a
    /// vertical bar with caps ([`error_bars`]).
    ErrorBars,
}

/// The points of an [`Style::ErrorBars`] series: y ± σ at each x (a σ that is zero
/// or not finite draws nothing).
pub fn error_bars(points: impl IntoIterator<Item = (f64, f64, f64)>) -> Vec<(f64, f64)> {
    points
        .into_iter()
        .filter(|&(_, _, s)| s.is_finite() && s > 0.0)
        .flat_map(|(x, y, s)| [(x, y - s), (x, y + s)])
        .collect()
}

/// The outline of a band between `lo` and `hi` at `x` (a [`Style::Band`] series).
pub fn band(x: &[f64], lo: &[f64], hi: &[f64]) -> Vec<(f64, f64)> {
    let lower = x.iter().zip(lo).map(|(&x, &y)| (x, y));
    let upper = x.iter().zip(hi).rev().map(|(&x, &y)| (x, y));
    lower.chain(upper).collect()
}

/// A chart: title, axis labels, series, and whether x is logarithmic.
pub struct Chart {
    /// Title.
    pub title: String,
    /// X-axis label with unit.
    pub x_label: String,
    /// Y-axis label with unit.
    pub y_label: String,
    /// Series.
    pub series: Vec<Series>,
    /// Logarithmic x axis.
    pub log_x: bool,
}

/// The palette (Tableau 10); a colour index beyond it repeats it.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
];

fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// The colour and style of the `i`-th of many model curves on one chart (one per
/// parameter): a colour each, drawn dashed once the palette repeats, so that twice
/// as many curves as colours stay apart.
pub fn nth_line(i: usize) -> (usize, Style) {
    match i < PALETTE.len() {
        true => (i, Style::Line),
        false => (i, Style::Dashed),
    }
}

fn range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        return (lo / 1.2, hi * 1.2);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * lo.abs().max(1.0)
    };
    (lo - pad, hi + pad)
}

/// The label of a tick at `v` on a linear axis from `lo` to `hi`: as many decimals
/// as a tenth of the span needs (plotters' own labels stop at 5 decimals, so an axis
/// of 10⁻⁷ read "0.0" at every tick), in scientific notation when the axis' largest
/// magnitude is below 10⁻³ or at least 10⁵; "0" at zero.
fn tick_label(v: f64, lo: f64, hi: f64) -> String {
    let step = (hi - lo).abs() / 10.0;
    if !(v.is_finite() && step.is_finite() && step > 0.0) {
        return format!("{v}");
    }
    if v.abs() < 1e-9 * step {
        return "0".into();
    }
    let step_exp = step.log10().floor();
    let magnitude = lo.abs().max(hi.abs());
    if !(1e-3..1e5).contains(&magnitude) {
        // one mantissa precision for the whole axis
        let digits = (magnitude.log10().floor() - step_exp).max(0.0) as usize;
        format!("{v:.digits$e}")
    } else {
        let digits = (-step_exp).max(0.0) as usize;
        format!("{v:.digits$}")
    }
}

/// The label of a tick at `v` on a logarithmic axis: the shortest decimal that
/// reads it exactly ("0.01", "200", "1e+06" from 10⁶ on).
fn log_tick_label(v: f64) -> String {
    if !v.is_finite() || v <= 0.0 {
        return format!("{v}");
    }
    if (1e-4..1e6).contains(&v) {
        // ticks are m·10ᵏ: six significant digits hold them, trailing zeros dropped
        let s = format!("{v:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:e}")
    }
}

impl Chart {
    /// The plot corner holding the fewest points (upper left on ties), where the
    /// legend hides the least data.
    fn emptiest_corner(&self, x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
        let fx = |v: f64| {
            if self.log_x {
                (v.ln() - x.0.ln()) / (x.1.ln() - x.0.ln())
            } else {
                (v - x.0) / (x.1 - x.0)
            }
        };
        let fy = |v: f64| (v - y.0) / (y.1 - y.0);
        // Corner regions: the outer 40 % of each axis.
        let corners = [
            (SeriesLabelPosition::UpperLeft, false, true),
            (SeriesLabelPosition::UpperRight, true, true),
            (SeriesLabelPosition::LowerLeft, false, false),
            (SeriesLabelPosition::LowerRight, true, false),
        ];
        let count = |right: bool, upper: bool| {
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .filter(|p| {
                    let (u, v) = (fx(p.0), fy(p.1));
                    u.is_finite()
                        && v.is_finite()
                        && (if right { u > 0.6 } else { u < 0.4 })
                        && (if upper { v > 0.6 } else { v < 0.4 })
                })
                .count()
        };
        corners
            .into_iter()
            .min_by_key(|&(_, right, upper)| count(right, upper))
            .map(|(c, ..)| c)
            .unwrap_or(SeriesLabelPosition::UpperLeft)
    }

    /// Render to an SVG file (written atomically).
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        crate::io::write::atomic_write(path, self.svg(path)?.as_bytes())
    }

    /// Render to SVG text; `path` (where it goes) names the chart in an error.
    pub fn svg(&self, path: &Path) -> Result<String> {
        let mut svg = String::new();
        self.draw(&mut svg)
            .map_err(|e| Error::settings(format!("could not draw {}: {e}", path.display())))?;
        Ok(svg)
    }

    fn draw(&self, out: &mut String) -> std::result::Result<(), Box<dyn std::error::Error + '_>> {
        let root = SVGBackend::with_string(out, (900, 560)).into_drawing_area();
        root.fill(&WHITE)?;
        let all = || self.series.iter().flat_map(|s| s.points.iter());
        let (x0, x1) = range(all().map(|p| p.0), self.log_x);
        let (y0, y1) = range(all().map(|p| p.1), false);
        let legend_corner = self.emptiest_corner((x0, x1), (y0, y1));
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(80);
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(self.x_label.as_str())
                    .y_desc(self.y_label.as_str())
                    .y_label_formatter(&|v| tick_label(*v, y0, y1))
                    .x_label_formatter(&|v| match self.log_x {
                        // a log axis' ticks are decades and their multiples
                        true => log_tick_label(*v),
                        false => tick_label(*v, x0, x1),
                    })
                    .light_line_style(RGBColor(235, 235, 235))
                    .draw()?;
                for s in &self.series {
                    let c = color(s.color);
                    let pts = s
                        .points
                        .iter()
                        .copied()
                        .filter(|p| p.0.is_finite() && p.1.is_finite());
                    match s.style {
                        Style::Points => chart
                            .draw_series(pts.map(|p| Circle::new(p, 3, c.filled())))?
                            .label(s.label.as_str())
                            .legend(move |(x, y)| Circle::new((x + 10, y), 3, c.filled())),
                        Style::Line => chart
                            .draw_series(LineSeries::new(pts, c.stroke_width(2)))?
                            .label(s.label.as_str())
                            .legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                            }),
                        Style::Band => {
                            // The outline keeps a band visible where it is thinner
                            // than a pixel.
                            let outline: Vec<(f64, f64)> = pts.collect();
                            chart.draw_series(std::iter::once(PathElement::new(
                                outline.clone(),
                                c.stroke_width(1),
                            )))?;
                            chart
                                .draw_series(std::iter::once(Polygon::new(
                                    outline,
                                    c.mix(0.45).filled(),
                                )))?
                                .label(s.label.as_str())
                                .legend(move |(x, y)| {
                                    Rectangle::new(
                                        [(x, y - 4), (x + 20, y + 4)],
                                        c.mix(0.45).filled(),
                                    )
                                })
                        }
                        Style::ErrorBars => {
                            let pts: Vec<(f64, f64)> = pts.collect();
                            chart
                                .draw_series(pts.chunks_exact(2).map(|w| {
                                    ErrorBar::new_vertical(
                                        w[0].0,
                                        w[0].1,
                                        0.5 * (w[0].1 + w[1].1),
                                        w[1].1,
                                        c.stroke_width(1),
                                        6,
                                    )
                                }))?
                                .label(s.label.as_str())
                                .legend(move |(x, y)| {
                                    ErrorBar::new_vertical(
                                        x + 10,
                                        y - 5,
                                        y,
                                        y + 5,
                                        c.stroke_width(1),
                                        6,
                                    )
                                })
                        }
                        Style::Dashed => chart
                            .draw_series(DashedLineSeries::new(pts, 6, 4, c.stroke_width(2)))?
                            .label(s.label.as_str())
                            .legend(move |(x, y)| {
                                EmptyElement::at((x, y))
                                    + PathElement::new(vec![(0, 0), (7, 0)], c.stroke_width(2))
                                    + PathElement::new(vec![(12, 0), (20, 0)], c.stroke_width(2))
                            }),
                    };
                }
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .position(legend_corner)
                    .draw()?;
            }};
        }
        if self.log_x {
            body!(builder.build_cartesian_2d((x0..x1).log_scale(), y0..y1)?);
        } else {
            body!(builder.build_cartesian_2d(x0..x1, y0..y1)?);
        }
        root.present()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::tick_label;

    /// Neighbouring ticks read differently at every scale (an axis of 10⁻⁷ once
    /// read "0.0" at every tick).
    #[test]
    fn tick_labels_tell_neighbours_apart() {
        let labels = |lo: f64, hi: f64, ticks: &[f64]| -> Vec<String> {
            ticks.iter().map(|&v| tick_label(v, lo, hi)).collect()
        };
        assert_eq!(
            labels(0.0, 1e-7, &[0.0, 2e-8, 4e-8]),
            ["0", "2.0e-8", "4.0e-8"]
        );
        assert_eq!(labels(-0.5, 0.5, &[-0.4, 0.0, 0.1]), ["-0.4", "0", "0.1"]);
        assert_eq!(labels(0.0, 30.0, &[5.0, 10.0]), ["5", "10"]);
        assert_eq!(
            labels(0.0, 2e5, &[5e4, 1e5, 1.5e5]),
            ["5.0e4", "1.0e5", "1.5e5"]
        );
        assert_eq!(labels(1.0, 1.002, &[1.0005]), ["1.0005"]);
    }

    /// Log-axis ticks read as the decades and multiples they are.
    #[test]
    fn log_tick_labels_are_exact() {
        use super::log_tick_label;
        let got: Vec<String> = [0.01, 0.2, 1.0, 30.0, 1000.0, 1e6]
            .iter()
            .map(|&v| log_tick_label(v))
            .collect();
        assert_eq!(got, ["0.01", "0.2", "1", "30", "1000", "1e6"]);
    }
}
