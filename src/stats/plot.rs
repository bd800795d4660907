//! Plots of a validation, each written as PNG and SVG: the aligned curves, Bland-Altman
//! (samples and breaths), the cosinor fits and the BARS fits with their 95 % bands.
//!
//! Text is rendered with the DejaVu Sans font shipped in `data/fonts/` (Bitstream Vera
//! licence, `data/fonts/DejaVu-LICENSE.txt`) and compiled into the binary, so no system font
//! is needed at run time.

use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../data/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the compiled-in font (once).
pub fn ensure_font() {
    REGISTER.call_once(|| {
        // The font is compiled in and known to parse; a failure would only lose text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mark {
    /// Solid line.
    Line,
    /// Dashed line.
    Dashed,
    /// Small filled circles.
    Points,
}

/// One series of a panel.
#[derive(Debug, Clone)]
pub struct Trace<'a> {
    /// Legend label.
    pub label: String,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates.
    pub y: &'a [f64],
    /// RGB colour.
    pub color: (u8, u8, u8),
    /// Drawing style.
    pub mark: Mark,
}

/// A horizontal reference line.
#[derive(Debug, Clone)]
pub struct HLine {
    /// Label in the legend.
    pub label: String,
    /// Ordinate.
    pub y: f64,
    /// RGB colour.
    pub color: (u8, u8, u8),
    /// Dashed when true.
    pub dashed: bool,
}

/// A shaded band between two curves.
#[derive(Debug, Clone)]
pub struct Band<'a> {
    /// Label in the legend.
    pub label: String,
    /// Abscissae.
    pub x: &'a [f64],
    /// Lower curve.
    pub lo: &'a [f64],
    /// Upper curve.
    pub hi: &'a [f64],
    /// RGB colour (drawn translucent).
    pub color: (u8, u8, u8),
}

/// One panel: axes, traces, reference lines, optional band.
#[derive(Debug, Clone)]
pub struct Panel<'a> {
    /// Title above the panel.
    pub title: String,
    /// Abscissa label.
    pub x_label: String,
    /// Ordinate label.
    pub y_label: String,
    /// Series.
    pub traces: Vec<Trace<'a>>,
    /// Horizontal lines.
    pub hlines: Vec<HLine>,
    /// Bands (drawn first).
    pub bands: Vec<Band<'a>>,
}

/// Blue used for the simulation.
pub const BLUE: (u8, u8, u8) = (31, 90, 180);
/// Red used for the spirometry.
pub const RED: (u8, u8, u8) = (200, 40, 40);
/// Dark grey for fits and reference lines.
pub const DARK: (u8, u8, u8) = (30, 30, 30);
/// Orange for highlighted fits.
pub const ORANGE: (u8, u8, u8) = (230, 120, 0);

/// The plotters colour of an RGB triple.
pub fn rgb(c: (u8, u8, u8)) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

fn range(panel: &Panel) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let mut see = |x: f64, y: f64| {
        if x.is_finite() && y.is_finite() {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    };
    for t in &panel.traces {
        for (x, y) in t.x.iter().zip(t.y) {
            see(*x, *y);
        }
    }
    for b in &panel.bands {
        for ((x, l), h) in b.x.iter().zip(b.lo).zip(b.hi) {
            see(*x, *l);
            see(*x, *h);
        }
    }
    for h in &panel.hlines {
        if h.y.is_finite() {
            y0 = y0.min(h.y);
            y1 = y1.max(h.y);
        }
    }
    if !x0.is_finite() {
        return ((0.0, 1.0), (0.0, 1.0));
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1.0;
    }
    let pad = 0.08 * (y1 - y0);
    ((x0, x1), (y0 - pad, y1 + 2.5 * pad))
}

/// A tick label as plotters writes it (1 to 5 decimals), with a value within `1e-9 x scale`
/// of zero written as zero: a tick computed as a sum of steps can land a rounding error
/// below zero, which would read "-0.0".
pub fn tick_label(v: f64, scale: f64) -> String {
    let v = if v.abs() <= 1e-9 * scale { 0.0 } else { v };
    plotters::data::float::FloatPrettyPrinter {
        allow_scientific: false,
        min_decimal: 1,
        max_decimal: 5,
    }
    .print(v)
}

/// Draws one panel into `area` (errors as text).
pub fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
) -> std::result::Result<(), String> {
    let ((x0, x1), (y0, y1)) = range(panel);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 26))
        .margin(14)
        .x_label_area_size(52)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| format!("{e:?}"))?;
    let (xs, ys) = (x0.abs().max(x1.abs()), y0.abs().max(y1.abs()));
    chart
        .configure_mesh()
        .x_label_formatter(&|v| tick_label(*v, xs))
        .y_label_formatter(&|v| tick_label(*v, ys))
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .label_style(("sans-serif", 18))
        .axis_desc_style(("sans-serif", 20))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()
        .map_err(|e| format!("{e:?}"))?;
    for b in &panel.bands {
        let mut pts: Vec<(f64, f64)> = b.x.iter().zip(b.hi).map(|(x, y)| (*x, *y)).collect();
        pts.extend(b.x.iter().zip(b.lo).rev().map(|(x, y)| (*x, *y)));
        let c = rgb(b.color);
        chart
            .draw_series(std::iter::once(Polygon::new(pts, c.mix(0.25).filled())))
            .map_err(|e| format!("{e:?}"))?
            .label(b.label.as_str())
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 6), (x + 24, y + 6)], c.mix(0.25).filled())
            });
    }
    for t in &panel.traces {
        let c = rgb(t.color);
        let pts: Vec<(f64, f64)> =
            t.x.iter()
                .zip(t.y)
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(|(x, y)| (*x, *y))
                .collect();
        let anno = match t.mark {
            Mark::Line => chart
                .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                .map_err(|e| format!("{e:?}"))?,
            Mark::Dashed => chart
                .draw_series(DashedLineSeries::new(pts, 10, 6, c.stroke_width(3)))
                .map_err(|e| format!("{e:?}"))?,
            Mark::Points => chart
                .draw_series(
                    pts.into_iter()
                        .map(|p| Circle::new(p, 3, c.mix(0.55).filled())),
                )
                .map_err(|e| format!("{e:?}"))?,
        };
        anno.label(t.label.as_str());
        if t.mark == Mark::Points {
            anno.legend(move |(x, y)| Circle::new((x + 12, y), 5, c.filled()));
        } else {
            anno.legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3))
            });
        }
    }
    for h in &panel.hlines {
        let c = rgb(h.color);
        let pts = vec![(x0, h.y), (x1, h.y)];
        let anno = if h.dashed {
            chart
                .draw_series(DashedLineSeries::new(pts, 12, 8, c.stroke_width(2)))
                .map_err(|e| format!("{e:?}"))?
        } else {
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                .map_err(|e| format!("{e:?}"))?
        };
        anno.label(h.label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 18))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(|e| format!("{e:?}"))?;
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    panels: &[Panel],
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(|e| format!("{e:?}"))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    for (a, p) in areas.iter().zip(panels) {
        draw_panel(a, p)?;
    }
    root.present().map_err(|e| format!("{e:?}"))
}

/// Writes `DIR/NAME.png` and `DIR/NAME.svg` with the panels stacked vertically.
pub fn write_figure(dir: &Path, name: &str, panels: &[Panel]) -> Result<()> {
    ensure_font();
    let h = 520 * panels.len().max(1) as u32;
    let png = dir.join(format!("{name}.png"));
    let svg = dir.join(format!("{name}.svg"));
    let fail = |p: &Path, e: String| Error::State(format!("{}: plotting failed: {e}", p.display()));
    draw_figure(
        BitMapBackend::new(&png, (1400, h)).into_drawing_area(),
        panels,
    )
    .map_err(|e| fail(&png, e))?;
    draw_figure(SVGBackend::new(&svg, (1400, h)).into_drawing_area(), panels)
        .map_err(|e| fail(&svg, e))?;
    Ok(())
}
