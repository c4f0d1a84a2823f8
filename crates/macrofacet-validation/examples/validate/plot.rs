//! A small line-plot rasterizer for the validation report: panels with axes, "nice" ticks and
//! tick labels (5×7 bitmap font), coloured anti-aliased polylines (solid or dashed), markers
//! with error bars, shaded bands, horizontal reference lines and a legend with swatches.
//! Figures are grids of panels, encoded as 8-bit RGB PNG with the `png` crate.

// A small general-purpose module: not every style or legend position is used by every report.
#![allow(dead_code)]

use super::font::{glyph, GLYPH_H, GLYPH_W};
use std::io::BufWriter;
use std::path::Path;

pub type Color = [u8; 3];

/// Tableau-10 palette.
pub const BLUE: Color = [31, 119, 180];
pub const ORANGE: Color = [255, 127, 14];
pub const GREEN: Color = [44, 160, 44];
pub const RED: Color = [214, 39, 40];
pub const PURPLE: Color = [148, 103, 189];
pub const GRAY: Color = [127, 127, 127];
pub const BLACK: Color = [0, 0, 0];
pub const PALETTE: [Color; 4] = [BLUE, ORANGE, GREEN, PURPLE];

/// An RGB raster with float channels (for blending), origin top-left.
pub struct Canvas {
    pub w: usize,
    pub h: usize,
    px: Vec<[f32; 3]>,
}

impl Canvas {
    pub fn new(w: usize, h: usize) -> Canvas {
        Canvas { w, h, px: vec![[1.0; 3]; w * h] }
    }

    /// Blends `color` over pixel `(x, y)` with coverage `a` in `[0, 1]`.
    pub fn blend(&mut self, x: i64, y: i64, color: Color, a: f64) {
        if x < 0 || y < 0 || x >= self.w as i64 || y >= self.h as i64 || !(a > 0.0) {
            return;
        }
        let a = a.min(1.0) as f32;
        let p = &mut self.px[y as usize * self.w + x as usize];
        for c in 0..3 {
            p[c] = p[c] * (1.0 - a) + (color[c] as f32 / 255.0) * a;
        }
    }

    pub fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, color: Color, a: f64) {
        let (xa, xb) = (x0.min(x1).round() as i64, x0.max(x1).round() as i64);
        let (ya, yb) = (y0.min(y1).round() as i64, y0.max(y1).round() as i64);
        for y in ya..yb {
            for x in xa..xb {
                self.blend(x, y, color, a);
            }
        }
    }

    /// An anti-aliased segment of width `width` with round caps (coverage from the distance to
    /// the segment).
    pub fn line(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, width: f64, color: Color) {
        if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
            return;
        }
        let r = 0.5 * width;
        let (dx, dy) = (x1 - x0, y1 - y0);
        let len2 = dx * dx + dy * dy;
        let xa = (x0.min(x1) - r - 1.0).floor() as i64;
        let xb = (x0.max(x1) + r + 1.0).ceil() as i64;
        let ya = (y0.min(y1) - r - 1.0).floor() as i64;
        let yb = (y0.max(y1) + r + 1.0).ceil() as i64;
        for y in ya.max(0)..=yb.min(self.h as i64 - 1) {
            for x in xa.max(0)..=xb.min(self.w as i64 - 1) {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let t = if len2 > 0.0 { (((px - x0) * dx + (py - y0) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
                let (qx, qy) = (x0 + t * dx - px, y0 + t * dy - py);
                let dist = (qx * qx + qy * qy).sqrt();
                let cov = (r + 0.5 - dist).clamp(0.0, 1.0);
                if cov > 0.0 {
                    // Max-blend within one segment: repaint with the coverage difference only.
                    self.blend(x, y, color, cov);
                }
            }
        }
    }

    /// A polyline; `dash = Some((on, off))` in pixels makes it dashed.
    pub fn polyline(&mut self, pts: &[(f64, f64)], width: f64, color: Color, dash: Option<(f64, f64)>) {
        let mut phase = 0.0;
        for w in pts.windows(2) {
            let ((x0, y0), (x1, y1)) = (w[0], w[1]);
            match dash {
                None => self.line(x0, y0, x1, y1, width, color),
                Some((on, off)) => {
                    let len = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
                    if !(len > 0.0) || !len.is_finite() {
                        continue;
                    }
                    let mut s = 0.0;
                    while s < len {
                        let period = on + off;
                        let p = phase % period;
                        let seg = if p < on { (on - p).min(len - s) } else { (period - p).min(len - s) };
                        if p < on {
                            let (a, b) = (s / len, (s + seg) / len);
                            self.line(x0 + a * (x1 - x0), y0 + a * (y1 - y0), x0 + b * (x1 - x0), y0 + b * (y1 - y0), width, color);
                        }
                        s += seg;
                        phase += seg;
                    }
                }
            }
        }
    }

    /// A filled anti-aliased disc.
    pub fn disc(&mut self, cx: f64, cy: f64, r: f64, color: Color) {
        for y in (cy - r - 1.0).floor() as i64..=(cy + r + 1.0).ceil() as i64 {
            for x in (cx - r - 1.0).floor() as i64..=(cx + r + 1.0).ceil() as i64 {
                let d = ((x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2)).sqrt();
                self.blend(x, y, color, (r + 0.5 - d).clamp(0.0, 1.0));
            }
        }
    }

    /// Stamps the glyphs of `s` (5×7 font, `scale` screen pixels per font pixel); `place(k, c, r)`
    /// maps font pixel `(c, r)` of the `k`-th character to screen coordinates.
    fn glyphs(&mut self, s: &str, scale: usize, color: Color, place: impl Fn(i64, i64, i64) -> (i64, i64)) {
        for (k, ch) in s.chars().enumerate() {
            let rows = glyph(ch).unwrap_or(["#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####"]);
            for (r, row) in rows.iter().enumerate() {
                for (c, b) in row.bytes().enumerate() {
                    if b == b'#' {
                        for dy in 0..scale {
                            for dx in 0..scale {
                                let (px, py) = place(k as i64, (c * scale + dx) as i64, (r * scale + dy) as i64);
                                self.blend(px, py, color, 1.0);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Text in the 5×7 font, `scale` screen pixels per font pixel; `(x, y)` is the top-left
    /// corner. Returns the width drawn.
    pub fn text(&mut self, x: f64, y: f64, s: &str, scale: usize, color: Color) -> f64 {
        let (x, y) = (x.round() as i64, y.round() as i64);
        let advance = ((GLYPH_W + 1) * scale) as i64;
        self.glyphs(s, scale, color, |k, c, r| (x + k * advance + c, y + r));
        text_width(s, scale)
    }

    /// Text rotated by 90° counter-clockwise (for y-axis labels); `(x, y)` is the bottom-left
    /// corner of the rotated string.
    pub fn text_vertical(&mut self, x: f64, y: f64, s: &str, scale: usize, color: Color) {
        let (x, y) = (x.round() as i64, y.round() as i64);
        let advance = ((GLYPH_W + 1) * scale) as i64;
        // Glyph pixel (c, r) -> screen (x + r, y - c).
        self.glyphs(s, scale, color, |k, c, r| (x + r, y - k * advance - c));
    }

    pub fn save_png(&self, path: &Path) -> std::io::Result<()> {
        let file = std::fs::File::create(path)?;
        let mut enc = png::Encoder::new(BufWriter::new(file), self.w as u32, self.h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        let data: Vec<u8> = self.px.iter().flat_map(|p| p.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)).collect();
        writer.write_image_data(&data).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    }
}

pub fn text_width(s: &str, scale: usize) -> f64 {
    let n = s.chars().count();
    if n == 0 {
        0.0
    } else {
        ((GLYPH_W + 1) * scale * n - scale) as f64
    }
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug)]
pub enum Style {
    /// A polyline; `dash` = (on, off) pixels.
    Line { width: f64, dash: Option<(f64, f64)> },
    /// Discs of radius `r` (with vertical error bars if the series has them).
    Markers { r: f64 },
    /// A histogram drawn as a step line over bins centred on the points.
    Steps { width: f64 },
}

#[derive(Clone, Debug)]
pub struct Series {
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
    pub fn steps(label: &str, color: Color, points: Vec<(f64, f64)>) -> Series {
        Series { label: label.into(), color, style: Style::Steps { width: 1.6 }, points, err: None }
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
    BottomRight,
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
}

/// "Nice" tick positions covering `[a, b]` (either order), about `target` of them.
pub fn nice_ticks(a: f64, b: f64, target: usize) -> (Vec<f64>, f64) {
    let (lo, hi) = (a.min(b), a.max(b));
    let span = (hi - lo).max(1e-300);
    let raw = span / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw * 0.999).unwrap_or(10.0 * mag);
    let first = (lo / step - 1e-9).ceil();
    let mut ticks = Vec::new();
    let mut k = first;
    while k * step <= hi + 1e-9 * step {
        ticks.push(k * step);
        k += 1.0;
    }
    (ticks, step)
}

/// A tick label with as many decimals as the step needs.
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = (0..7)
        .find(|&d| {
            let s = step * 10f64.powi(d as i32);
            (s - s.round()).abs() < 1e-6 * s.max(1.0)
        })
        .unwrap_or(6);
    let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
    format!("{:.*}", decimals, v)
}

fn data_range(panel: &Panel, horizontal: bool) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in &panel.series {
        for (i, &(x, y)) in s.points.iter().enumerate() {
            let e = s.err.as_ref().map(|e| e[i]).unwrap_or(0.0);
            let (a, b) = if horizontal { (x, x) } else { (y - e, y + e) };
            if a.is_finite() && b.is_finite() {
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
    }
    for band in &panel.bands {
        for i in 0..band.x.len() {
            let vals = if horizontal { [band.x[i], band.x[i]] } else { [band.lo[i], band.hi[i]] };
            for v in vals {
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
    }
    if !horizontal {
        for &(y, _, _) in &panel.hlines {
            lo = lo.min(y);
            hi = hi.max(y);
        }
    }
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

const TICK_SCALE: usize = 2;
const TITLE_SCALE: usize = 2;
const LEGEND_SCALE: usize = 2;

/// Draws `panel` into the rectangle `(ox, oy, pw, ph)` of `canvas`.
pub fn draw_panel(canvas: &mut Canvas, panel: &Panel, ox: f64, oy: f64, pw: f64, ph: f64) {
    let (mr, mt, mb) = (16.0, 34.0, 58.0);
    let xr = panel.x.unwrap_or_else(|| data_range(panel, true));
    let yr = panel.y.unwrap_or_else(|| {
        let (lo, hi) = data_range(panel, false);
        let extra = panel.legend_room * (hi - lo);
        match panel.legend {
            LegendPos::TopLeft | LegendPos::TopRight => (lo, hi + extra),
            LegendPos::BottomLeft | LegendPos::BottomRight => (lo - extra, hi),
            LegendPos::None => (lo, hi),
        }
    });
    // Left margin: y label, the widest tick label, gaps.
    let (yt, ys) = nice_ticks(yr.0, yr.1, 5);
    let widest = yt.iter().map(|&t| text_width(&tick_label(t, ys), TICK_SCALE)).fold(0.0, f64::max);
    let ml = 6.0 + (GLYPH_H * TICK_SCALE) as f64 + 10.0 + widest + 10.0;
    let (x0, y0, x1, y1) = (ox + ml, oy + mt, ox + pw - mr, oy + ph - mb);
    let sx = |x: f64| x0 + (x - xr.0) / (xr.1 - xr.0) * (x1 - x0);
    let sy = |y: f64| y1 - (y - yr.0) / (yr.1 - yr.0) * (y1 - y0);
    // Title and axis labels.
    let tw = text_width(&panel.title, TITLE_SCALE);
    canvas.text(x0 + 0.5 * ((x1 - x0) - tw), oy + 8.0, &panel.title, TITLE_SCALE, BLACK);
    let lw = text_width(&panel.xlabel, TICK_SCALE);
    canvas.text(x0 + 0.5 * ((x1 - x0) - lw), y1 + 34.0, &panel.xlabel, TICK_SCALE, BLACK);
    let lh = text_width(&panel.ylabel, TICK_SCALE);
    canvas.text_vertical(ox + 6.0, y0 + 0.5 * ((y1 - y0) + lh), &panel.ylabel, TICK_SCALE, BLACK);
    // Grid and ticks.
    let (xt, xs) = nice_ticks(xr.0, xr.1, 6);
    let grid = [228, 228, 228];
    for &t in &xt {
        let x = sx(t);
        canvas.line(x, y0, x, y1, 1.0, grid);
        canvas.line(x, y1, x, y1 + 5.0, 1.2, BLACK);
        let s = tick_label(t, xs);
        let w = text_width(&s, TICK_SCALE);
        canvas.text(x - 0.5 * w, y1 + 9.0, &s, TICK_SCALE, BLACK);
    }
    for &t in &yt {
        let y = sy(t);
        canvas.line(x0, y, x1, y, 1.0, grid);
        canvas.line(x0 - 5.0, y, x0, y, 1.2, BLACK);
        let s = tick_label(t, ys);
        let w = text_width(&s, TICK_SCALE);
        canvas.text(x0 - 9.0 - w, y - (GLYPH_H * TICK_SCALE) as f64 * 0.5, &s, TICK_SCALE, BLACK);
    }
    // Clip everything below to the plot rectangle by drawing into a scratch canvas.
    let (cw, ch) = ((x1 - x0).ceil() as usize + 1, (y1 - y0).ceil() as usize + 1);
    let mut sub = Canvas::new(cw, ch);
    let tx = |x: f64| sx(x) - x0;
    let ty = |y: f64| sy(y) - y0;
    for band in &panel.bands {
        // Column fill between the two interpolated curves.
        for i in 0..band.x.len().saturating_sub(1) {
            let (xa, xb) = (tx(band.x[i]), tx(band.x[i + 1]));
            let (l, r) = (xa.min(xb), xa.max(xb));
            let mut px = l.floor() as i64;
            while (px as f64) < r {
                let c = px as f64 + 0.5;
                if c >= l && c <= r {
                    let f = if r > l { (c - xa) / (xb - xa) } else { 0.0 };
                    let lo = band.lo[i] + f * (band.lo[i + 1] - band.lo[i]);
                    let hi = band.hi[i] + f * (band.hi[i + 1] - band.hi[i]);
                    let (ya, yb) = (ty(hi), ty(lo));
                    if ya.is_finite() && yb.is_finite() {
                        for py in ya.min(yb).floor() as i64..=ya.max(yb).ceil() as i64 {
                            let cov = ((py as f64 + 1.0).min(ya.max(yb)) - (py as f64).max(ya.min(yb))).clamp(0.0, 1.0);
                            sub.blend(px, py, band.color, band.alpha * cov);
                        }
                    }
                }
                px += 1;
            }
        }
    }
    for &(y, color, dashed) in &panel.hlines {
        let yy = ty(y);
        sub.polyline(&[(0.0, yy), (cw as f64, yy)], 1.4, color, if dashed { Some((6.0, 4.0)) } else { None });
    }
    for s in &panel.series {
        let pts: Vec<(f64, f64)> = s.points.iter().map(|&(x, y)| (tx(x), ty(y))).collect();
        match s.style {
            Style::Line { width, dash } => {
                // Break the line at non-finite values.
                for run in pts.split(|p| !(p.0.is_finite() && p.1.is_finite())) {
                    sub.polyline(run, width, s.color, dash);
                }
            }
            Style::Markers { r } => {
                for (i, &(x, y)) in pts.iter().enumerate() {
                    if let Some(e) = &s.err {
                        let (ya, yb) = (ty(s.points[i].1 - e[i]), ty(s.points[i].1 + e[i]));
                        sub.line(x, ya, x, yb, 1.2, s.color);
                    }
                    if x.is_finite() && y.is_finite() {
                        sub.disc(x, y, r, s.color);
                    }
                }
            }
            Style::Steps { width } => {
                let mut path = Vec::new();
                for (i, &(x, y)) in s.points.iter().enumerate() {
                    let left = if i > 0 { 0.5 * (s.points[i - 1].0 + x) } else { x - 0.5 * (s.points.get(1).map(|p| p.0).unwrap_or(x + 1.0) - x) };
                    let right = if i + 1 < s.points.len() { 0.5 * (x + s.points[i + 1].0) } else { x + (x - left) };
                    path.push((tx(left), ty(y)));
                    path.push((tx(right), ty(y)));
                }
                sub.polyline(&path, width, s.color, None);
            }
        }
    }
    for yy in 0..ch {
        for xx in 0..cw {
            let p = sub.px[yy * cw + xx];
            let (gx, gy) = (x0.round() as i64 + xx as i64, y0.round() as i64 + yy as i64);
            if gx >= 0 && gy >= 0 && (gx as usize) < canvas.w && (gy as usize) < canvas.h {
                let q = &mut canvas.px[gy as usize * canvas.w + gx as usize];
                // Multiply: the scratch canvas is white where nothing was drawn.
                for c in 0..3 {
                    q[c] *= p[c];
                }
            }
        }
    }
    // Frame.
    canvas.polyline(&[(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)], 1.2, BLACK, None);
    // Legend.
    let entries: Vec<(&str, Color, Option<Style>, bool)> = panel
        .series
        .iter()
        .filter(|s| !s.label.is_empty())
        .map(|s| (s.label.as_str(), s.color, Some(s.style), false))
        .chain(panel.bands.iter().filter(|b| !b.label.is_empty()).map(|b| (b.label.as_str(), b.color, None, true)))
        .collect();
    if entries.is_empty() || panel.legend == LegendPos::None {
        return;
    }
    let row_h = (GLYPH_H * LEGEND_SCALE) as f64 + 6.0;
    let sw = 26.0;
    let width = entries.iter().map(|e| text_width(e.0, LEGEND_SCALE)).fold(0.0, f64::max) + sw + 18.0;
    let height = row_h * entries.len() as f64 + 8.0;
    let (lx, ly) = match panel.legend {
        LegendPos::TopRight => (x1 - width - 6.0, y0 + 6.0),
        LegendPos::TopLeft => (x0 + 6.0, y0 + 6.0),
        LegendPos::BottomLeft => (x0 + 6.0, y1 - height - 6.0),
        LegendPos::BottomRight | LegendPos::None => (x1 - width - 6.0, y1 - height - 6.0),
    };
    canvas.fill_rect(lx, ly, lx + width, ly + height, [255, 255, 255], 0.85);
    canvas.polyline(&[(lx, ly), (lx + width, ly), (lx + width, ly + height), (lx, ly + height), (lx, ly)], 1.0, GRAY, None);
    for (i, (label, color, style, band)) in entries.iter().enumerate() {
        let cy = ly + 4.0 + row_h * (i as f64 + 0.5);
        let sx0 = lx + 6.0;
        if *band {
            canvas.fill_rect(sx0, cy - 6.0, sx0 + sw, cy + 6.0, *color, 0.3);
        } else {
            match style.unwrap() {
                Style::Line { width, dash } => canvas.polyline(&[(sx0, cy), (sx0 + sw, cy)], width, *color, dash.map(|(a, b)| (a * 0.8, b * 0.8))),
                Style::Markers { r } => {
                    canvas.line(sx0 + 0.5 * sw, cy - 7.0, sx0 + 0.5 * sw, cy + 7.0, 1.2, *color);
                    canvas.disc(sx0 + 0.5 * sw, cy, r + 0.5, *color);
                }
                Style::Steps { width } => canvas.polyline(&[(sx0, cy + 4.0), (sx0 + 0.5 * sw, cy + 4.0), (sx0 + 0.5 * sw, cy - 4.0), (sx0 + sw, cy - 4.0)], width, *color, None),
            }
        }
        canvas.text(sx0 + sw + 8.0, cy - (GLYPH_H * LEGEND_SCALE) as f64 * 0.5, label, LEGEND_SCALE, BLACK);
    }
}

/// A grid of panels, row-major, `cols` wide; each panel `pw × ph` pixels.
pub struct Figure {
    pub cols: usize,
    pub pw: usize,
    pub ph: usize,
    pub panels: Vec<Panel>,
}

impl Figure {
    pub fn render(&self) -> Canvas {
        let rows = self.panels.len().div_ceil(self.cols).max(1);
        let mut c = Canvas::new(self.cols * self.pw, rows * self.ph);
        for (i, p) in self.panels.iter().enumerate() {
            let (col, row) = (i % self.cols, i / self.cols);
            draw_panel(&mut c, p, (col * self.pw) as f64, (row * self.ph) as f64, self.pw as f64, self.ph as f64);
        }
        c
    }

    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        self.render().save_png(path)
    }
}
