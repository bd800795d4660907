//! The figure of a fit (`<stem>_report.png` and its SVG twin), stacked panels 1400 px wide:
//! the fitted lung volume over time with the breath onsets; the volumes displaced by the
//! rib cage and by the abdomen since the first frame (when the per-breath report was made;
//! the first frame lies anywhere in a breath, so the curves start at zero rather than at the
//! first frame's distance from the rest state); three markers of the
//! midline recorded vs fitted (their ventral displacement); and a front view of the marker
//! set ([`front_view`]), each marker coloured by its RMS residual over the frames where it
//! was tracked, with a colour bar (viridis anchors, Smith & van der Walt 2015, matplotlib's
//! default map). Directions are those of the model's anatomical frame (x anterior, y
//! superior, z right), whatever frame the fit's markers are in ([`Fit::to_anatomy`]: under
//! skin fitting they are in the recording's frame); the front view shows the subject's
//! right on the viewer's left.

use super::Fit;
use super::clinical::BreathReport;
use crate::stats::plot::{
    BLUE, DARK, Mark, ORANGE, Panel, RED, Trace, draw_panel, ensure_font, rgb, tick_label,
};
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Width of the figure [px].
pub const WIDTH: u32 = 1400;
/// Height of each time-series panel [px].
pub const PANEL_HEIGHT: u32 = 520;
/// Height of the front view of the marker set [px].
pub const FRONT_HEIGHT: u32 = 760;

/// The figure's height for `time_panels` time-series panels and the front view.
pub fn figure_height(time_panels: usize) -> u32 {
    PANEL_HEIGHT * time_panels as u32 + FRONT_HEIGHT
}

/// Each marker's RMS distance [m] between the fitted model and the recorded point over the
/// frames where the point is tracked (NaN for a point never tracked).
pub fn marker_rms(fit: &Fit) -> Vec<f64> {
    let n = fit.fitted.markers.first().map_or(0, |m| m.len());
    let mut sum = vec![0.0; n];
    let mut count = vec![0usize; n];
    for (model, recorded) in fit.fitted.markers.iter().zip(&fit.recorded) {
        for (j, (p, q)) in model.iter().zip(recorded).enumerate() {
            if let Some(q) = q {
                sum[j] += (p - q).norm_squared();
                count[j] += 1;
            }
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &c)| {
            if c > 0 {
                (s / c as f64).sqrt()
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// The front view of the marker set at the first fitted frame: per marker, (-z, y) in the
/// model's anatomical frame [m] (lateral, the subject's right to the left; superior), read
/// through [`Fit::to_anatomy`] so that a fit whose markers are in the recording's frame
/// (skin fitting) is seen from the front too. Empty without fitted frames.
pub fn front_view(fit: &Fit) -> Vec<(f64, f64)> {
    fit.fitted.markers.first().map_or_else(Vec::new, |first| {
        first
            .iter()
            .map(|p| {
                let a = fit.to_anatomy.apply(p);
                (-a.z, a.y)
            })
            .collect()
    })
}

/// The ventral (anatomical x) component of the displacement `p - base` [m] of a marker
/// of `fit` (both in the fit's frame; [`Fit::to_anatomy`]).
fn ventral(fit: &Fit, p: &nalgebra::Point3<f64>, base: &nalgebra::Point3<f64>) -> f64 {
    (fit.to_anatomy.rotation * (p - base)).x
}

/// The fitted ventral displacement [mm] of marker `j` of `fit` from its first fitted frame,
/// at each of the fit's times (the marker panel's fitted lines); empty for a marker the fit
/// does not have.
pub fn ventral_displacement(fit: &Fit, j: usize) -> Vec<f64> {
    let Some(base) = fit.fitted.markers.first().and_then(|m| m.get(j)).copied() else {
        return Vec::new();
    };
    fit.fitted
        .markers
        .iter()
        .map(|m| ventral(fit, &m[j], &base) * 1e3)
        .collect()
}

/// Viridis at `u` in [0, 1], linear between five anchors of matplotlib's table.
pub fn viridis(u: f64) -> (u8, u8, u8) {
    const ANCHORS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = u * 4.0;
    let i = (s.floor() as usize).min(3);
    let w = s - i as f64;
    let (a, b) = (ANCHORS[i], ANCHORS[i + 1]);
    let mix = |x: f64, y: f64| (x + w * (y - x)).round() as u8;
    (mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// One owned series: label, abscissae, ordinates, colour, mark.
type Series = (String, Vec<f64>, Vec<f64>, (u8, u8, u8), Mark);

/// Owned series of one panel (the plot helpers borrow slices).
struct OwnedPanel {
    title: String,
    y_label: String,
    series: Vec<Series>,
}

impl OwnedPanel {
    fn panel(&self) -> Panel<'_> {
        Panel {
            title: self.title.clone(),
            x_label: "time [s]".into(),
            y_label: self.y_label.clone(),
            traces: self
                .series
                .iter()
                .map(|(label, x, y, color, mark)| Trace {
                    label: label.clone(),
                    x,
                    y,
                    color: *color,
                    mark: *mark,
                })
                .collect(),
            hlines: vec![],
            bands: vec![],
        }
    }
}

/// `v` less its first value.
fn since_first(v: &[f64]) -> Vec<f64> {
    let first = v.first().copied().unwrap_or_default();
    v.iter().map(|x| x - first).collect()
}

/// The time-series panels (module doc).
fn time_panels(fit: &Fit, report: Option<&BreathReport>) -> Vec<OwnedPanel> {
    let mut lung = vec![(
        "fitted model".to_string(),
        fit.times.clone(),
        fit.fitted.lung_volume.clone(),
        BLUE,
        Mark::Line,
    )];
    let mut title = format!(
        "Fitted lung volume ({}; cost {:.2} mm, {} evaluations)",
        fit.method.name(),
        fit.cost_m * 1e3,
        fit.evaluations
    );
    if let Some(r) = report {
        // Breath onsets as points on the curve.
        let (t, v): (Vec<f64>, Vec<f64>) = r
            .breaths
            .iter()
            .filter_map(|b| {
                let k = r.compartments.times.iter().position(|&t| t >= b.onset_s)?;
                Some((b.onset_s, r.compartments.lung[k]))
            })
            .unzip();
        lung.push(("breath onset".into(), t, v, RED, Mark::Points));
        let stats = r.stats();
        let get = |name: &str| stats.iter().find(|s| s.0 == name).map_or(f64::NAN, |s| s.1);
        title = format!(
            "Fitted lung volume: {} breath{}, VT {:.3} L, Ti/Ttot {:.2}, IE50 {:.2} (means); cost {:.2} mm",
            r.breaths.len(),
            if r.breaths.len() == 1 { "" } else { "s" },
            get("tidal_volume_l"),
            get("ti_ttot"),
            get("ie50"),
            fit.cost_m * 1e3
        );
    }
    let mut panels = vec![OwnedPanel {
        title,
        y_label: "lung volume [L]".into(),
        series: lung,
    }];
    if let Some(r) = report {
        let c = &r.compartments;
        let stats = r.stats();
        let get = |name: &str| stats.iter().find(|s| s.0 == name).map_or(f64::NAN, |s| s.1);
        panels.push(OwnedPanel {
            title: format!(
                "Compartments: rib-cage share {:.0} %, phase angle {:+.1} deg (+: abdomen leads)",
                100.0 * get("rib_cage_share"),
                get("phase_angle_deg")
            ),
            y_label: "displaced volume since the first frame [L]".into(),
            series: vec![
                (
                    "rib cage".into(),
                    c.times.clone(),
                    since_first(&c.rib_cage),
                    ORANGE,
                    Mark::Line,
                ),
                (
                    "abdomen".into(),
                    c.times.clone(),
                    since_first(&c.abdomen),
                    BLUE,
                    Mark::Line,
                ),
            ],
        });
    }
    let Some(first) = fit.fitted.markers.first().filter(|m| !m.is_empty()) else {
        return panels;
    };
    let (rows, cols) = fit.grid;
    let mut series = Vec::new();
    let colors = [BLUE, RED, DARK];
    let picks =
        [0, rows / 2, rows.saturating_sub(1)].map(|r| (r * cols + cols / 2).min(first.len() - 1));
    for (k, &j) in picks.iter().enumerate() {
        let base = first[j];
        let (mut tr, mut yr) = (Vec::new(), Vec::new());
        for (t, f) in fit.times.iter().zip(&fit.recorded) {
            if let Some(q) = f.get(j).copied().flatten() {
                tr.push(*t);
                yr.push(ventral(fit, &q, &base) * 1e3);
            }
        }
        let yf = ventral_displacement(fit, j);
        series.push((
            format!("marker[{}] recorded", j + 1),
            tr,
            yr,
            colors[k],
            Mark::Points,
        ));
        series.push((
            format!("marker[{}] fitted", j + 1),
            fit.times.clone(),
            yf,
            colors[k],
            Mark::Line,
        ));
    }
    panels.push(OwnedPanel {
        title: "Markers: ventral displacement, recorded vs fitted".into(),
        y_label: "ventral displacement [mm]".into(),
        series,
    });
    panels
}

/// The front view with its colour bar.
fn draw_front<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    fit: &Fit,
    rms: &[f64],
) -> std::result::Result<(), String> {
    let e = |x: &dyn std::fmt::Debug| format!("{x:?}");
    // Markers at their first fitted frame (the model's end-expiratory grid).
    let pts = front_view(fit);
    let (mut u0, mut u1, mut v0, mut v1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(u, v) in &pts {
        u0 = u0.min(u);
        u1 = u1.max(u);
        v0 = v0.min(v);
        v1 = v1.max(v);
    }
    if !(u0.is_finite() && v0.is_finite()) {
        return Ok(());
    }
    // Equal scales on both axes. The plot is as wide as the markers' extent needs at the
    // panel's height (at least a third of the figure, at most all but the colour bar), and
    // it and the colour bar are centred, so that the axes do not run on over empty space.
    let (w, h) = ((u1 - u0).max(1e-3), (v1 - v0).max(1e-3));
    let ph = FRONT_HEIGHT as f64 - 140.0;
    let (bar_width, frame) = (260.0, 140.0);
    let plot_width =
        (ph * w / h * 1.15 + frame).clamp(WIDTH as f64 / 3.0, WIDTH as f64 - bar_width);
    let left = ((WIDTH as f64 - plot_width - bar_width) / 2.0).floor() as u32;
    let (_, centred) = area.split_horizontally(left);
    let (plot, rest) = centred.split_horizontally(plot_width as u32);
    let (bar, _) = rest.split_horizontally(bar_width as u32);
    let pw = plot_width - frame;
    let scale = (w / pw).max(h / ph) * 1.15;
    let (uc, vc) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
    let (hu, hv) = (0.5 * scale * pw, 0.5 * scale * ph);
    // The colour bar spans the smallest to the largest residual.
    let finite = || rms.iter().copied().filter(|r| r.is_finite());
    let max_rms = finite().fold(0.0, f64::max);
    let low = finite().fold(f64::INFINITY, f64::min).min(max_rms);
    let span = if max_rms - low > 1e-9 {
        max_rms - low
    } else {
        1e-6
    };
    let mut chart = ChartBuilder::on(&plot)
        .caption(
            format!(
                "Front view of the marker set: RMS residual per marker ({:.2}-{:.2} mm)",
                low * 1e3,
                max_rms * 1e3
            ),
            ("sans-serif", 26),
        )
        .margin(14)
        .x_label_area_size(52)
        .y_label_area_size(80)
        .build_cartesian_2d((uc - hu)..(uc + hu), (vc - hv)..(vc + hv))
        .map_err(|x| e(&x))?;
    let (us, vs) = ((uc.abs() + hu), (vc.abs() + hv));
    chart
        .configure_mesh()
        .x_label_formatter(&|v| tick_label(*v, us))
        .y_label_formatter(&|v| tick_label(*v, vs))
        .x_desc("lateral -z [m] (subject's right on the left)")
        .y_desc("superior y [m]")
        .label_style(("sans-serif", 18))
        .axis_desc_style(("sans-serif", 20))
        .light_line_style(RGBColor(240, 240, 240))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(|x| e(&x))?;
    chart
        .draw_series(pts.iter().zip(rms).map(|(&p, &r)| {
            if r.is_finite() {
                Circle::new(p, 11, rgb(viridis((r - low) / span)).filled())
            } else {
                Circle::new(p, 11, RGBColor(150, 150, 150).stroke_width(2))
            }
        }))
        .map_err(|x| e(&x))?;
    // Colour bar: a vertical gradient with ticks in mm.
    let (_, bh) = bar.dim_in_pixel();
    let (x0, y0, y1) = (40i32, 80i32, bh as i32 - 90);
    let steps = 100;
    for k in 0..steps {
        // Each band reaches 1 px into the next: abutting rectangles leave hairline gaps
        // where an SVG renderer antialiases their shared edge.
        let ya = (y1 - (y1 - y0) * k / steps + 1).min(y1);
        let yb = y1 - (y1 - y0) * (k + 1) / steps;
        let c = rgb(viridis((k as f64 + 0.5) / steps as f64));
        bar.draw(&Rectangle::new([(x0, yb), (x0 + 40, ya)], c.filled()))
            .map_err(|x| e(&x))?;
    }
    bar.draw(&Rectangle::new(
        [(x0, y0), (x0 + 40, y1)],
        RGBColor(80, 80, 80).stroke_width(1),
    ))
    .map_err(|x| e(&x))?;
    for k in 0..=4 {
        let y = y1 - (y1 - y0) * k / 4;
        bar.draw(&Text::new(
            format!("{:.2}", (low + span * k as f64 / 4.0) * 1e3),
            (x0 + 50, y - 9),
            ("sans-serif", 18),
        ))
        .map_err(|x| e(&x))?;
    }
    bar.draw(&Text::new(
        "RMS residual [mm]",
        (10, y0 - 40),
        ("sans-serif", 20),
    ))
    .map_err(|x| e(&x))?;
    Ok(())
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    panels: &[Panel],
    fit: &Fit,
    rms: &[f64],
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(|e| format!("{e:?}"))?;
    let mut rest = root.clone();
    for p in panels {
        let (top, below) = rest.split_vertically(PANEL_HEIGHT);
        draw_panel(&top, p)?;
        rest = below;
    }
    draw_front(&rest, fit, rms)?;
    root.present().map_err(|e| format!("{e:?}"))
}

/// Writes `DIR/NAME.png` and `DIR/NAME.svg` (module doc); returns the PNG's path.
pub fn write_report_figure(
    dir: &Path,
    name: &str,
    fit: &Fit,
    report: Option<&BreathReport>,
) -> Result<std::path::PathBuf> {
    ensure_font();
    let owned = time_panels(fit, report);
    let panels: Vec<Panel> = owned.iter().map(|p| p.panel()).collect();
    let rms = marker_rms(fit);
    let size = (WIDTH, figure_height(panels.len()));
    let png = dir.join(format!("{name}.png"));
    let svg = dir.join(format!("{name}.svg"));
    let fail = |p: &Path, e: String| Error::State(format!("{}: plotting failed: {e}", p.display()));
    draw(
        BitMapBackend::new(&png, size).into_drawing_area(),
        &panels,
        fit,
        &rms,
    )
    .map_err(|e| fail(&png, e))?;
    draw(
        SVGBackend::new(&svg, size).into_drawing_area(),
        &panels,
        fit,
        &rms,
    )
    .map_err(|e| fail(&svg, e))?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_runs_from_purple_to_yellow() {
        assert_eq!(viridis(0.0), (68, 1, 84));
        assert_eq!(viridis(1.0), (253, 231, 37));
        assert_eq!(viridis(0.5), (33, 145, 140));
        assert_eq!(viridis(f64::NAN), (68, 1, 84));
        assert_eq!(viridis(2.0), (253, 231, 37));
    }

    #[test]
    fn a_tick_a_rounding_error_below_zero_reads_zero() {
        assert_eq!(tick_label(-2.7e-17, 0.2), "0.0");
        assert_eq!(tick_label(-0.05, 0.2), "-0.05");
        assert_eq!(tick_label(0.25, 1.0), "0.25");
    }

    #[test]
    fn displaced_volumes_start_at_zero() {
        assert_eq!(
            since_first(&[-0.16, -0.1, 0.2]),
            [0.0, -0.1 + 0.16, 0.2 + 0.16]
        );
        assert!(since_first(&[]).is_empty());
    }

    #[test]
    fn height_counts_the_panels() {
        assert_eq!(figure_height(3), 3 * 520 + 760);
    }
}
