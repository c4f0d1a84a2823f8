//! The report's figures: grids of line-plot panels drawn with `plotters` into SVG files. A panel
//! has a title, axis labels, ticks with a light grid, solid or dashed polylines, markers with
//! vertical error bars, shaded bands, horizontal reference lines and a legend.
//!
//! SVG keeps the text as text (the Markdown viewer renders it), so no font library is needed to
//! build or run the report.

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
// The colour trait (`mix`, `filled`, `stroke_width`); `Color` below names the report's colours.
use plotters::style::Color as _;
use std::path::Path;

pub type Color = RGBColor;

/// Tableau-10 palette.
pub const BLUE: Color = RGBColor(31, 119, 180);
pub const ORANGE: Color = RGBColor(255, 127, 14);
pub const GREEN: Color = RGBColor(44, 160, 44);
pub const RED: Color = RGBColor(214, 39, 40);
pub const PURPLE: Color = RGBColor(148, 103, 189);
pub const GRAY: Color = RGBColor(127, 127, 127);
pub const BLACK: Color = RGBColor(0, 0, 0);
pub const PALETTE: [Color; 4] = [BLUE, ORANGE, GREEN, PURPLE];

/// How a series is drawn.
#[derive(Clone, Copy, Debug)]
pub enum Style {
    /// A polyline of `width` pixels; `dash` = (on, off) pixels.
    Line { width: f64, dash: Option<(f64, f64)> },
    /// Discs of radius `r` pixels (with vertical error bars if the series has them).
    Markers { r: f64 },
}

#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text; an empty label keeps the series out of the legend.
    pub label: String,
    pub color: Color,
    pub style: Style,
    pub points: Vec<(f64, f64)>,
    /// Half-length of a vertical error bar per point.
    pub err: Option<Vec<f64>>,
}

impl Series {
    pub fn line(label: &str, color: Color, points: Vec<(f64, f64)>) -> Series {
        Series { label: label.into(), color, style: Style::Line { width: 2.0, dash: None }, points, err: None }
    }
    pub fn dashed(label: &str, color: Color, points: Vec<(f64, f64)>) -> Series {
        Series { label: label.into(), color, style: Style::Line { width: 2.0, dash: Some((7.0, 5.0)) }, points, err: None }
    }
    pub fn markers(label: &str, color: Color, points: Vec<(f64, f64)>, err: Option<Vec<f64>>) -> Series {
        Series { label: label.into(), color, style: Style::Markers { r: 2.6 }, points, err }
    }
}

/// A shaded region between `lo(x)` and `hi(x)`.
#[derive(Clone, Debug)]
pub struct Band {
    pub label: String,
    pub color: Color,
    pub alpha: f64,
    pub x: Vec<f64>,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LegendPos {
    TopRight,
    TopLeft,
    BottomLeft,
    None,
}

#[derive(Clone, Debug)]
pub struct Panel {
    pub title: String,
    pub xlabel: String,
    pub ylabel: String,
    /// Axis ranges; `x.0 > x.1` draws a reversed axis. `None` fits the data.
    pub x: Option<(f64, f64)>,
    pub y: Option<(f64, f64)>,
    pub series: Vec<Series>,
    pub bands: Vec<Band>,
    /// Horizontal reference lines `(y, color, dashed)`.
    pub hlines: Vec<(f64, Color, bool)>,
    pub legend: LegendPos,
    /// Extra room for the legend when the y-range is fitted: this fraction of the data span is
    /// added on the legend's side (top or bottom).
    pub legend_room: f64,
}

impl Panel {
    pub fn new(title: &str, xlabel: &str, ylabel: &str) -> Panel {
        Panel {
            title: title.into(),
            xlabel: xlabel.into(),
            ylabel: ylabel.into(),
            x: None,
            y: None,
            series: Vec::new(),
            bands: Vec::new(),
            hlines: Vec::new(),
            legend: LegendPos::TopRight,
            legend_room: 0.0,
        }
    }

    /// The finite range of the data along x (`horizontal`) or y, error bars, bands and
    /// reference lines included; a 6 % margin on y.
    fn data_range(&self, horizontal: bool) -> (f64, f64) {
        let mut values: Vec<f64> = Vec::new();
        for s in &self.series {
            for (i, &(x, y)) in s.points.iter().enumerate() {
                let e = s.err.as_ref().map_or(0.0, |e| e[i]);
                values.extend(if horizontal { [x, x] } else { [y - e, y + e] });
            }
        }
        for band in &self.bands {
            values.extend(if horizontal { band.x.clone() } else { band.lo.iter().chain(&band.hi).copied().collect() });
        }
        if !horizontal {
            values.extend(self.hlines.iter().map(|h| h.0));
        }
        let finite = values.into_iter().filter(|v| v.is_finite());
        let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
        if !(lo.is_finite() && hi.is_finite()) {
            return (0.0, 1.0);
        }
        if hi - lo < 1e-12 {
            let pad = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
            return (lo - pad, hi + pad);
        }
        let pad = if horizontal { 0.0 } else { 0.06 * (hi - lo) };
        (lo - pad, hi + pad)
    }

    /// The drawn ranges: the given ones, else the data's, with the legend room on its side.
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let x = self.x.unwrap_or_else(|| self.data_range(true));
        let y = self.y.unwrap_or_else(|| {
            let (lo, hi) = self.data_range(false);
            let extra = self.legend_room * (hi - lo);
            match self.legend {
                LegendPos::TopLeft | LegendPos::TopRight => (lo, hi + extra),
                LegendPos::BottomLeft => (lo - extra, hi),
                LegendPos::None => (lo, hi),
            }
        });
        (x, y)
    }
}

/// The parts of the polyline `points` inside the rectangle `x × y` (either order of the ends):
/// each segment is clipped (Liang–Barsky), and non-finite points break the line, since
/// `plotters` draws whatever coordinates it is given, outside the plot area too.
fn clip_polyline(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let (x0, x1, y0, y1) = (x.0.min(x.1), x.0.max(x.1), y.0.min(y.1), y.0.max(y.1));
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    for w in points.windows(2) {
        let ((ax, ay), (bx, by)) = (w[0], w[1]);
        let (dx, dy) = (bx - ax, by - ay);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut inside = [ax, ay, bx, by].iter().all(|v| v.is_finite());
        for (p, q) in [(-dx, ax - x0), (dx, x1 - ax), (-dy, ay - y0), (dy, y1 - ay)] {
            if !inside {
                break;
            }
            if p == 0.0 {
                inside = q >= 0.0;
            } else if p < 0.0 {
                t0 = t0.max(q / p);
            } else {
                t1 = t1.min(q / p);
            }
            inside &= t0 <= t1;
        }
        if !inside {
            runs.extend((!current.is_empty()).then(|| std::mem::take(&mut current)));
            continue;
        }
        let (a, b) = ((ax + t0 * dx, ay + t0 * dy), (ax + t1 * dx, ay + t1 * dy));
        if current.last() != Some(&a) {
            runs.extend((!current.is_empty()).then(|| std::mem::take(&mut current)));
            current.push(a);
        }
        current.push(b);
        if t1 < 1.0 {
            runs.push(std::mem::take(&mut current));
        }
    }
    runs.extend((!current.is_empty()).then_some(current));
    runs
}

/// A tick label without trailing zeros ("20", "0.25", not "20.0"); tick values are round
/// numbers, so six decimals are exact for every range the report draws.
fn tick_label(v: &f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Draws `panel` into `area`.
fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &Panel) -> DrawResult<DB> {
    let (xr, yr) = panel.ranges();
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 22))
        .margin(12)
        .margin_right(24)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)?;
    chart
        .configure_mesh()
        .x_desc(panel.xlabel.as_str())
        .y_desc(panel.ylabel.as_str())
        .x_labels(7)
        .y_labels(6)
        .x_label_formatter(&tick_label)
        .y_label_formatter(&tick_label)
        .max_light_lines(0)
        .bold_line_style(RGBColor(228, 228, 228))
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .draw()?;
    let clip = |points: &[(f64, f64)]| clip_polyline(points, xr, yr);
    let (ylo, yhi) = (yr.0.min(yr.1), yr.0.max(yr.1));
    for band in &panel.bands {
        // The band's outline: lo forward, hi backward, clamped to the y-range (the x-range is
        // the data's or contains it).
        let outline: Vec<(f64, f64)> = band.x.iter().zip(&band.lo).chain(band.x.iter().zip(&band.hi).rev()).map(|(&x, &v)| (x, v.clamp(ylo, yhi))).filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
        let fill = band.color.mix(band.alpha).filled();
        let drawn = chart.draw_series(std::iter::once(Polygon::new(outline, fill)))?;
        if !band.label.is_empty() {
            drawn.label(band.label.as_str()).legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 24, y + 6)], fill));
        }
    }
    for &(y, color, dashed) in &panel.hlines {
        let ends = [(xr.0, y), (xr.1, y)];
        let style = color.stroke_width(1);
        if dashed {
            chart.draw_series(DashedLineSeries::new(ends, 6, 4, style))?;
        } else {
            chart.draw_series(LineSeries::new(ends, style))?;
        }
    }
    for s in &panel.series {
        let color = s.color;
        match s.style {
            Style::Line { width, dash } => {
                let style = color.stroke_width(width.round().max(1.0) as u32);
                for run in clip(&s.points) {
                    match dash {
                        None => chart.draw_series(LineSeries::new(run, style))?,
                        Some((on, off)) => chart.draw_series(DashedLineSeries::new(run, on.round() as u32, off.round() as u32, style))?,
                    };
                }
                if !s.label.is_empty() {
                    // A legend-only series: an empty element list with the label and swatch.
                    let drawn = chart.draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?;
                    drawn.label(s.label.as_str());
                    match dash {
                        None => drawn.legend(move |(x, y)| PathElement::new([(x, y), (x + 24, y)], style)),
                        Some((on, off)) => drawn.legend(move |(x, y)| DashedPathElement::new([(x, y), (x + 24, y)], on.round() as u32, off.round() as u32, style)),
                    };
                }
            }
            Style::Markers { r } => {
                if let Some(err) = &s.err {
                    let bars = s.points.iter().zip(err).flat_map(|(&(x, y), &e)| clip(&[(x, y - e), (x, y + e)]));
                    chart.draw_series(bars.map(|bar| PathElement::new(bar, color.stroke_width(1))))?;
                }
                let inside = |&&(x, y): &&(f64, f64)| clip(&[(x, y), (x, y)]).len() == 1;
                let radius = r.round().max(1.0) as i32;
                let drawn = chart.draw_series(s.points.iter().filter(inside).map(|&p| Circle::new(p, radius, color.filled())))?;
                if !s.label.is_empty() {
                    // The swatch shows an error bar only when the series has them.
                    let bar = if s.err.is_some() { 7 } else { 0 };
                    drawn.label(s.label.as_str()).legend(move |(x, y)| {
                        EmptyElement::at((x + 12, y)) + PathElement::new([(0, -bar), (0, bar)], color.stroke_width(1)) + Circle::new((0, 0), radius + 1, color.filled())
                    });
                }
            }
        }
    }
    // A frame around the plot area.
    chart.draw_series(std::iter::once(PathElement::new([(xr.0, yr.0), (xr.1, yr.0), (xr.1, yr.1), (xr.0, yr.1), (xr.0, yr.0)], BLACK.stroke_width(1))))?;
    let position = match panel.legend {
        LegendPos::TopRight => SeriesLabelPosition::UpperRight,
        LegendPos::TopLeft => SeriesLabelPosition::UpperLeft,
        LegendPos::BottomLeft => SeriesLabelPosition::LowerLeft,
        LegendPos::None => return Ok(()),
    };
    let has_legend = !(panel.series.iter().all(|s| s.label.is_empty()) && panel.bands.iter().all(|b| b.label.is_empty()));
    if has_legend {
        chart
            .configure_series_labels()
            .position(position)
            .margin(8)
            .label_font(("sans-serif", 16))
            .background_style(WHITE.mix(0.85))
            .border_style(GRAY)
            .draw()?;
    }
    Ok(())
}

/// A grid of panels, row-major, `cols` wide; each panel `pw × ph` pixels.
pub struct Figure {
    pub cols: usize,
    pub pw: usize,
    pub ph: usize,
    pub panels: Vec<Panel>,
}

impl Figure {
    /// Writes the figure as an SVG file.
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let rows = self.panels.len().div_ceil(self.cols).max(1);
        let size = ((self.cols * self.pw) as u32, (rows * self.ph) as u32);
        let draw = || -> DrawResult<SVGBackend> {
            let root = SVGBackend::new(path, size).into_drawing_area();
            root.fill(&WHITE)?;
            for (area, panel) in root.split_evenly((rows, self.cols)).iter().zip(&self.panels) {
                draw_panel(area, panel)?;
            }
            root.present()
        };
        draw().map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))
    }
}

#[cfg(test)]
mod tests {
    use super::{clip_polyline, tick_label};

    #[test]
    fn tick_labels_drop_trailing_zeros() {
        assert_eq!(tick_label(&20.0), "20");
        assert_eq!(tick_label(&-0.0), "0");
        assert_eq!(tick_label(&0.0025), "0.0025");
        assert_eq!(tick_label(&(0.1 + 0.2)), "0.3");
    }

    #[test]
    fn clipping_keeps_inside_parts_and_breaks_at_gaps() {
        let unit = (0.0, 1.0);
        // Crossing the right edge: the inside half only.
        assert_eq!(clip_polyline(&[(0.5, 0.5), (1.5, 0.5)], unit, unit), vec![vec![(0.5, 0.5), (1.0, 0.5)]]);
        // Leaving and re-entering: two runs; a NaN breaks the line too.
        let runs = clip_polyline(&[(0.2, 0.5), (0.4, 2.0), (0.6, 0.5), (f64::NAN, 0.5), (0.7, 0.5), (0.8, 0.5)], unit, unit);
        assert_eq!(runs.len(), 3);
        assert_eq!(runs[0][0], (0.2, 0.5));
        assert_eq!(runs[2], vec![(0.7, 0.5), (0.8, 0.5)]);
        // A reversed range is the same rectangle.
        assert_eq!(clip_polyline(&[(0.5, 0.5), (1.5, 0.5)], (1.0, 0.0), unit).len(), 1);
    }
}
