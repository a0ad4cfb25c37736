//! Line charts as SVG: a figure is a grid of panels, each a set of curves on shared axes. The flight
//! plots (evaluation) and the learning curves (training) are both drawn with it; labelled points with
//! guide lines ([`draw_scatter`]) show a trade-off, one point per controller. Every figure, and
//! every other output file flapper writes, goes to disk through [`write_atomically`]: complete or
//! absent, never half written.

pub use flapper_files::write_atomically;

mod scatter;

pub use scatter::{Guide, LabelledPoint, Labels, PointGroup, Scatter, draw_scatter};

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

pub use plotters::style::RGBColor;

/// One curve of a panel.
pub struct Curve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
    pub dashed: bool,
}

/// A chart of curves sharing axes.
pub struct Panel<'a> {
    pub title: String,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub curves: Vec<Curve>,
    /// Same scale on both axes (for paths).
    pub equal_aspect: bool,
}

pub const COLORS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
];

/// Draws `panels` on a `grid` of (rows, columns) into an SVG file of `size` pixels; the error is a
/// message for the caller to put next to the path.
pub fn draw(path: &Path, size: (u32, u32), panels: &[Panel], grid: (usize, usize)) -> Result<(), String> {
    let error = |e: &dyn std::fmt::Display| e.to_string();
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(&e))?;
    for (area, panel) in root.split_evenly(grid).iter().zip(panels) {
        draw_panel(area, panel).map_err(|e| error(&e))?;
    }
    root.present().map_err(|e| error(&e))?;
    drop(root);
    write_atomically(path, svg.as_bytes()).map_err(|e| error(&e))
}

fn draw_panel(area: &DrawingArea<SVGBackend, Shift>, panel: &Panel) -> Result<(), Box<dyn std::error::Error>> {
    let points = panel.curves.iter().flat_map(|c| c.points.iter()).filter(|(x, y)| x.is_finite() && y.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in points {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let pad = |lo: f64, hi: f64| {
        let span = (hi - lo).max(1e-3);
        (lo - 0.05 * span, hi + 0.05 * span)
    };
    let ((mut x0, mut x1), (mut y0, mut y1)) = (pad(x0, x1), pad(y0, y1));
    if panel.equal_aspect {
        // Widen the shorter range so a metre is a metre both ways (plot areas are about 2:1 wide).
        let (dx, dy) = (x1 - x0, y1 - y0);
        let (px, py) = (area.dim_in_pixel().0 as f64 - 80.0, area.dim_in_pixel().1 as f64 - 70.0);
        let scale = (dx / px).max(dy / py);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        (x0, x1) = (cx - 0.5 * scale * px, cx + 0.5 * scale * px);
        (y0, y1) = (cy - 0.5 * scale * py, cy + 0.5 * scale * py);
    }
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart.configure_mesh().x_desc(panel.x_label).y_desc(panel.y_label).light_line_style(WHITE.mix(0.0)).draw()?;
    for curve in &panel.curves {
        let color = curve.color;
        let style =
            ShapeStyle { color: color.to_rgba(), filled: false, stroke_width: if curve.dashed { 1 } else { 2 } };
        let width = style.stroke_width;
        let series = if curve.dashed {
            chart.draw_series(DashedLineSeries::new(curve.points.iter().copied(), 6, 4, style))?
        } else {
            chart.draw_series(LineSeries::new(curve.points.iter().copied(), style))?
        };
        // A curve without a label stays out of the legend (one entry for several pieces of a kind).
        if !curve.label.is_empty() {
            series
                .label(curve.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(width)));
        }
    }
    if panel.curves.iter().filter(|c| !c.label.is_empty()).count() > 1 {
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    }
    Ok(())
}

/// Draws a dashed `reference` path and the `flown` paths in 3-D (x, y, z in metres) into an SVG file.
pub fn draw_paths_3d(
    path: &Path,
    title: &str,
    reference: &[(f64, f64, f64)],
    flown: &[Vec<(f64, f64, f64)>],
) -> Result<(), String> {
    let error = |e: &dyn std::fmt::Display| e.to_string();
    let all = reference
        .iter()
        .chain(flown.iter().flatten())
        .filter(|p| p.0.is_finite() && p.1.is_finite() && p.2.is_finite());
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in all {
        for (k, v) in [p.0, p.1, p.2].into_iter().enumerate() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    if !lo[0].is_finite() {
        (lo, hi) = ([0.0; 3], [1.0; 3]);
    }
    // Equal scale on the three axes: a cube around the paths.
    let half = (0..3).map(|k| hi[k] - lo[k]).fold(0.5, f64::max) / 2.0 * 1.05;
    let centre: Vec<f64> = (0..3).map(|k| 0.5 * (lo[k] + hi[k])).collect();
    let range = |k: usize| centre[k] - half..centre[k] + half;
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (900, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(10)
        .build_cartesian_3d(range(0), range(2), range(1))
        .map_err(|e| error(&e))?;
    chart.with_projection(|mut p| {
        p.pitch = 0.45;
        p.yaw = 0.6;
        p.scale = 0.8;
        p.into_matrix()
    });
    chart.configure_axes().draw().map_err(|e| error(&e))?;
    // Plotters' 3-D charts take (x, y, z) with y up: pass (x, altitude, lateral).
    let up = |p: &(f64, f64, f64)| (p.0, p.2, p.1);
    let dashed = ShapeStyle { color: BLACK.to_rgba(), filled: false, stroke_width: 1 };
    chart.draw_series(DashedLineSeries::new(reference.iter().map(up), 6, 4, dashed)).map_err(|e| error(&e))?;
    for (k, points) in flown.iter().enumerate() {
        let style = ShapeStyle { color: COLORS[(k + 1) % COLORS.len()].to_rgba(), filled: false, stroke_width: 2 };
        chart.draw_series(LineSeries::new(points.iter().map(up), style)).map_err(|e| error(&e))?;
    }
    drop(chart);
    root.present().map_err(|e| error(&e))?;
    drop(root);
    write_atomically(path, svg.as_bytes()).map_err(|e| error(&e))
}

/// The poles (crosses) and zeros (circles) of one transfer function in the complex plane.
pub struct PoleZeroMap {
    pub title: String,
    /// (real, imaginary) parts.
    pub poles: Vec<(f64, f64)>,
    pub zeros: Vec<(f64, f64)>,
}

/// Draws pole-zero maps side by side (the paper's Fig. 5), the imaginary axis marked, into an SVG file.
pub fn draw_pole_zero_maps(path: &Path, maps: &[PoleZeroMap]) -> Result<(), String> {
    let error = |e: &dyn std::fmt::Display| e.to_string();
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (420 * maps.len().max(1) as u32, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(&e))?;
    for (area, map) in root.split_evenly((1, maps.len().max(1))).iter().zip(maps) {
        draw_pole_zero(area, map).map_err(|e| error(&e))?;
    }
    root.present().map_err(|e| error(&e))?;
    drop(root);
    write_atomically(path, svg.as_bytes()).map_err(|e| error(&e))
}

fn draw_pole_zero(area: &DrawingArea<SVGBackend, Shift>, map: &PoleZeroMap) -> Result<(), Box<dyn std::error::Error>> {
    let all = map.poles.iter().chain(&map.zeros).filter(|(x, y)| x.is_finite() && y.is_finite());
    let reach = all.fold(1.0f64, |m, &(x, y)| m.max(x.abs()).max(y.abs())) * 1.2;
    let mut chart = ChartBuilder::on(area)
        .caption(&map.title, ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(-reach..reach, -reach..reach)?;
    chart.configure_mesh().x_desc("real (1/s)").y_desc("imaginary (rad/s)").light_line_style(WHITE.mix(0.0)).draw()?;
    chart.draw_series(LineSeries::new([(0.0, -reach), (0.0, reach)], BLACK.mix(0.4).stroke_width(1)))?;
    chart.draw_series(LineSeries::new([(-reach, 0.0), (reach, 0.0)], BLACK.mix(0.2).stroke_width(1)))?;
    let pole_color = COLORS[1];
    chart
        .draw_series(map.poles.iter().map(|&p| Cross::new(p, 7, pole_color.stroke_width(2))))?
        .label("poles")
        .legend(move |(x, y)| Cross::new((x + 10, y), 5, pole_color.stroke_width(2)));
    let zero_color = COLORS[0];
    chart
        .draw_series(map.zeros.iter().map(|&z| Circle::new(z, 6, zero_color.stroke_width(2))))?
        .label("zeros")
        .legend(move |(x, y)| Circle::new((x + 10, y), 5, zero_color.stroke_width(2)));
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    Ok(())
}

/// One point of a Bode plot: (frequency in Hz, magnitude in dB, phase in degrees).
pub type BodePoint = (f64, f64, f64);

/// One axis of a Bode plot: the model's response as a curve, the measured one as points.
pub struct BodeAxis {
    pub title: String,
    pub model: Vec<BodePoint>,
    pub measured: Vec<BodePoint>,
}

/// Which coordinates of a Bode point a panel draws.
type BodeView<'a> = &'a dyn Fn(&BodePoint) -> (f64, f64);

/// Draws one row per axis, magnitude left and phase right, on a logarithmic frequency axis.
pub fn draw_bode(path: &Path, axes: &[BodeAxis]) -> Result<(), String> {
    let error = |e: &dyn std::fmt::Display| e.to_string();
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1100, 330 * axes.len().max(1) as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(&e))?;
    let areas = root.split_evenly((axes.len().max(1), 2));
    for (row, axis) in axes.iter().enumerate() {
        let magnitude = |p: &BodePoint| (p.0, p.1);
        let phase = |p: &BodePoint| (p.0, p.2);
        draw_bode_panel(&areas[2 * row], &format!("{}: magnitude", axis.title), "magnitude (dB)", axis, &magnitude)
            .map_err(|e| error(&e))?;
        draw_bode_panel(&areas[2 * row + 1], &format!("{}: phase", axis.title), "phase (deg)", axis, &phase)
            .map_err(|e| error(&e))?;
    }
    root.present().map_err(|e| error(&e))?;
    drop(areas);
    drop(root);
    write_atomically(path, svg.as_bytes()).map_err(|e| error(&e))
}

fn draw_bode_panel(
    area: &DrawingArea<SVGBackend, Shift>,
    title: &str,
    y_label: &str,
    axis: &BodeAxis,
    pick: BodeView,
) -> Result<(), Box<dyn std::error::Error>> {
    let points: Vec<(f64, f64)> =
        axis.model.iter().chain(&axis.measured).map(pick).filter(|(f, v)| *f > 0.0 && v.is_finite()).collect();
    let (f0, f1) = points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
    let (v0, v1) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let (f0, f1) = if f0 < f1 { (f0, f1) } else { (0.01, 1.0) };
    let (v0, v1) = if v0 < v1 { (v0, v1) } else { (-1.0, 1.0) };
    let pad = 0.05 * (v1 - v0).max(1.0);
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d((f0..f1).log_scale(), (v0 - pad)..(v1 + pad))?;
    chart
        .configure_mesh()
        .x_desc("frequency (Hz)")
        .y_desc(y_label)
        .x_label_formatter(&|f| format!("{}", (f * 1000.0).round() / 1000.0))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    let model_color = COLORS[1];
    chart
        .draw_series(LineSeries::new(axis.model.iter().map(pick), model_color.stroke_width(2)))?
        .label("model")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], model_color.stroke_width(2)));
    let measured_color = COLORS[0];
    chart
        .draw_series(axis.measured.iter().map(|p| Circle::new(pick(p), 4, measured_color.stroke_width(2))))?
        .label("measured (flown records)")
        .legend(move |(x, y)| Circle::new((x + 10, y), 4, measured_color.stroke_width(2)));
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    Ok(())
}
