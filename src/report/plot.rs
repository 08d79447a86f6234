//! Line-and-scatter charts as SVG (plotters), shared by every report.

use crate::error::{Error, Result};
use plotters::coord::types::RangedCoordf64;
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
    /// Open markers (censored data: a value not reached, e.g. a specimen that
    /// survived).
    OpenPoints,
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
    /// Stems: each point a vertical line from y = 0 to it with a marker on top (a
    /// discrete spectrum); the y axis includes 0.
    Stems,
    /// A shaded span of x: from the smallest to the largest x of the points, the
    /// plot's whole height, light, behind every other series (the range the data
    /// support on a curve drawn beyond it); its y values are not used.
    Span,
    /// Points the axes must include, not drawn and not in the legend: (x, 0) to
    /// start an axis at 0, where its data's noise would otherwise fill the plot
    /// and read as peaks.
    Anchor,
}

/// The legend of a fit's confidence band ([`Style::Band`] around a fitted curve).
pub const BAND_LABEL: &str = "±1σ confidence band of the fit (parameter covariance)";

/// Opacity of a [`Style::Span`]'s fill: light enough that the curves over it read.
const SPAN_ALPHA: f64 = 0.12;

/// The `y_unit` of a Weibull probability-paper axis: y is ln(−ln(1 − F)), its ticks
/// sit at round shares F (0.1 % … 99.9 %) and read in % (IEEE Std 930-2004 §6.1).
pub const PROBABILITY_PAPER: &str = "probability paper (Weibull)";

/// The shares F at which a probability-paper axis has ticks.
const PAPER_TICKS: [f64; 12] = [
    0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 0.632, 0.9, 0.99,
];

/// The label of a probability-paper tick at y = ln(−ln(1 − F)): F in %, to the
/// digits a tick needs ("0.1 %", "63.2 %").
fn paper_label(y: f64) -> String {
    let p = 100.0 * -(-y.exp()).exp_m1();
    let s = format!("{p:.1}");
    format!("{} %", s.trim_end_matches(".0"))
}

/// An axis whose ticks are given: a probability-paper axis' round shares, a log
/// axis shorter than a decade (where plotters' own log ticks give none).
struct Ticked<R>(R, Vec<f64>);

/// Labelled ticks asked of plotters for a log axis longer than a decade (its
/// mesh's default label count).
const LOG_TICKS: usize = 10;

impl<R: Ranged<ValueType = f64>> Ranged for Ticked<R> {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;
    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        self.0.map(v, limit)
    }
    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, _: Hint) -> Vec<f64> {
        self.1.clone()
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.0.range()
    }
}

/// Ticks of a log axis from `lo` to `hi` (0 < lo < hi) shorter than a decade:
/// 1, 2, 5 × 10ᵏ inside it; when those are fewer than four, every m × 10ᵏ
/// (m = 1…9), then every half (m = 1, 1.5, …, 9.5); None for a longer axis
/// (plotters' own ticks serve it).
fn short_log_ticks(lo: f64, hi: f64) -> Option<Vec<f64>> {
    if !(lo > 0.0 && hi / lo < 10.0) {
        return None;
    }
    let k0 = lo.log10().floor() as i32;
    let within = |ms: &[f64]| -> Vec<f64> {
        (k0..=k0 + 1)
            .flat_map(|k| ms.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let units: Vec<f64> = (1..10).map(f64::from).collect();
    let halves: Vec<f64> = (2..20).map(|h| f64::from(h) / 2.0).collect();
    let mut sets = [within(&[1.0, 2.0, 5.0]), within(&units), within(&halves)].into_iter();
    let mut ticks = sets.next().unwrap_or_default();
    for finer in sets {
        if ticks.len() >= 4 {
            break;
        }
        ticks = finer;
    }
    Some(ticks)
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

/// The outline of a band between `lo` and `hi` at `x` (a [`Style::Band`] series):
/// its lower edge forward, then its upper edge back, each thinned as a [`line`].
pub fn band(x: &[f64], lo: &[f64], hi: &[f64]) -> Vec<(f64, f64)> {
    let lower = line(x.iter().zip(lo).map(|(&x, &y)| (x, y)));
    let upper = line(x.iter().zip(hi).map(|(&x, &y)| (x, y)));
    lower.into_iter().chain(upper.into_iter().rev()).collect()
}

/// A chart: title, axis labels, series, whether x is logarithmic, and the SI unit
/// of each axis.
///
/// An axis with a unit (`x_unit`, `y_unit`: values in that SI unit, e.g. `"Pa"`)
/// gets one SI prefix chosen from its range, the same for every tick, and its label
/// gains the prefixed unit: values up to 1.4·10⁵ Pa on "nominal stress" read
/// "nominal stress (kPa)" with ticks 0, 50, 100, … (never "140000.0 kPa").
/// An axis without one shows the values as they are.
pub struct Chart {
    /// Title.
    pub title: String,
    /// X-axis label: the quantity, and its unit when `x_unit` is `None`.
    pub x_label: String,
    /// Y-axis label: the quantity, and its unit when `y_unit` is `None`.
    pub y_label: String,
    /// Series.
    pub series: Vec<Series>,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// SI unit of the x values (prefix chosen by the chart), if any.
    pub x_unit: Option<String>,
    /// SI unit of the y values (prefix chosen by the chart), if any; or
    /// [`PROBABILITY_PAPER`]: y is ln(−ln(1 − F)), ticks at round F in %.
    pub y_unit: Option<String>,
}

/// The first colours: Tableau 10.
const TABLEAU: [RGBColor; 10] = [
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

/// OKLab (Ottosson 2020, <https://bottosson.github.io/posts/oklab/>) of an sRGB colour.
fn oklab(c: RGBColor) -> [f64; 3] {
    let lin = |v: u8| {
        let v = v as f64 / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let (r, g, b) = (lin(c.0), lin(c.1), lin(c.2));
    let l = (0.4122214708 * r + 0.5363325363 * g + 0.0514459929 * b).cbrt();
    let m = (0.2119034982 * r + 0.6806995451 * g + 0.1073969566 * b).cbrt();
    let s = (0.0883024619 * r + 0.2817188376 * g + 0.6299787005 * b).cbrt();
    [
        0.2104542553 * l + 0.7936177850 * m - 0.0040720468 * s,
        1.9779984951 * l - 2.4285922050 * m + 0.4505937099 * s,
        0.0259040371 * l + 0.7827717662 * m - 0.8086757660 * s,
    ]
}

/// The sRGB colour of OKLab (L, a, b), if it lies in the sRGB gamut.
fn srgb(lab: [f64; 3]) -> Option<RGBColor> {
    let [ll, a, b] = lab;
    let l = (ll + 0.3963377774 * a + 0.2158037573 * b).powi(3);
    let m = (ll - 0.1055613458 * a - 0.0638541728 * b).powi(3);
    let s = (ll - 0.0894841775 * a - 1.2914855480 * b).powi(3);
    let rgb = [
        4.0767416621 * l - 3.3077115913 * m + 0.2309699292 * s,
        -1.2684380046 * l + 2.6097574011 * m - 0.3413193965 * s,
        -0.0041960863 * l - 0.7034186147 * m + 1.7076147010 * s,
    ];
    if rgb.iter().any(|v| !(0.0..=1.0).contains(v)) {
        return None;
    }
    let gamma = |v: f64| {
        let v = if v <= 0.0031308 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (255.0 * v).round() as u8
    };
    Some(RGBColor(gamma(rgb[0]), gamma(rgb[1]), gamma(rgb[2])))
}

/// The palette: Tableau 10, then, one at a time, the colour of a fixed OKLab grid
/// (lightness 0.4–0.7, so every colour reads on white; chroma 0.06–0.14; hue every
/// 15°; in the sRGB gamut) farthest from all colours before it (greedy farthest-point
/// order, ties to the first in the grid). Deterministic; no colour repeats until the
/// grid is used up (243 colours), and the first 40 are at least 0.07 apart in OKLab
/// (a just noticeable difference is about 0.02).
fn palette() -> &'static [RGBColor] {
    static PALETTE: std::sync::OnceLock<Vec<RGBColor>> = std::sync::OnceLock::new();
    PALETTE.get_or_init(|| {
        let mut grid: Vec<(RGBColor, [f64; 3])> = Vec::new();
        for l in [0.4, 0.5, 0.6, 0.7] {
            for c in [0.06, 0.1, 0.14] {
                for k in 0..24 {
                    let h = std::f64::consts::TAU * k as f64 / 24.0;
                    if let Some(rgb) = srgb([l, c * h.cos(), c * h.sin()]) {
                        // the gamut test holds before rounding; the distances use
                        // the colour drawn
                        grid.push((rgb, oklab(rgb)));
                    }
                }
            }
        }
        let dist = |a: &[f64; 3], b: &[f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        // each grid colour's distance to the nearest colour chosen so far
        let mut nearest: Vec<f64> = grid
            .iter()
            .map(|(_, g)| {
                TABLEAU
                    .iter()
                    .map(|&t| dist(g, &oklab(t)))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let mut out = TABLEAU.to_vec();
        let mut taken = vec![false; grid.len()];
        while let Some(best) = (0..grid.len()).filter(|&k| !taken[k]).reduce(|a, b| {
            if nearest[b] > nearest[a] {
                b
            } else {
                a
            }
        }) {
            taken[best] = true;
            out.push(grid[best].0);
            for k in 0..grid.len() {
                nearest[k] = nearest[k].min(dist(&grid[k].1, &grid[best].1));
            }
        }
        out
    })
}

/// The `i`-th colour of the palette (see [`palette`]).
fn color(i: usize) -> RGBColor {
    let p = palette();
    p[i % p.len()]
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
/// reads it to six significant digits ("0.01", "200", "1e6" from 10⁶ on, "1e-7"
/// for the 1.0000000000000001e-7 a tick's arithmetic gives).
fn log_tick_label(v: f64) -> String {
    if !v.is_finite() || v <= 0.0 {
        return format!("{v}");
    }
    if (1e-4..1e6).contains(&v) {
        // ticks are m·10ᵏ: six significant digits hold them, trailing zeros dropped
        let s = format!("{v:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{v:.5e}");
        let (mantissa, exponent) = s.split_once('e').expect("an exponent");
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    }
}

/// Legend text size (px as drawn).
const LEGEND_FONT: u32 = 14;
/// Tick labels and axis descriptions (px as drawn): plotters' default, 12 given,
/// is drawn at 9.7 px ([`SVG_FONT`]), small once a 1000–1300 px chart shrinks to
/// the width of a page.
pub(crate) const AXIS_FONT: f64 = 13.0;
/// plotters' SVG backend writes `font-size` as the size it is given divided by
/// 1.24 (plotters-svg `svg.rs`): a size in px as drawn is given to it times this,
/// so that the legend is drawn at the size its column is measured for.
pub(crate) const SVG_FONT: f64 = 1.24;
/// Where a legend line's text starts in the legend column (px; the key before it),
/// and the room kept free right of the longest line.
const LEGEND_TEXT_X: u32 = 40;
const LEGEND_RIGHT_PX: u32 = 16;

/// The width (em) of `c` in sans-serif text, an upper estimate of the advance
/// widths of DejaVu Sans (the widest common sans-serif, and Chromium's default on
/// Linux; the SVG backend cannot measure text, and the browser picks the font):
/// narrow glyphs and space 0.42 (DejaVu: i 0.278, t 0.392, r 0.411, space 0.318),
/// lower case and digits 0.66 (n 0.634, digits 0.636), m, w and the widest
/// symbols 1.0 (m 0.974, W 0.989, % 0.950), anything else 0.84 (upper case:
/// D 0.770, O 0.787; ± and × 0.838; Greek letters about 0.6).
fn char_em(c: char) -> f64 {
    match c {
        'i' | 'l' | 'j' | 't' | 'f' | 'r' | '.' | ',' | ':' | ';' | '\'' | '|' | '!' | '('
        | ')' | '[' | ']' | ' ' => 0.42,
        'm' | 'w' | 'M' | 'W' | '%' | '@' | '—' | '…' | '≤' | '≥' | '∞' => 1.0,
        c if c.is_ascii_lowercase() || c.is_ascii_digit() => 0.66,
        _ => 0.84,
    }
}

/// The width (px) of `text` in the legend's font: [`char_em`] summed.
fn legend_text_px(text: &str) -> u32 {
    (text.chars().map(char_em).sum::<f64>() * LEGEND_FONT as f64).ceil() as u32
}
/// Legend labels wrap at this many characters.
const LEGEND_CHARS: usize = 40;
/// Height of one legend line (px).
const LEGEND_LINE_PX: u32 = 18;
/// The plot's own size (px); the legend column is added to the right of it.
const PLOT_SIZE: (u32, u32) = (900, 560);

/// An axis' SI prefix from its range `(lo, hi)` when it has a unit: the factor to
/// multiply values by and the label with the prefixed unit ("stress (kPa)").
fn axis_scale(label: &str, unit: Option<&str>, (lo, hi): (f64, f64)) -> (f64, String) {
    match unit {
        Some(u) if !u.is_empty() && u != "1" && u != PROBABILITY_PAPER => {
            let (f, p) = super::format::prefix(lo.abs().max(hi.abs()));
            (f, format!("{label} ({p}{u})"))
        }
        _ => (1.0, label.to_string()),
    }
}

/// A legend entry: the series and its label's lines.
type LegendEntry<'a> = (&'a Series, Vec<String>);

impl Chart {
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

    /// The legend's entries (series with a label, each label wrapped) and the size of
    /// the column holding them (zero wide when there are none).
    fn legend(&self) -> (Vec<LegendEntry<'_>>, (u32, u32)) {
        let entries: Vec<LegendEntry> = self
            .series
            .iter()
            .filter(|s| !s.label.trim().is_empty() && s.style != Style::Anchor)
            .map(|s| (s, super::format::wrap(&s.label, LEGEND_CHARS)))
            .collect();
        let text_px = entries
            .iter()
            .flat_map(|(_, l)| l.iter().map(|l| legend_text_px(l)))
            .max();
        let Some(text_px) = text_px else {
            return (entries, (0, 0));
        };
        let lines: usize = entries.iter().map(|(_, l)| l.len()).sum();
        let width = LEGEND_TEXT_X + text_px + LEGEND_RIGHT_PX;
        let height = LEGEND_LINE_PX * lines as u32 + 6 * entries.len() as u32;
        (entries, (width, height))
    }

    fn draw(&self, out: &mut String) -> std::result::Result<(), Box<dyn std::error::Error + '_>> {
        let (entries, (legend_w, legend_h)) = self.legend();
        // The legend sits in a column right of the plot, from the plot's top (below
        // the title); the picture grows downwards when the legend is taller.
        let top = 60;
        let size = (PLOT_SIZE.0 + legend_w, PLOT_SIZE.1.max(top + legend_h + 20));
        let root = SVGBackend::with_string(out, size).into_drawing_area();
        root.fill(&WHITE)?;
        let (plot_area, legend_area) = root.split_horizontally(PLOT_SIZE.0);
        let plot_area = plot_area.shrink((0, 0), PLOT_SIZE);
        let all = || self.series.iter().flat_map(|s| s.points.iter());
        let (x0, x1) = range(all().map(|p| p.0), self.log_x);
        // a span's y is not data; stems stand on 0
        let ys = self
            .series
            .iter()
            .filter(|s| s.style != Style::Span)
            .flat_map(|s| {
                let zero = (s.style == Style::Stems && !s.points.is_empty()).then_some(0.0);
                s.points.iter().map(|p| p.1).chain(zero)
            });
        let (y0, y1) = range(ys, false);
        let (fx, x_desc) = axis_scale(&self.x_label, self.x_unit.as_deref(), (x0, x1));
        let (fy, y_desc) = axis_scale(&self.y_label, self.y_unit.as_deref(), (y0, y1));
        let paper = self.y_unit.as_deref() == Some(PROBABILITY_PAPER);
        let mut builder = ChartBuilder::on(&plot_area);
        builder
            .caption(&self.title, ("sans-serif", 18.0 * SVG_FONT))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(80);
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(x_desc.as_str())
                    .y_desc(y_desc.as_str())
                    .y_label_formatter(&|v| match paper {
                        true => paper_label(*v),
                        false => tick_label(*v * fy, y0 * fy, y1 * fy),
                    })
                    .x_label_formatter(&|v| match self.log_x {
                        // a log axis' ticks are decades and their multiples
                        true => log_tick_label(*v * fx),
                        false => tick_label(*v * fx, x0 * fx, x1 * fx),
                    })
                    .label_style(("sans-serif", AXIS_FONT * SVG_FONT))
                    .axis_desc_style(("sans-serif", AXIS_FONT * SVG_FONT))
                    .light_line_style(RGBColor(235, 235, 235))
                    .draw()?;
                // spans first, behind the data
                let spans = self.series.iter().filter(|s| s.style == Style::Span);
                for s in spans.chain(self.series.iter().filter(|s| s.style != Style::Span)) {
                    let c = color(s.color);
                    let pts = drawn(s, size, |p| chart.backend_coord(p)).into_iter();
                    match s.style {
                        Style::Points => {
                            chart
                                .draw_series(pts.map(|p| Circle::new(p, MARKER_PX, c.filled())))?;
                        }
                        Style::OpenPoints => {
                            chart.draw_series(pts.map(|p| Circle::new(p, 4, c.stroke_width(2))))?;
                        }
                        Style::Line => {
                            chart.draw_series(LineSeries::new(pts, c.stroke_width(2)))?;
                        }
                        Style::Band => {
                            // The outline keeps a band visible where it is thinner
                            // than a pixel.
                            let outline: Vec<(f64, f64)> = pts.collect();
                            chart.draw_series(std::iter::once(PathElement::new(
                                outline.clone(),
                                c.stroke_width(1),
                            )))?;
                            chart.draw_series(std::iter::once(Polygon::new(
                                outline,
                                c.mix(0.3).filled(),
                            )))?;
                        }
                        Style::ErrorBars => {
                            let pts: Vec<(f64, f64)> = pts.collect();
                            chart.draw_series(pts.chunks_exact(2).map(|w| {
                                ErrorBar::new_vertical(
                                    w[0].0,
                                    w[0].1,
                                    0.5 * (w[0].1 + w[1].1),
                                    w[1].1,
                                    c.stroke_width(1),
                                    6,
                                )
                            }))?;
                        }
                        Style::Dashed => {
                            chart.draw_series(DashedLineSeries::new(
                                pts,
                                6,
                                4,
                                c.stroke_width(2),
                            ))?;
                        }
                        Style::Stems => {
                            let pts: Vec<(f64, f64)> = pts.collect();
                            chart.draw_series(pts.iter().map(|&(x, y)| {
                                PathElement::new(vec![(x, 0.0), (x, y)], c.stroke_width(2))
                            }))?;
                            chart
                                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
                        }
                        Style::Span => {
                            let xs: Vec<f64> = pts.map(|p| p.0).collect();
                            let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
                            let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                            if lo < hi {
                                chart.draw_series(std::iter::once(Rectangle::new(
                                    [(lo.max(x0), y0), (hi.min(x1), y1)],
                                    c.mix(SPAN_ALPHA).filled(),
                                )))?;
                            }
                        }
                        Style::Anchor => {}
                    }
                }
            }};
        }
        let ticks = || -> Vec<f64> {
            PAPER_TICKS
                .iter()
                .map(|&f| (-(-f).ln_1p()).ln())
                .filter(|y| (y0..=y1).contains(y))
                .collect()
        };
        let log = || -> LogCoord<f64> { (x0..x1).log_scale().into() };
        // plotters' own ticks of a longer log axis, each once: it can give the
        // end decade twice (two "10" labels on one spot, bench's multi-start chart)
        let long_log = || {
            let mut t = log().key_points(LOG_TICKS);
            t.sort_by(f64::total_cmp);
            t.dedup_by(|a, b| (*a / *b - 1.0).abs() < 1e-9);
            t
        };
        let short = self
            .log_x
            .then(|| short_log_ticks(x0, x1).unwrap_or_else(long_log));
        let paper_y = || Ticked::<RangedCoordf64>((y0..y1).into(), ticks());
        match (short, paper) {
            (Some(t), false) => body!(builder.build_cartesian_2d(Ticked(log(), t), y0..y1)?),
            (Some(t), true) => {
                body!(builder.build_cartesian_2d(Ticked(log(), t), paper_y())?)
            }
            (None, false) => body!(builder.build_cartesian_2d(x0..x1, y0..y1)?),
            (None, true) => body!(builder.build_cartesian_2d(x0..x1, paper_y())?),
        }
        let mut y = top as i32;
        for (s, lines) in &entries {
            let mid = y + LEGEND_LINE_PX as i32 / 2;
            legend_key(&legend_area, s.style, color(s.color), (8, mid))?;
            for (k, line) in lines.iter().enumerate() {
                legend_area.draw(&Text::new(
                    line.as_str(),
                    (
                        LEGEND_TEXT_X as i32,
                        y + 2 + (k as u32 * LEGEND_LINE_PX) as i32,
                    ),
                    ("sans-serif", f64::from(LEGEND_FONT) * SVG_FONT).into_font(),
                ))?;
            }
            y += (LEGEND_LINE_PX * lines.len() as u32 + 6) as i32;
        }
        root.present()?;
        Ok(())
    }
}

/// The points of `s` that are drawn: the finite ones, thinned to what shows at the
/// chart's resolution, in their order. `pixel` maps a point to the pixel it lands on.
///
/// A series of 10⁶ points draws as a few thousand, the same picture (a relaxation
/// curve of 10⁶ samples made a 130 MB SVG before):
/// - filled markers ([`Style::Points`]): those that still colour a pixel when
///   drawn in order ([`uncovered_discs`]): a marker whose every pixel an earlier
///   marker of the series, in the same colour, already covers changes nothing;
/// - open markers and stems ([`Style::OpenPoints`], [`Style::Stems`]): one per
///   pixel, the first that lands there ([`distinct_pixels`]);
/// - lines and band outlines ([`Style::Line`], [`Style::Dashed`], [`Style::Band`]):
///   in each run of points on one pixel column, its first, lowest, highest and last
///   point ([`m4`]: Jugel, Jerzak, Hackenbroich & Markl 2014, "M4: a
///   visualization-oriented time series data aggregation", PVLDB 7(10) 797–808),
///   which rasterize as the whole run does; every extreme is kept;
/// - error bars, spans and anchors as they are (they are few, or only their range
///   counts).
fn drawn(
    s: &Series,
    size: (u32, u32),
    pixel: impl Fn(&(f64, f64)) -> (i32, i32),
) -> Vec<(f64, f64)> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let keep = |pts: &[(f64, f64)], pick: &Thinning<'_>| {
        let pts: Vec<(f64, f64)> = pts.iter().copied().filter(finite).collect();
        let px: Vec<(i32, i32)> = pts.iter().map(&pixel).collect();
        pick(&px).into_iter().map(|i| pts[i]).collect::<Vec<_>>()
    };
    match s.style {
        Style::Points => keep(&s.points, &|px| uncovered_discs(px, size, MARKER_PX)),
        Style::OpenPoints | Style::Stems => keep(&s.points, &distinct_pixels),
        // a band's outline, its lower edge forward and its upper edge back, is a
        // line; where it turns, one column's run holds both edges' ends
        Style::Line | Style::Dashed | Style::Band => keep(&s.points, &m4),
        Style::ErrorBars | Style::Span | Style::Anchor => {
            s.points.iter().copied().filter(finite).collect()
        }
    }
}

/// A rule choosing which of a series' points (given as the pixels they land on) to
/// draw: their indices, in order.
type Thinning<'a> = dyn Fn(&[(i32, i32)]) -> Vec<usize> + 'a;

/// The radius (px) of a filled data marker ([`Style::Points`]).
const MARKER_PX: i32 = 3;

/// The indices (in order) of a set of the filled markers of radius `r` centred on
/// `px` that covers the pixels all of them cover: a pixel belongs to a marker when
/// its centre is within r + ½ of the marker's. Markers of one colour drawn opaque
/// make the same picture in any order, so the markers are tried first one per
/// cell of a lattice of spacing r + 1 (their discs tile the plane), then the rest,
/// and each is kept when it colours a pixel no marker kept before it has: a dense
/// cloud draws as about its area / (r + 1)² markers, not one per pixel. A marker
/// off the picture of `size` is kept.
fn uncovered_discs(px: &[(i32, i32)], size: (u32, u32), r: i32) -> Vec<usize> {
    let (w, h) = (size.0 as i32, size.1 as i32);
    let reach = (r as f64 + 0.5).powi(2);
    let disc: Vec<(i32, i32)> = (-r..=r)
        .flat_map(|dx| (-r..=r).map(move |dy| (dx, dy)))
        .filter(|&(dx, dy)| f64::from(dx * dx + dy * dy) <= reach)
        .collect();
    let mut covered = vec![false; (w.max(0) * h.max(0)) as usize];
    let at =
        |x: i32, y: i32| ((0..w).contains(&x) && (0..h).contains(&y)).then(|| (y * w + x) as usize);
    let cell = |(x, y): (i32, i32)| (x.div_euclid(r + 1), y.div_euclid(r + 1));
    let mut cells = std::collections::HashSet::new();
    let (first, rest): (Vec<usize>, Vec<usize>) =
        (0..px.len()).partition(|&i| cells.insert(cell(px[i])));
    let mut out = Vec::new();
    for i in first.into_iter().chain(rest) {
        let (x, y) = px[i];
        let mut new = false;
        for &(dx, dy) in &disc {
            match at(x + dx, y + dy) {
                Some(k) if !covered[k] => {
                    covered[k] = true;
                    new = true;
                }
                Some(_) => {}
                None => new = true,
            }
        }
        if new {
            out.push(i);
        }
    }
    out.sort_unstable();
    out
}

/// The indices of the first point on each pixel (in order).
fn distinct_pixels(px: &[(i32, i32)]) -> Vec<usize> {
    let mut seen = std::collections::HashSet::with_capacity(px.len().min(1 << 16));
    (0..px.len()).filter(|&i| seen.insert(px[i])).collect()
}

/// The indices (in order) of the points a polyline through `px` needs to rasterize
/// as the whole does: in each run of consecutive points on one pixel column, the
/// first, the lowest, the highest and the last (M4, Jugel et al. 2014). The
/// segments inside a run cover the column from its lowest to its highest point,
/// and so do first → extremes → last; the segments between runs are kept whole.
fn m4(px: &[(i32, i32)]) -> Vec<usize> {
    m4_runs(px.iter().map(|&(x, y)| (x, f64::from(y))))
}

/// [`m4`] over runs of equal keys: of each run of consecutive items with one key,
/// the indices (in order) of its first item, of its least and greatest value, and
/// of its last.
fn m4_runs<K: PartialEq>(items: impl Iterator<Item = (K, f64)>) -> Vec<usize> {
    /// A run: its key, its first index, (index, value) of its least and greatest,
    /// its last index.
    struct Run<K> {
        key: K,
        first: usize,
        lo: (usize, f64),
        hi: (usize, f64),
        last: usize,
    }
    let flush = |out: &mut Vec<usize>, r: Run<K>| {
        let mut picks = [r.first, r.lo.0.min(r.hi.0), r.lo.0.max(r.hi.0), r.last];
        picks.sort_unstable();
        for (k, &i) in picks.iter().enumerate() {
            if k == 0 || picks[k - 1] != i {
                out.push(i);
            }
        }
    };
    let mut out = Vec::new();
    let mut run: Option<Run<K>> = None;
    for (i, (key, v)) in items.enumerate() {
        match &mut run {
            Some(r) if r.key == key => {
                if v < r.lo.1 {
                    r.lo = (i, v);
                }
                if v > r.hi.1 {
                    r.hi = (i, v);
                }
                r.last = i;
            }
            _ => {
                if let Some(r) = run.take() {
                    flush(&mut out, r);
                }
                run = Some(Run {
                    key,
                    first: i,
                    lo: (i, v),
                    hi: (i, v),
                    last: i,
                });
            }
        }
    }
    if let Some(r) = run {
        flush(&mut out, r);
    }
    out
}

/// Bins of x (linear and logarithmic alike) over which [`line`] and [`band`] thin
/// a series before a chart is made of it: more than a chart has pixel columns
/// (900 px), so each column holds whole bins.
const LINE_BINS: f64 = 4096.0;

/// The points of a model curve (in order) a chart draws the same from, made
/// before the chart so that nothing of the curve's length is held: M4
/// ([`m4_runs`]) over runs of points in one of [`LINE_BINS`] bins of x on a linear
/// and on a log scale (a new run where either bin changes), over the points' own x
/// range; 10⁶ points become at most 4·2·4096. Every extreme of every bin is kept.
/// A chart's pixel column (wider than four bins) holds whole bins but at its two
/// edges, where a bin may straddle it: there a column can lose the extreme of its
/// share of that bin (under ¼ px wide), what a curve moves over ¼ px (a pixel on
/// a curve crossing the plot's height in 100 columns).
/// Data, noisy from point to point, are thinned where drawn ([`drawn`]), on the
/// pixels themselves. Points that are not finite are left out (a chart leaves them
/// out).
pub fn line<I: Iterator<Item = (f64, f64)> + Clone>(points: I) -> Vec<(f64, f64)> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let widen = |(a, b): (f64, f64), v: f64| (a.min(v), b.max(v));
    let empty = (f64::INFINITY, f64::NEG_INFINITY);
    // x's range on a linear and on a log scale (x > 0), in one pass
    let (lin, log) =
        points
            .clone()
            .filter(finite)
            .fold((empty, empty), |(lin, log), (x, _)| match x > 0.0 {
                true => (widen(lin, x), widen(log, x.ln())),
                false => (widen(lin, x), log),
            });
    let bin = |(lo, hi): (f64, f64), v: f64| match hi > lo {
        true => ((v - lo) / (hi - lo) * LINE_BINS).min(LINE_BINS - 1.0) as i64,
        false => 0,
    };
    let key = |x: f64| (bin(lin, x), if x > 0.0 { bin(log, x.ln()) } else { -1 });
    let picks = m4_runs(points.clone().filter(finite).map(|p| (key(p.0), p.1)));
    let mut picks = picks.into_iter().peekable();
    points
        .filter(finite)
        .enumerate()
        .filter_map(|(i, p)| match picks.peek() {
            Some(&k) if k == i => {
                picks.next();
                Some(p)
            }
            _ => None,
        })
        .collect()
}

/// Draw the legend key of a series of `style` in colour `c`, 24 px wide from `(x, y)`
/// (its vertical middle): a marker, a solid or a visibly dashed line (three dashes),
/// a filled and outlined box for a band, a capped bar for error bars.
fn legend_key<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    style: Style,
    c: RGBColor,
    (x, y): (i32, i32),
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let line = |a: i32, b: i32| PathElement::new(vec![(x + a, y), (x + b, y)], c.stroke_width(2));
    match style {
        Style::Points => area.draw(&Circle::new((x + 12, y), 4, c.filled())),
        Style::OpenPoints => area.draw(&Circle::new((x + 12, y), 4, c.stroke_width(2))),
        Style::Line => area.draw(&line(0, 24)),
        Style::Dashed => {
            area.draw(&line(0, 6))?;
            area.draw(&line(9, 15))?;
            area.draw(&line(18, 24))
        }
        Style::Band => {
            area.draw(&Rectangle::new(
                [(x, y - 6), (x + 24, y + 6)],
                c.mix(0.3).filled(),
            ))?;
            area.draw(&Rectangle::new(
                [(x, y - 6), (x + 24, y + 6)],
                c.stroke_width(1),
            ))
        }
        Style::ErrorBars => area.draw(&ErrorBar::new_vertical(
            x + 12,
            y - 7,
            y,
            y + 7,
            c.stroke_width(1),
            8,
        )),
        Style::Stems => {
            area.draw(&PathElement::new(
                vec![(x + 12, y + 7), (x + 12, y - 3)],
                c.stroke_width(2),
            ))?;
            area.draw(&Circle::new((x + 12, y - 3), 4, c.filled()))
        }
        Style::Span => area.draw(&Rectangle::new(
            [(x, y - 7), (x + 24, y + 7)],
            c.mix(SPAN_ALPHA).filled(),
        )),
        Style::Anchor => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reproducible draws below m (Knuth's 64-bit linear congruential generator,
    /// its high bits): test data without a seeded crate's stream.
    fn draws(seed: u64) -> impl FnMut(u64) -> u64 {
        let mut state = seed;
        move |m| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % m
        }
    }

    /// What a polyline through `px` colours in each pixel column it crosses: the
    /// lowest and highest pixel of each run of points on one column, and the
    /// columns in the order visited. M4 keeps all of it.
    fn columns(px: &[(i32, i32)]) -> Vec<(i32, i32, i32)> {
        let mut out: Vec<(i32, i32, i32)> = Vec::new();
        for &(x, y) in px {
            match out.last_mut() {
                Some(c) if c.0 == x => {
                    c.1 = c.1.min(y);
                    c.2 = c.2.max(y);
                }
                _ => out.push((x, y, y)),
            }
        }
        out
    }

    /// 10⁵ noisy points over 900 pixel columns thin to at most four a column run,
    /// keep every run's extremes, its first and last point and the order, and a
    /// line that moves back and forth (a band's edges, a hysteresis loop) too.
    #[test]
    fn m4_keeps_what_a_line_draws() {
        let mut draw = draws(12345);
        let mut noise = || draw(41) as i32 - 20;
        let forward: Vec<(i32, i32)> = (0..100_000)
            .map(|i| (i * 900 / 100_000, 300 + noise()))
            .collect();
        let looped: Vec<(i32, i32)> = (0..20_000)
            .map(|i| {
                let x = if i < 10_000 {
                    i / 20
                } else {
                    (20_000 - i) / 20
                };
                (x, 100 + (i / 10_000) * 50 + noise())
            })
            .collect();
        for px in [forward, looped] {
            let keep = m4(&px);
            assert!(keep.windows(2).all(|w| w[0] < w[1]), "in order");
            assert_eq!(keep[0], 0);
            assert_eq!(*keep.last().unwrap(), px.len() - 1);
            let kept: Vec<(i32, i32)> = keep.iter().map(|&i| px[i]).collect();
            assert_eq!(columns(&kept), columns(&px));
            assert!(kept.len() <= 4 * columns(&px).len());
        }
    }

    /// A line thinned in data space ([`line`]) draws as the whole: on a pixel grid
    /// of whole bins (1 024 columns over its own range, linear or logarithmic)
    /// exactly, noise and all; a model curve on a 900 px axis over a wider range
    /// (bins straddling columns) within a pixel, its steepest stretch (e^(−t) on a
    /// linear axis, 10 px a bin) included. 10⁵ points over five decades become at
    /// most 4·2·4096.
    #[test]
    fn a_line_thinned_before_its_chart_draws_the_same() {
        let mut draw = draws(7);
        let mut noise = || draw(1000) as f64 / 1000.0 - 0.5;
        let t = |i: usize| 0.01 * 10f64.powf(5.0 * i as f64 / 99_999.0);
        let noisy: Vec<(f64, f64)> = (0..100_000)
            .map(|i| (t(i), 3.0 + t(i).ln() + noise()))
            .collect();
        let smooth: Vec<(f64, f64)> = (0..100_000).map(|i| (t(i), (-t(i)).exp())).collect();
        let on = |pts: &[(f64, f64)], (lo, hi): (f64, f64), cols: f64, log: bool| {
            let col = |x: f64| match log {
                false => ((x - lo) / (hi - lo) * cols).min(cols - 1.0) as i32,
                true => ((x / lo).ln() / (hi / lo).ln() * cols).min(cols - 1.0) as i32,
            };
            pts.iter()
                .map(|&(x, y)| (col(x), (y * 400.0).floor() as i32))
                .collect::<Vec<_>>()
        };
        for (pts, range, cols, slack) in [
            (&noisy, (0.01, 1000.0), 1024.0, 0),
            (&smooth, (0.005, 2000.0), 900.0, 1),
        ] {
            let thin = line(pts.iter().copied());
            assert!(thin.len() <= 8 * 4096, "{} points", thin.len());
            for log in [false, true] {
                let (a, b) = (on(&thin, range, cols, log), on(pts, range, cols, log));
                let (a, b) = (columns(&a), columns(&b));
                assert_eq!(a.len(), b.len(), "log {log}: the columns visited");
                for (a, b) in a.iter().zip(&b) {
                    let off = (a.1 - b.1).abs().max((a.2 - b.2).abs());
                    assert!(
                        a.0 == b.0 && off <= slack,
                        "log {log}, column {}: {a:?} against {b:?}",
                        b.0
                    );
                }
            }
        }
    }

    /// Markers: the thinned set covers exactly the pixels all markers cover, with
    /// far fewer markers in a dense cloud; distinct pixels keep one point a pixel.
    #[test]
    fn thinned_markers_colour_the_same_pixels() {
        let mut draw = draws(99);
        let mut next = |m: u64| draw(m) as i32;
        let size = (300, 200);
        let px: Vec<(i32, i32)> = (0..50_000)
            .map(|_| (next(320) - 10, next(120) + 40))
            .collect();
        let r = MARKER_PX;
        let paint = |idx: &mut dyn Iterator<Item = usize>| {
            let mut on = std::collections::BTreeSet::new();
            for i in idx {
                let (x, y) = px[i];
                for dx in -r..=r {
                    for dy in -r..=r {
                        if f64::from(dx * dx + dy * dy) <= (r as f64 + 0.5).powi(2) {
                            on.insert((x + dx, y + dy));
                        }
                    }
                }
            }
            on
        };
        let keep = uncovered_discs(&px, size, r);
        assert!(keep.windows(2).all(|w| w[0] < w[1]), "in order");
        assert_eq!(paint(&mut keep.iter().copied()), paint(&mut (0..px.len())));
        // the cloud's 320 × 120 px: 2 400 lattice cells of 4 × 4 px, then markers
        // filling the gaps between their discs (6 727 in all), not 50 000
        assert!(keep.len() < 8_000, "{} markers", keep.len());
        let one = distinct_pixels(&[(1, 1), (2, 1), (1, 1), (2, 2), (2, 1)]);
        assert_eq!(one, vec![0, 1, 3]);
    }

    /// The first 40 colours are pairwise at least 0.07 apart in OKLab (about three
    /// just noticeable differences; the greedy order gives 0.0726 at 40), and the
    /// palette never repeats a colour.
    #[test]
    fn palette_does_not_repeat() {
        let labs: Vec<[f64; 3]> = (0..40).map(|i| oklab(color(i))).collect();
        for a in 0..labs.len() {
            for b in 0..a {
                let d = (0..3)
                    .map(|k| (labs[a][k] - labs[b][k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(d >= 0.07, "colours {b} and {a} are {d:.4} apart");
            }
        }
        let all = palette();
        assert!(all.len() > 200, "{} colours", all.len());
        for a in 0..all.len() {
            assert!(!all[..a].contains(&all[a]), "colour {a} repeats");
        }
        // the conversion round-trips inside the gamut (the grid is made with it; a
        // colour on the gamut's edge, like Tableau's orange, may fall out by rounding)
        for c in [TABLEAU[0], TABLEAU[8], RGBColor(120, 60, 90)] {
            assert_eq!(srgb(oklab(c)), Some(c));
        }
    }

    /// An axis in Pa up to 1.4·10⁵ reads in kPa with plain ticks.
    #[test]
    fn si_axis_reads_in_prefixed_unit() {
        let (f, label) = axis_scale("stress", Some("Pa"), (-7e3, 1.4e5));
        assert_eq!(label, "stress (kPa)");
        let ticks: Vec<String> = [0.0, 5e4, 1e5, 1.4e5]
            .iter()
            .map(|&v| tick_label(v * f, -7e3 * f, 1.4e5 * f))
            .collect();
        assert_eq!(ticks, ["0", "50", "100", "140"]);
        assert_eq!(axis_scale("λ", Some("1"), (0.0, 5.0)), (1.0, "λ".into()));
        assert_eq!(axis_scale("t (s)", None, (0.0, 5e5)), (1.0, "t (s)".into()));
    }

    /// A chart whose data fill the plot keeps its legend out of it: every legend
    /// text starts right of the plot (x ≥ 900 px), one per label line, with 1, 3 and
    /// 20 series and long labels; a dashed series' key is three dashes.
    #[test]
    fn legend_sits_outside_the_data() {
        for n in [1usize, 3, 20] {
            let series: Vec<Series> = (0..n)
                .map(|i| Series {
                    label: format!(
                        "series {i} with a rather long label that has to wrap somewhere"
                    ),
                    points: (0..50).map(|k| (k as f64, (k * (i + 1)) as f64)).collect(),
                    color: i,
                    style: if i % 2 == 0 {
                        Style::Line
                    } else {
                        Style::Dashed
                    },
                })
                .collect();
            let chart = Chart {
                title: "t".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                series,
                log_x: false,
                x_unit: None,
                y_unit: None,
            };
            let svg = chart.svg(Path::new("t.svg")).unwrap();
            let doc = scraper::Html::parse_document(&svg);
            let texts = scraper::Selector::parse("text").unwrap();
            let legend: Vec<f64> = doc
                .select(&texts)
                .filter(|t| {
                    let s: String = t.text().collect();
                    s.starts_with("series ") || s.contains("long label") || s.contains("wrap")
                })
                .map(|t| t.value().attr("x").unwrap().parse::<f64>().unwrap())
                .collect();
            assert_eq!(legend.len(), 2 * n, "{n} series: two lines each");
            assert!(legend.iter().all(|&x| x >= 900.0), "{n} series: {legend:?}");
        }
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (40, 20)).into_drawing_area();
            legend_key(&root, Style::Dashed, color(0), (8, 10)).unwrap();
            root.present().unwrap();
        }
        assert_eq!(svg.matches("<polyline").count(), 3, "{svg}");
    }

    /// Every legend line lies inside the picture: its start plus its width in
    /// DejaVu Sans (the widest common sans-serif, Chromium's default on Linux; the
    /// advance widths of the characters used, from the font's metrics) is within the
    /// SVG's width, for the power chart's long band label (once clipped at the right
    /// edge), wide capitals and symbols; and the width estimate is at least DejaVu's
    /// for every character of those labels.
    #[test]
    fn legend_lines_lie_within_the_picture() {
        // DejaVu Sans advance widths (em), from DejaVuSans.ttf's hmtx (2048 units/em)
        let dejavu = |c: char| -> f64 {
            match c {
                ' ' => 0.3179,
                'i' | 'l' | 'j' => 0.278,
                't' => 0.392,
                'r' => 0.411,
                'f' => 0.352,
                '.' | ',' | ':' => 0.3179,
                '(' | ')' => 0.390,
                '/' => 0.337,
                'm' => 0.974,
                'w' => 0.818,
                'M' => 0.863,
                'W' => 0.989,
                '%' => 0.950,
                '·' => 0.3179,
                '±' | '×' => 0.838,
                'σ' => 0.634,
                c if c.is_ascii_digit() => 0.636,
                c if c.is_ascii_lowercase() => 0.635,
                c if c.is_ascii_uppercase() => 0.787,
                _ => 0.838,
            }
        };
        let labels = [
            "total V·I: min/max per output interval (samples alias the ringing)",
            "MMMMMMMMMMMMMMMMMMMM WWWWWWWWWWWWWWWWWWW",
            "mmmmmmmmmmmmmmmmmmmm wwwwwwwwwwwwwwwwwwww",
            "±1σ × 100 % OOOOOOOO DDDDDDDD QQQQQQQQ",
        ];
        for label in labels {
            for c in label.chars() {
                assert!(
                    char_em(c) >= dejavu(c),
                    "'{c}': {} < {}",
                    char_em(c),
                    dejavu(c)
                );
            }
            let chart = Chart {
                title: "power".into(),
                x_label: "time (s)".into(),
                y_label: "power".into(),
                series: vec![
                    Series {
                        label: label.into(),
                        points: band(&[0.0, 1.0], &[0.0, 0.0], &[1.0, 2.0]),
                        color: 3,
                        style: Style::Band,
                    },
                    Series {
                        label: "leakage".into(),
                        points: vec![(0.0, 0.0), (1.0, 0.1)],
                        color: 4,
                        style: Style::Dashed,
                    },
                ],
                log_x: false,
                x_unit: None,
                y_unit: Some("W".into()),
            };
            let svg = chart.svg(Path::new("power.svg")).unwrap();
            let doc = scraper::Html::parse_document(&svg);
            let root = doc
                .select(&scraper::Selector::parse("svg").unwrap())
                .next()
                .unwrap();
            let width: f64 = root.value().attr("width").unwrap().parse().unwrap();
            let mut lines = 0;
            for t in doc.select(&scraper::Selector::parse("text").unwrap()) {
                let x: f64 = t.value().attr("x").unwrap().parse().unwrap();
                let text: String = t.text().collect::<String>().trim().to_string();
                if x < PLOT_SIZE.0 as f64 {
                    continue;
                }
                lines += 1;
                let w: f64 = text.chars().map(dejavu).sum::<f64>() * LEGEND_FONT as f64;
                assert!(x + w <= width, "'{text}' ends at {} > {width}", x + w);
            }
            assert!(lines >= 2, "{label}: {lines} legend lines");
        }
    }

    /// Stems stand on 0 (the y axis includes it), one line and one marker per
    /// point; a span is one filled rectangle drawn before the data (behind them),
    /// and its y values do not stretch the axis; an anchor draws nothing, has no
    /// legend entry, and puts its point inside the axis.
    #[test]
    fn stems_spans_and_anchors() {
        let (y0, y1) = {
            let chart = Chart {
                title: "t".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                series: vec![
                    Series {
                        label: "supported".into(),
                        points: vec![(2.0, 1e9), (3.0, -1e9)],
                        color: 8,
                        style: Style::Span,
                    },
                    Series {
                        label: "stems".into(),
                        points: vec![(1.0, 5.0), (2.0, 7.0), (4.0, 6.0)],
                        color: 0,
                        style: Style::Stems,
                    },
                ],
                log_x: false,
                x_unit: None,
                y_unit: None,
            };
            let svg = chart.svg(Path::new("s.svg")).unwrap();
            // three stems (a line each) and three markers, one span rectangle
            assert!(svg.matches("<polyline").count() >= 3, "{svg}");
            assert!(svg.matches("<circle").count() > 3, "{svg}");
            let rect = svg.find("opacity=\"0.12\"").expect("the span's fill");
            let stem = svg.find("<circle").unwrap();
            assert!(rect < stem, "the span is drawn behind the stems");
            // the y axis: from 0 (stems), not stretched to ±1e9 by the span
            let labels = texts(&svg);
            (
                labels.contains(&"0".to_string()),
                labels.iter().any(|l| l.contains("e8") || l.contains("e9")),
            )
        };
        assert!(y0, "the stems' axis shows 0");
        assert!(!y1, "the span's y values stretched the axis");
        let flat = |anchor: bool| {
            let mut series = vec![Series {
                label: "tan δ".into(),
                points: (0..20)
                    .map(|k| {
                        (
                            10.0 + k as f64,
                            0.05 * (1.0 + 0.007 * ((k % 3) as f64 - 1.0)),
                        )
                    })
                    .collect(),
                color: 0,
                style: Style::Line,
            }];
            if anchor {
                series.push(Series {
                    label: "from 0".into(),
                    points: vec![(10.0, 0.0)],
                    color: 0,
                    style: Style::Anchor,
                });
            }
            Chart {
                title: "t".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                series,
                log_x: false,
                x_unit: None,
                y_unit: None,
            }
            .svg(Path::new("a.svg"))
            .unwrap()
        };
        let (plain, anchored) = (texts(&flat(false)), texts(&flat(true)));
        let zero = "0".to_string();
        assert!(
            !plain.contains(&zero),
            "without an anchor the axis hugs the data"
        );
        assert!(anchored.contains(&zero), "the anchored axis starts at 0");
        assert!(
            !anchored.contains(&"from 0".to_string()),
            "an anchor has no legend entry"
        );
    }

    /// The texts of an SVG, trimmed.
    fn texts(svg: &str) -> Vec<String> {
        scraper::Html::parse_document(svg)
            .select(&scraper::Selector::parse("text").unwrap())
            .map(|t| t.text().collect::<String>().trim().to_string())
            .collect()
    }

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

    /// A probability-paper tick at y = ln(−ln(1 − F)) reads F in %, and a log axis
    /// shorter than a decade gets ticks (plotters gives it none): the coarsest set
    /// of m·10ᵏ with at least four inside, exact decimals.
    #[test]
    fn probability_paper_and_short_log_axes_have_ticks() {
        for (f, want) in [
            (0.001f64, "0.1 %"),
            (0.01, "1 %"),
            (0.632, "63.2 %"),
            (0.99, "99 %"),
        ] {
            assert_eq!(paper_label((-(-f).ln_1p()).ln()), want);
        }
        assert_eq!(
            short_log_ticks(1.1e7, 3.6e7).unwrap(),
            [1.5e7, 2e7, 2.5e7, 3e7, 3.5e7]
        );
        assert_eq!(
            short_log_ticks(1.0, 9.5).unwrap(),
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
        );
        assert_eq!(short_log_ticks(1.0, 100.0), None);
    }

    /// A log axis of a decade or more labels each tick once: plotters' own key
    /// points gave the end decade twice (two "10" labels on one spot, the bench's
    /// multi-start chart, found by the browser check of every page).
    #[test]
    fn a_long_log_axis_labels_each_tick_once() {
        for (lo, hi) in [(1.0, 10.0), (1.0, 10.2), (0.9, 11.0), (3e-3, 4e2)] {
            let chart = Chart {
                title: "t".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                series: vec![Series {
                    label: "s".into(),
                    points: vec![(lo, 1.0), (hi, 2.0)],
                    color: 0,
                    style: Style::Points,
                }],
                log_x: true,
                x_unit: None,
                y_unit: None,
            };
            let svg = chart.svg(Path::new("s.svg")).unwrap();
            let labels = texts(&svg);
            let mut seen = std::collections::BTreeSet::new();
            for l in &labels {
                assert!(
                    seen.insert(l.clone()),
                    "{lo}…{hi}: '{l}' twice in {labels:?}"
                );
            }
        }
    }

    /// Log-axis ticks read as the decades and multiples they are.
    #[test]
    fn log_tick_labels_are_exact() {
        use super::log_tick_label;
        // 1e-7 as a tick's arithmetic reaches it (10^-7 by powf); 2e-9 and 3e12
        // outside the plain-decimal range
        let got: Vec<String> = [
            0.01,
            0.2,
            1.0,
            30.0,
            1000.0,
            1e6,
            1.0000000000000001e-7,
            2e-9,
            3e12,
        ]
        .iter()
        .map(|&v| log_tick_label(v))
        .collect();
        assert_eq!(
            got,
            ["0.01", "0.2", "1", "30", "1000", "1e6", "1e-7", "2e-9", "3e12"]
        );
    }
}
