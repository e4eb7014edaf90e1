//! SVG charts of runs and box sets: the only importer of `plotters`.
//!
//! Each function draws into a `String` it is given and opens no files; the CLI decides where
//! charts go. Data come from runs: nothing here computes or invents numbers.

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use thiserror::Error;

/// A chart could not be drawn.
#[derive(Debug, Error)]
#[error("chart '{title}': {reason}")]
pub struct ChartError {
    title: String,
    reason: String,
}

fn fail(title: &str, e: impl std::fmt::Display) -> ChartError {
    ChartError { title: title.into(), reason: e.to_string() }
}

/// A named polyline.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points in data coordinates, drawn in order.
    pub points: Vec<(f64, f64)>,
}

/// Axis scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Linear.
    Linear,
    /// Base-10 logarithmic (non-positive values are dropped).
    Log,
}

const COLORS: [RGBColor; 6] = [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189), RGBColor(255, 127, 14), RGBColor(23, 190, 207)];

fn range(values: impl Iterator<Item = f64>, scale: Scale) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (scale == Scale::Linear || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    match scale {
        Scale::Log => (lo / 1.5, hi * 1.5),
        Scale::Linear => {
            let pad = 0.05 * (hi - lo).max(1e-9);
            (lo - pad, hi + pad)
        }
    }
}

/// Lines on linear or log axes, with a legend.
pub fn lines(out: &mut String, title: &str, x_label: &str, y_label: &str, series: &[Series], x: Scale, y: Scale) -> Result<(), ChartError> {
    let keep = |p: &(f64, f64)| (x == Scale::Linear || p.0 > 0.0) && (y == Scale::Linear || p.1 > 0.0) && p.0.is_finite() && p.1.is_finite();
    let series: Vec<Series> = series.iter().map(|s| Series { label: s.label.clone(), points: s.points.iter().copied().filter(keep).collect() }).collect();
    let (x0, x1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)), x);
    let (y0, y1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)), y);
    let root = SVGBackend::with_string(out, (800, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(title, e))?;
    match (x, y) {
        (Scale::Log, Scale::Log) => draw_lines(&root, title, x_label, y_label, (x0..x1).log_scale(), (y0..y1).log_scale(), &series),
        (Scale::Log, Scale::Linear) => draw_lines(&root, title, x_label, y_label, (x0..x1).log_scale(), y0..y1, &series),
        (Scale::Linear, Scale::Log) => draw_lines(&root, title, x_label, y_label, x0..x1, (y0..y1).log_scale(), &series),
        (Scale::Linear, Scale::Linear) => draw_lines(&root, title, x_label, y_label, x0..x1, y0..y1, &series),
    }?;
    root.present().map_err(|e| fail(title, e))
}

fn draw_lines<XR, YR>(root: &DrawingArea<SVGBackend, plotters::coord::Shift>, title: &str, x_label: &str, y_label: &str, xr: XR, yr: YR, series: &[Series]) -> Result<(), ChartError>
where
    XR: AsRangedCoord<Value = f64>,
    YR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: ValueFormatter<f64>,
    YR::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(xr, yr)
        .map_err(|e| fail(title, e))?;
    // Short labels: plotters prints log-axis values with every digit.
    let short = |v: &f64| {
        let a = v.abs();
        if a != 0.0 && !(1e-2..1e4).contains(&a) {
            format!("{v:.0e}")
        } else {
            format!("{}", (v * 1000.0).round() / 1000.0)
        }
    };
    chart.configure_mesh().x_desc(x_label).y_desc(y_label).x_label_formatter(&short).y_label_formatter(&short).draw().map_err(|e| fail(title, e))?;
    for (k, s) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        chart
            .draw_series(LineSeries::new(s.points.iter().copied(), color.stroke_width(2)))
            .map_err(|e| fail(title, e))?
            .label(s.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(|e| fail(title, e))?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK).draw().map_err(|e| fail(title, e))?;
    Ok(())
}

/// One panel of boxes projected on two coordinates: `[x_lo, x_hi, y_lo, y_hi]` each.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Panel title.
    pub title: String,
    /// Rectangles to draw.
    pub rects: Vec<[f64; 4]>,
    /// Optional points drawn on top (e.g. sampled true solutions, cusps).
    pub marks: Vec<(f64, f64)>,
}

/// Side-by-side panels of projected boxes over a common frame.
pub fn box_panels(out: &mut String, title: &str, x_label: &str, y_label: &str, panels: &[Panel], x_range: (f64, f64), y_range: (f64, f64)) -> Result<(), ChartError> {
    let w = 380 * panels.len().max(1) as u32;
    let root = SVGBackend::with_string(out, (w, 430)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(title, e))?;
    let root = root.titled(title, ("sans-serif", 20)).map_err(|e| fail(title, e))?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, panel) in areas.iter().zip(panels) {
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, ("sans-serif", 14))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)
            .map_err(|e| fail(title, e))?;
        chart.configure_mesh().x_desc(x_label).y_desc(y_label).x_labels(5).y_labels(5).draw().map_err(|e| fail(title, e))?;
        chart
            .draw_series(panel.rects.iter().map(|r| Rectangle::new([(r[0], r[2]), (r[1], r[3])], COLORS[0].mix(0.5).filled())))
            .map_err(|e| fail(title, e))?;
        chart
            .draw_series(panel.rects.iter().map(|r| Rectangle::new([(r[0], r[2]), (r[1], r[3])], COLORS[0].stroke_width(1))))
            .map_err(|e| fail(title, e))?;
        chart.draw_series(panel.marks.iter().map(|&p| Circle::new(p, 2, COLORS[1].filled()))).map_err(|e| fail(title, e))?;
    }
    root.present().map_err(|e| fail(title, e))
}

/// How a layer of points is marked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled disc (certified points).
    Dot,
    /// An open circle (points found but not proven).
    Ring,
    /// A cross.
    Cross,
    /// A filled triangle.
    Triangle,
}

/// One layer of a `LayeredPanel`; `color` indexes the palette (0 blue, 1 red, 2 green, 3
/// purple, 4 orange, 5 cyan). Layers are drawn in order, so marks go last.
#[derive(Clone, Debug)]
pub enum Layer {
    /// Boxes `[x_lo, x_hi, y_lo, y_hi]`, filled translucent and outlined.
    Boxes { label: String, rects: Vec<[f64; 4]>, color: usize },
    /// Points drawn with `marker`.
    Points { label: String, points: Vec<(f64, f64)>, marker: Marker, color: usize },
    /// Text centred at data coordinates (region labels).
    Text { items: Vec<(f64, f64, String)> },
}

/// A panel with its own axes and layers; a layer with a non-empty label enters the legend.
#[derive(Clone, Debug)]
pub struct LayeredPanel {
    /// Panel title.
    pub title: String,
    /// Axis descriptions.
    pub x_label: String,
    /// Axis descriptions.
    pub y_label: String,
    /// Visible ranges; boxes are clipped to them.
    pub x_range: (f64, f64),
    /// Visible ranges; boxes are clipped to them.
    pub y_range: (f64, f64),
    /// What to draw, in order.
    pub layers: Vec<Layer>,
}

/// Panels on a grid of `columns` columns, each with its own axes, boxes of several kinds, marked
/// points and text.
pub fn layered_panels(out: &mut String, title: &str, panels: &[LayeredPanel], columns: usize) -> Result<(), ChartError> {
    let cols = columns.clamp(1, panels.len().max(1));
    let rows = panels.len().max(1).div_ceil(cols);
    // One panel alone gets room for a long title.
    let width = (560 * cols as u32).max(760);
    let root = SVGBackend::with_string(out, (width, 40 + 540 * rows as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(title, e))?;
    let root = root.titled(title, ("sans-serif", 20)).map_err(|e| fail(title, e))?;
    let areas = root.split_evenly((rows, cols));
    for (area, panel) in areas.iter().zip(panels) {
        let (x0, x1) = panel.x_range;
        let (y0, y1) = panel.y_range;
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, ("sans-serif", 14))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(50)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| fail(title, e))?;
        chart.configure_mesh().x_desc(&panel.x_label).y_desc(&panel.y_label).x_labels(6).y_labels(6).draw().map_err(|e| fail(title, e))?;
        let mut legend = false;
        // SVG does not clip to the plotting area: boxes are cut to the ranges, points outside dropped.
        let inside = |p: &(f64, f64)| (x0..=x1).contains(&p.0) && (y0..=y1).contains(&p.1);
        for layer in &panel.layers {
            match layer {
                Layer::Boxes { label, rects, color } => {
                    let c = COLORS[color % COLORS.len()];
                    // Boxes thinner than a pixel (a curve tangent to an axis) are widened to
                    // one about their centre: plotters rounds to whole pixels and would drop them.
                    let (px, py) = ((x1 - x0) / 400.0, (y1 - y0) / 400.0);
                    let widen = |lo: f64, hi: f64, p: f64| if hi - lo < p { (0.5 * (lo + hi) - 0.5 * p, 0.5 * (lo + hi) + 0.5 * p) } else { (lo, hi) };
                    let clipped: Vec<[(f64, f64); 2]> = rects
                        .iter()
                        .filter(|r| r[1] >= x0 && r[0] <= x1 && r[3] >= y0 && r[2] <= y1)
                        .map(|r| {
                            let ((a, b), (c, d)) = (widen(r[0], r[1], px), widen(r[2], r[3], py));
                            [(a.max(x0), c.max(y0)), (b.min(x1), d.min(y1))]
                        })
                        .collect();
                    chart.draw_series(clipped.iter().map(|&r| Rectangle::new(r, c.mix(0.35).filled()))).map_err(|e| fail(title, e))?;
                    let s = chart.draw_series(clipped.iter().map(|&r| Rectangle::new(r, c.stroke_width(1)))).map_err(|e| fail(title, e))?;
                    if !label.is_empty() {
                        legend = true;
                        s.label(label.clone()).legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.mix(0.6).filled()));
                    }
                }
                Layer::Points { label, points, marker, color } => {
                    let c = COLORS[color % COLORS.len()];
                    let pts: Vec<(f64, f64)> = points.iter().copied().filter(inside).collect();
                    let element = move |p: (f64, f64)| -> DynElement<'static, SVGBackend, (f64, f64)> {
                        match marker {
                            Marker::Dot => Circle::new(p, 4, c.filled()).into_dyn(),
                            Marker::Ring => Circle::new(p, 5, c.stroke_width(2)).into_dyn(),
                            Marker::Cross => Cross::new(p, 5, c.stroke_width(2)).into_dyn(),
                            Marker::Triangle => TriangleMarker::new(p, 6, c.filled()).into_dyn(),
                        }
                    };
                    let m = *marker;
                    let s = chart.draw_series(pts.iter().map(|&p| element(p))).map_err(|e| fail(title, e))?;
                    if !label.is_empty() {
                        legend = true;
                        s.label(label.clone()).legend(move |(x, y)| match m {
                            Marker::Dot => Circle::new((x + 6, y), 4, c.filled()).into_dyn(),
                            Marker::Ring => Circle::new((x + 6, y), 5, c.stroke_width(2)).into_dyn(),
                            Marker::Cross => Cross::new((x + 6, y), 5, c.stroke_width(2)).into_dyn(),
                            Marker::Triangle => TriangleMarker::new((x + 6, y), 6, c.filled()).into_dyn(),
                        });
                    }
                }
                Layer::Text { items } => {
                    let font = ("sans-serif", 16).into_font().color(&BLACK).pos(plotters::style::text_anchor::Pos::new(plotters::style::text_anchor::HPos::Center, plotters::style::text_anchor::VPos::Center));
                    chart
                        .draw_series(items.iter().filter(|(x, y, _)| inside(&(*x, *y))).map(|(x, y, t)| Text::new(t.clone(), (*x, *y), font.clone())))
                        .map_err(|e| fail(title, e))?;
                }
            }
        }
        if legend {
            chart.configure_series_labels().position(SeriesLabelPosition::UpperRight).background_style(WHITE.mix(0.85)).border_style(BLACK).label_font(("sans-serif", 12)).draw().map_err(|e| fail(title, e))?;
        }
    }
    root.present().map_err(|e| fail(title, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_lines_and_panels_as_svg() {
        let mut s = String::new();
        let series = [Series { label: "a".into(), points: vec![(0.1, 1.0), (0.01, 3.0), (-1.0, 2.0)] }];
        lines(&mut s, "t", "x", "y", &series, Scale::Log, Scale::Log).expect("draws");
        assert!(s.starts_with("<svg") && s.contains("<polyline"));
        let mut p = String::new();
        let panel = Panel { title: "p".into(), rects: vec![[0.0, 0.5, 0.0, 0.5]], marks: vec![(0.2, 0.2)] };
        box_panels(&mut p, "t", "x", "y", &[panel], (-1.0, 1.0), (-1.0, 1.0)).expect("draws");
        assert!(p.contains("<rect") && p.contains("<circle"));
        let mut q = String::new();
        let panel = LayeredPanel {
            title: "p".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            x_range: (0.0, 1.0),
            y_range: (0.0, 1.0),
            layers: vec![
                Layer::Boxes { label: "boxes".into(), rects: vec![[0.1, 0.2, 0.1, 0.2], [5.0, 6.0, 5.0, 6.0]], color: 0 },
                Layer::Points { label: "cusps".into(), points: vec![(0.5, 0.5), (2.0, 2.0)], marker: Marker::Triangle, color: 1 },
                Layer::Text { items: vec![(0.7, 0.7, "4".into())] },
            ],
        };
        layered_panels(&mut q, "t", &[panel], 1).expect("draws");
        // The box and the point outside the ranges are dropped; the label is written.
        let q = q.replace('\n', "");
        assert!(q.contains("<polygon") && q.contains(">4</text>") && q.contains(">cusps</text>"));
    }
}
