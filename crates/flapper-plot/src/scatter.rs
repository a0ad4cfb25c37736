//! Labelled points on one chart, in groups of a colour each, with straight guide lines (bars to meet,
//! reference values): a trade-off between two measurements, one point per controller.

use std::path::Path;

use plotters::prelude::*;

use crate::write_atomically;

/// One point and the name written beside it.
pub struct LabelledPoint {
    pub x: f64,
    pub y: f64,
    pub label: String,
}

/// Points of one kind (one colour, one legend entry).
pub struct PointGroup {
    pub legend: String,
    pub color: RGBColor,
    /// Filled discs labelled above, or rings labelled below (points of another provenance, which may
    /// sit on a filled one).
    pub filled: bool,
    /// Whether every point's label is drawn, or only where it clears the other points and labels.
    pub labels: Labels,
    pub points: Vec<LabelledPoint>,
}

/// Which of a group's labels a chart draws. Groups are labelled in their order, so an earlier
/// group's labels take their places first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Labels {
    /// Every one, overlapping others where no place around its point is free.
    Every,
    /// Only those with a free place around their point: many points close together (a cloud of
    /// experiments) keep their marks and lose their names, which a table beside the figure holds.
    WhereTheyFit,
}

/// A dashed line across the whole chart at one value.
pub enum Guide {
    /// At this y, along x.
    Horizontal { y: f64, label: String },
    /// At this x, along y.
    Vertical { x: f64, label: String },
}

/// A chart of labelled points.
pub struct Scatter<'a> {
    pub title: String,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub groups: Vec<PointGroup>,
    pub guides: Vec<Guide>,
}

/// The axes' ranges: from 0 to past the largest point or guide (points with a non-finite coordinate
/// are left out of the chart).
fn ranges(scatter: &Scatter) -> ((f64, f64), (f64, f64)) {
    let points = scatter.groups.iter().flat_map(|g| &g.points).filter(|p| p.x.is_finite() && p.y.is_finite());
    let (mut x1, mut y1) = points.fold((0.0f64, 0.0f64), |(x, y), p| (x.max(p.x), y.max(p.y)));
    for guide in &scatter.guides {
        match guide {
            Guide::Horizontal { y, .. } => y1 = y1.max(*y),
            Guide::Vertical { x, .. } => x1 = x1.max(*x),
        }
    }
    ((0.0, (x1 * 1.15).max(1e-3)), (0.0, (y1 * 1.1).max(1e-3)))
}

/// Draws `scatter` into an SVG file of `size` pixels; the error is a message for the caller to put
/// next to the path.
pub fn draw_scatter(path: &Path, size: (u32, u32), scatter: &Scatter) -> Result<(), String> {
    let error = |e: &dyn std::fmt::Display| e.to_string();
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(&e))?;
    draw_chart(&root, scatter).map_err(|e| error(&e))?;
    root.present().map_err(|e| error(&e))?;
    drop(root);
    write_atomically(path, svg.as_bytes()).map_err(|e| error(&e))
}

/// Font size of the labels (px), and the width a character of it takes, about.
const LABEL_PX: i32 = 12;
const CHAR_PX: f64 = 6.6;

/// A label's box on the canvas: left, top, width, height (px).
#[derive(Debug, Clone, Copy, PartialEq)]
struct LabelBox(i32, i32, i32, i32);

impl LabelBox {
    fn overlaps(&self, other: &LabelBox) -> bool {
        self.0 < other.0 + other.2
            && other.0 < self.0 + self.2
            && self.1 < other.1 + other.3
            && other.1 < self.1 + self.3
    }

    fn inside(&self, (x, y): (&std::ops::Range<i32>, &std::ops::Range<i32>)) -> bool {
        self.0 >= x.start && self.0 + self.2 <= x.end && self.1 >= y.start && self.1 + self.3 <= y.end
    }
}

/// The longest label a [`Labels::WhereTheyFit`] group shows (characters); a longer one is cut, with an
/// ellipsis, so that it fits beside its point more often and stays near it.
const OPTIONAL_LABEL_CHARS: usize = 36;

/// A point's label as drawn: whole for a group labelled in full, else cut to [`OPTIONAL_LABEL_CHARS`].
fn shown_label(labels: Labels, label: &str) -> String {
    match labels {
        Labels::WhereTheyFit if label.chars().count() > OPTIONAL_LABEL_CHARS => {
            let kept: String = label.chars().take(OPTIONAL_LABEL_CHARS - 1).collect();
            format!("{}…", kept.trim_end())
        }
        _ => label.to_string(),
    }
}

fn text_width_px(text: &str) -> i32 {
    (text.chars().count() as f64 * CHAR_PX).ceil() as i32
}

/// Where each point's label goes, as the offset of its top-left corner from the point (px): the
/// first of a few places around the point (on its right above or below, the side `below_first` says
/// first, then the same on its left, then further up or down on either side: an optional label only
/// the first four) whose box stays in `area` and clears every point, every label placed before it and
/// the boxes `taken`. A label that `must_show` and finds no such place takes the first place that
/// clears the labels and the other must-show points only (it may lie over a cloud of optional points),
/// and failing that its first place; any other label without a place is left out (`None`).
fn place_labels(
    points_px: &[(i32, i32)],
    widths_px: &[i32],
    below_first: &[bool],
    must_show: &[bool],
    mut taken: Vec<LabelBox>,
    area: (&std::ops::Range<i32>, &std::ops::Range<i32>),
) -> Vec<Option<(i32, i32)>> {
    let marks: Vec<LabelBox> = points_px.iter().map(|&(x, y)| LabelBox(x - 6, y - 6, 12, 12)).collect();
    let mut offsets = Vec::with_capacity(points_px.len());
    for (k, (&(x, y), &width)) in points_px.iter().zip(widths_px).enumerate() {
        let (above, below) = (-LABEL_PX - 2, 2);
        let (first, second) = if below_first[k] { (below, above) } else { (above, below) };
        let left = -8 - width;
        let (higher, lower) = (-2 * LABEL_PX - 4, LABEL_PX + 4);
        let (highest, lowest) = (-3 * LABEL_PX - 6, 2 * LABEL_PX + 6);
        let places = [
            (8, first),
            (8, second),
            (left, first),
            (left, second),
            (8, higher),
            (8, lower),
            (left, higher),
            (left, lower),
            (8, highest),
            (8, lowest),
        ];
        let fits = |&(dx, dy): &(i32, i32), every_mark: bool| {
            let label = LabelBox(x + dx, y + dy, width, LABEL_PX);
            let clear_of_marks = marks
                .iter()
                .enumerate()
                .all(|(j, mark)| j == k || !(every_mark || must_show[j]) || !label.overlaps(mark));
            label.inside(area) && clear_of_marks && taken.iter().all(|other| !label.overlaps(other))
        };
        // An optional label stays next to its point (the four nearest places), where it cannot be
        // read as another point's.
        let tried = if must_show[k] { &places[..] } else { &places[..4] };
        let mut chosen = tried.iter().copied().find(|place| fits(place, true));
        if must_show[k] {
            chosen = chosen.or_else(|| places.iter().copied().find(|place| fits(place, false))).or(Some(places[0]));
        }
        if let Some((dx, dy)) = chosen {
            taken.push(LabelBox(x + dx, y + dy, width, LABEL_PX));
        }
        offsets.push(chosen);
    }
    offsets
}

fn draw_chart(
    area: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    scatter: &Scatter,
) -> Result<(), Box<dyn std::error::Error>> {
    let ((x0, x1), (y0, y1)) = ranges(scatter);
    let mut chart = ChartBuilder::on(area)
        .caption(&scatter.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart.configure_mesh().x_desc(scatter.x_label).y_desc(scatter.y_label).light_line_style(WHITE.mix(0.0)).draw()?;
    let guide_style = ShapeStyle { color: BLACK.mix(0.55), filled: false, stroke_width: 1 };
    let mut guide_labels = Vec::new();
    for guide in &scatter.guides {
        // The guide's name inside the chart: right-aligned under the right end of a horizontal line,
        // beside the top of a vertical one.
        let (line, label, at, offset) = match guide {
            Guide::Horizontal { y, label } => ([(x0, *y), (x1, *y)], label, (x1, *y), (-8 - text_width_px(label), 3)),
            Guide::Vertical { x, label } => ([(*x, y0), (*x, y1)], label, (*x, y1), (4, 2)),
        };
        chart.draw_series(DashedLineSeries::new(line, 6, 4, guide_style))?;
        let font = ("sans-serif", LABEL_PX).into_font().color(&BLACK.mix(0.7));
        chart.draw_series(std::iter::once(EmptyElement::at(at) + Text::new(label.clone(), offset, font)))?;
        let (px, py) = chart.backend_coord(&at);
        guide_labels.push(LabelBox(px + offset.0, py + offset.1, text_width_px(label), LABEL_PX));
    }
    let shown: Vec<(&PointGroup, &LabelledPoint)> = scatter
        .groups
        .iter()
        .flat_map(|g| g.points.iter().map(move |p| (g, p)))
        .filter(|(_, p)| p.x.is_finite() && p.y.is_finite())
        .collect();
    let points_px: Vec<(i32, i32)> = shown.iter().map(|(_, p)| chart.backend_coord(&(p.x, p.y))).collect();
    let labels: Vec<String> = shown.iter().map(|(g, p)| shown_label(g.labels, &p.label)).collect();
    let widths: Vec<i32> = labels.iter().map(|label| text_width_px(label)).collect();
    let below_first: Vec<bool> = shown.iter().map(|(g, _)| !g.filled).collect();
    let must_show: Vec<bool> = shown.iter().map(|(g, _)| g.labels == Labels::Every).collect();
    let (x_px, y_px) = chart.plotting_area().get_pixel_range();
    let offsets = place_labels(&points_px, &widths, &below_first, &must_show, guide_labels, (&x_px, &y_px));
    // The marks and labels go down last group first, so that the first groups' marks (the controllers
    // measured here) lie on top of a cloud of later ones; the legend then lists the groups in order.
    let style = |group: &PointGroup| ShapeStyle { color: group.color.to_rgba(), filled: group.filled, stroke_width: 2 };
    for group in scatter.groups.iter().rev() {
        let (style, font) = (style(group), ("sans-serif", LABEL_PX).into_font().color(&group.color));
        let mine = shown.iter().zip(labels.iter().zip(&offsets)).filter(|((g, _), _)| std::ptr::eq(*g, group));
        chart.draw_series(mine.map(|((_, p), (label, &offset))| {
            let (label, offset) = match offset {
                Some(offset) => (label.clone(), offset),
                None => (String::new(), (0, 0)),
            };
            EmptyElement::at((p.x, p.y)) + Circle::new((0, 0), 5, style) + Text::new(label, offset, font.clone())
        }))?;
    }
    for group in &scatter.groups {
        let style = style(group);
        let nothing: Vec<Circle<(f64, f64), i32>> = Vec::new();
        chart
            .draw_series(nothing)?
            .label(group.legend.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, style));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_axes_start_at_zero_and_hold_every_point_and_guide() {
        let point = |x, y| LabelledPoint { x, y, label: String::new() };
        let scatter = Scatter {
            title: String::new(),
            x_label: "",
            y_label: "",
            groups: vec![PointGroup {
                legend: String::new(),
                color: crate::COLORS[0],
                filled: true,
                labels: Labels::Every,
                points: vec![point(0.25, 5.0), point(f64::NAN, 99.0), point(1.2, 1.0)],
            }],
            guides: vec![
                Guide::Horizontal { y: 6.0, label: String::new() },
                Guide::Vertical { x: 0.3, label: String::new() },
            ],
        };
        let ((x0, x1), (y0, y1)) = ranges(&scatter);
        assert_eq!((x0, y0), (0.0, 0.0));
        assert!((x1 - 1.2 * 1.15).abs() < 1e-12, "{x1}");
        assert!((y1 - 6.0 * 1.1).abs() < 1e-12, "the guide above every point sets the top, NaN points none: {y1}");
    }

    #[test]
    fn labels_move_aside_from_each_other_and_from_what_is_taken() {
        let area = (&(0..1000), &(0..700));
        // Two points close together: the second label leaves the first's place.
        let both = [true, true];
        let offsets = place_labels(&[(100, 300), (110, 305)], &[120, 120], &[false, false], &both, Vec::new(), area);
        assert_eq!(offsets[0], Some((8, -LABEL_PX - 2)));
        let first = LabelBox(108, 300 - LABEL_PX - 2, 120, LABEL_PX);
        let (dx, dy) = offsets[1].expect("a free place");
        let second = LabelBox(110 + dx, 305 + dy, 120, LABEL_PX);
        assert!(!first.overlaps(&second), "{offsets:?}");
        // A ring's label goes below first, unless a guide's label is there.
        assert_eq!(place_labels(&[(500, 300)], &[80], &[true], &[true], Vec::new(), area), [Some((8, 2))]);
        let guide = LabelBox(480, 300, 200, LABEL_PX);
        assert_eq!(place_labels(&[(500, 300)], &[80], &[true], &[true], vec![guide], area), [Some((8, -LABEL_PX - 2))]);
        // At the right edge the label goes to the left of its point.
        assert_eq!(
            place_labels(&[(990, 300)], &[80], &[false], &[true], Vec::new(), area),
            [Some((-88, -LABEL_PX - 2))]
        );
    }

    #[test]
    fn a_long_optional_label_is_cut_and_a_full_one_kept() {
        let long = "seed 1, s5h1esd1 1000 then 300 iterations with the energy kernel 60 W";
        let cut = shown_label(Labels::WhereTheyFit, long);
        assert!(cut.chars().count() <= OPTIONAL_LABEL_CHARS, "{cut}");
        assert!(cut.ends_with('…') && long.starts_with(cut.trim_end_matches('…')), "{cut}");
        assert_eq!(shown_label(Labels::Every, long), long);
        assert_eq!(shown_label(Labels::WhereTheyFit, "final"), "final");
    }

    #[test]
    fn a_label_with_no_free_place_is_left_out_unless_it_must_show() {
        let area = (&(0..1000), &(0..700));
        // A point in a tight cloud: every place around it holds another point's mark.
        let mut cloud = vec![(500, 300)];
        for dx in [-40, -20, 0, 20, 40, 60, 80, 100, 120] {
            for dy in [-30, -15, 0, 15, 30] {
                if (dx, dy) != (0, 0) {
                    cloud.push((500 + dx, 300 + dy));
                }
            }
        }
        let n = cloud.len();
        let widths = vec![60; n];
        let rings = vec![true; n];
        let first_only: Vec<bool> = (0..n).map(|k| k == 0).collect();
        let optional = place_labels(&cloud, &widths, &rings, &vec![false; n], Vec::new(), area);
        assert_eq!(optional[0], None, "no free place around the cloud's centre: {optional:?}");
        let forced = place_labels(&cloud, &widths, &rings, &first_only, Vec::new(), area);
        assert_eq!(forced[0], Some((8, 2)), "a label that must show lies over optional points");
        // Two must-show points in the cloud: the second's label clears the first's label and mark.
        let first_two: Vec<bool> = (0..n).map(|k| k < 2).collect();
        let forced = place_labels(&cloud, &widths, &rings, &first_two, Vec::new(), area);
        let (dx, dy) = forced[1].expect("shown");
        let (x1, y1) = cloud[1];
        let second = LabelBox(x1 + dx, y1 + dy, 60, LABEL_PX);
        assert!(!second.overlaps(&LabelBox(508, 302, 60, LABEL_PX)), "{forced:?}");
        assert!(!second.overlaps(&LabelBox(494, 294, 12, 12)), "{forced:?}");
        // A lone point's optional label is drawn.
        assert_eq!(place_labels(&[(200, 200)], &[60], &[true], &[false], Vec::new(), area), [Some((8, 2))]);
    }
}
