//! Drawing one [`FigureSpec`] on any plotters backend: axes, heat map with
//! colour bar, series in four styles with NaN gaps, legend.

use crate::range::{Extent, PAD_FRACTION, cell_edges, tick_decimals};
use plotters::coord::Shift;
use plotters::prelude::*;
use rig_types::{FigureSpec, SeriesStyle};

/// Width of the colour-bar strip at the right of a heat map, pixels.
const COLOUR_BAR_PX: u32 = 120;
const FONT: &str = "sans-serif";

/// Tableau-10: distinguishable, and fixed so colours do not depend on anything but order.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Viridis sampled at nine evenly spaced points (matplotlib's table), linearly
/// interpolated: perceptually ordered and readable in grey.
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

fn viridis(t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let i = (t.floor() as usize).min(VIRIDIS.len() - 2);
    let f = t - i as f64;
    let lerp = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// Everything computed from the spec before drawing: validated shapes and ranges.
#[derive(Debug)]
pub struct Plan {
    x_range: (f64, f64),
    y_range: (f64, f64),
    /// Heat-map cell edges and the z range, when there is a heat map.
    heat: Option<HeatPlan>,
}

#[derive(Debug)]
struct HeatPlan {
    x_edges: Vec<f64>,
    y_edges: Vec<f64>,
    z_range: (f64, f64),
}

impl Plan {
    /// Validates the spec and computes the axis ranges; `Err` says what is malformed.
    pub fn new(spec: &FigureSpec) -> Result<Plan, String> {
        let (mut xe, mut ye) = (Extent::empty(), Extent::empty());
        for s in &spec.series {
            if s.x.len() != s.y.len() {
                return Err(format!("series {:?} has {} x values but {} y values", s.name, s.x.len(), s.y.len()));
            }
            for (&x, &y) in s.x.iter().zip(&s.y) {
                // A point is plotted only when both coordinates are finite.
                if x.is_finite() && y.is_finite() {
                    xe.add(x);
                    ye.add(y);
                }
            }
        }
        let mut x_range = xe.padded(PAD_FRACTION);
        let mut y_range = ye.padded(PAD_FRACTION);
        let heat = match &spec.heatmap {
            None => None,
            Some(h) => {
                if h.z.len() != h.y.len() {
                    return Err(format!("heat map has {} y centres but {} z rows", h.y.len(), h.z.len()));
                }
                if let Some((i, r)) = h.z.iter().enumerate().find(|(_, r)| r.len() != h.x.len()) {
                    return Err(format!(
                        "heat map z row {i} has {} cells, expected {} (x centres)",
                        r.len(),
                        h.x.len()
                    ));
                }
                let monotone = |v: &[f64]| v.windows(2).all(|w| w[1] > w[0]) && v.iter().all(|c| c.is_finite());
                if !monotone(&h.x) || !monotone(&h.y) {
                    return Err("heat map centres must be finite and strictly increasing".into());
                }
                let (x_edges, y_edges) = (cell_edges(&h.x), cell_edges(&h.y));
                let mut ze = Extent::empty();
                h.z.iter().flatten().for_each(|&z| ze.add(z));
                // The map fills the axes; series overlaid on it widen them only if they stick out.
                let span = |edges: &[f64], data: &Extent, padded: (f64, f64)| {
                    let (lo, hi) = (edges[0], edges[edges.len() - 1]);
                    if data.is_empty() {
                        (lo, hi)
                    } else {
                        (if data.min < lo { padded.0 } else { lo }, if data.max > hi { padded.1 } else { hi })
                    }
                };
                if !x_edges.is_empty() && !y_edges.is_empty() {
                    x_range = span(&x_edges, &xe, x_range);
                    y_range = span(&y_edges, &ye, y_range);
                }
                let z_range = if ze.is_empty() {
                    (0.0, 1.0)
                } else if ze.max > ze.min {
                    (ze.min, ze.max)
                } else {
                    ze.padded(0.0)
                };
                Some(HeatPlan { x_edges, y_edges, z_range })
            }
        };
        Ok(Plan { x_range, y_range, heat })
    }
}

/// Runs of consecutive plottable points: a NaN (or infinite) value ends a run,
/// so lines show a gap instead of bridging missing data.
fn finite_runs(x: &[f64], y: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur = Vec::new();
    for (&a, &b) in x.iter().zip(y) {
        if a.is_finite() && b.is_finite() {
            cur.push((a, b));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Draws the whole figure on `root` and presents it.
pub fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, spec: &FigureSpec, plan: &Plan) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let (w, _) = root.dim_in_pixel();
    let (plot_area, bar_area) = match &plan.heat {
        Some(_) => {
            let (a, b) = root.split_horizontally(w.saturating_sub(COLOUR_BAR_PX));
            (a, Some(b))
        }
        None => (root.clone(), None),
    };

    let x_dec = tick_decimals(plan.x_range.0, plan.x_range.1);
    let y_dec = tick_decimals(plan.y_range.0, plan.y_range.1);
    let x_fmt = move |v: &f64| rig_types::fmt_fixed(*v, x_dec);
    let y_fmt = move |v: &f64| rig_types::fmt_fixed(*v, y_dec);

    let mut chart = ChartBuilder::on(&plot_area)
        .caption(&spec.title, (FONT, 20))
        .margin(14)
        .x_label_area_size(52)
        .y_label_area_size(78)
        .build_cartesian_2d(plan.x_range.0..plan.x_range.1, plan.y_range.0..plan.y_range.1)?;
    chart
        .configure_mesh()
        .x_desc(spec.x_label.as_str())
        .y_desc(spec.y_label.as_str())
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()?;

    if let (Some(h), Some(heat)) = (&spec.heatmap, &plan.heat) {
        let (z0, z1) = heat.z_range;
        let mut cells = Vec::new();
        for (j, row) in h.z.iter().enumerate() {
            for (i, &z) in row.iter().enumerate() {
                // A non-finite cell (e.g. a simulation that did not converge) stays white.
                if z.is_finite() {
                    let c = viridis((z - z0) / (z1 - z0));
                    cells.push(Rectangle::new(
                        [(heat.x_edges[i], heat.y_edges[j]), (heat.x_edges[i + 1], heat.y_edges[j + 1])],
                        c.filled(),
                    ));
                }
            }
        }
        chart.draw_series(cells)?;
    }

    let mut any_label = false;
    // On a heat map, series start at red (the palette's blue and green vanish
    // in viridis) and symbols get a white halo.
    let on_heat = plan.heat.is_some();
    let first_colour = if on_heat { 3 } else { 0 };
    for (k, s) in spec.series.iter().enumerate() {
        let colour = PALETTE[(first_colour + k) % PALETTE.len()];
        let runs = finite_runs(&s.x, &s.y);
        let line = colour.stroke_width(2);
        // Every series is drawn as one annotated element (possibly empty) so
        // the legend lists it even when all its points are gaps.
        let anno = match s.style {
            SeriesStyle::Line => {
                for r in runs.iter().skip(1) {
                    chart.draw_series(LineSeries::new(r.iter().copied(), line))?;
                }
                chart.draw_series(LineSeries::new(runs.first().cloned().unwrap_or_default(), line))?
            }
            SeriesStyle::Dashed => {
                for r in runs.iter().skip(1) {
                    chart.draw_series(DashedLineSeries::new(r.iter().copied(), 8, 5, line))?;
                }
                chart.draw_series(DashedLineSeries::new(runs.first().cloned().unwrap_or_default(), 8, 5, line))?
            }
            SeriesStyle::Points => {
                let pts: Vec<(f64, f64)> = runs.into_iter().flatten().collect();
                if on_heat {
                    chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, WHITE.filled())))?;
                }
                chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 2, colour.filled())))?
            }
            SeriesStyle::Markers => {
                let pts: Vec<(f64, f64)> = runs.into_iter().flatten().collect();
                if on_heat {
                    chart.draw_series(pts.iter().map(|&p| Cross::new(p, 7, WHITE.stroke_width(5))))?;
                }
                chart.draw_series(pts.into_iter().map(|p| Cross::new(p, 6, colour.stroke_width(2))))?
            }
        };
        if !s.name.is_empty() {
            any_label = true;
            let style = s.style;
            anno.label(s.name.as_str()).legend(move |(x, y)| -> DynElement<'static, DB, (i32, i32)> {
                match style {
                    SeriesStyle::Line => PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)).into_dyn(),
                    SeriesStyle::Dashed => {
                        PathElement::new(vec![(x, y), (x + 7, y)], colour.stroke_width(2)).into_dyn()
                    }
                    SeriesStyle::Points => Circle::new((x + 10, y), 3, colour.filled()).into_dyn(),
                    SeriesStyle::Markers => Cross::new((x + 10, y), 6, colour.stroke_width(2)).into_dyn(),
                }
            });
        }
    }
    if any_label {
        chart
            .configure_series_labels()
            .position(legend_corner(spec, plan))
            .label_font((FONT, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }

    if let (Some(bar), Some(h), Some(heat)) = (bar_area, &spec.heatmap, &plan.heat) {
        draw_colour_bar(&bar, &h.z_label, heat.z_range)?;
    }
    root.present()
}

/// The legend goes in the plot corner holding the fewest data points, ties
/// broken in the fixed order upper right, upper left, lower right, lower left.
fn legend_corner(spec: &FigureSpec, plan: &Plan) -> SeriesLabelPosition {
    let (x0, x1) = plan.x_range;
    let (y0, y1) = plan.y_range;
    // The legend box is roughly a third of the width and a quarter of the
    // height for a few entries; grow the height with the entry count.
    let named = spec.series.iter().filter(|s| !s.name.is_empty()).count() as f64;
    let fx = 0.35;
    let fy = (0.06 * named + 0.04).min(0.6);
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let count = |right: bool, upper: bool| {
        spec.series
            .iter()
            .flat_map(|s| s.x.iter().zip(&s.y))
            .filter(|(x, y)| {
                let u = (**x - x0) / (x1 - x0);
                let v = (**y - y0) / (y1 - y0);
                let in_x = if right { u >= 1.0 - fx } else { u <= fx };
                let in_y = if upper { v >= 1.0 - fy } else { v <= fy };
                in_x && in_y
            })
            .count()
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, right, upper) in corners {
        let n = count(right, upper);
        if n < best.0 {
            best = (n, pos);
        }
    }
    best.1
}

/// The heat map's colour scale: a vertical strip from z min to z max with its label.
fn draw_colour_bar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, z_label: &str, z: (f64, f64)) -> DrawResult<DB> {
    let z_dec = tick_decimals(z.0, z.1);
    let z_fmt = move |v: &f64| rig_types::fmt_fixed(*v, z_dec);
    let mut bar = ChartBuilder::on(area)
        .margin_top(48)
        .margin_bottom(66)
        .margin_right(8)
        .y_label_area_size(0)
        .right_y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, z.0..z.1)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(z_label)
        .y_label_formatter(&z_fmt)
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .draw()?;
    const STEPS: usize = 100;
    let dz = (z.1 - z.0) / STEPS as f64;
    bar.draw_series((0..STEPS).map(|i| {
        let lo = z.0 + dz * i as f64;
        Rectangle::new([(0.0, lo), (1.0, lo + dz)], viridis((i as f64 + 0.5) / STEPS as f64).filled())
    }))?;
    Ok(())
}
