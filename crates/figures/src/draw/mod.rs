//! Drawing one [`FigureSpec`] (or one panel of a [`Sheet`]) on any plotters
//! backend: axes (linear or log x), heat map with colour bar and hatched
//! regions, series in every [`SeriesStyle`] with NaN gaps, legend inside the
//! emptiest corner or outside the plot area.

use crate::glyph::{HALO, glyph, legend_swatch};
use crate::log_axis::{LogTicks, log_ticks};
use crate::range::{Extent, PAD_FRACTION, cell_edges, tick_decimals};
use plotters::coord::Shift;
use plotters::coord::combinators::BindKeyPoints;
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use rig_types::{AxisScale, FigureSpec, SeriesStyle, Sheet};

mod legend;
use legend::{draw_colour_bar, draw_legend_strip, legend_corner, legend_entries, legend_height};
#[cfg(test)]
mod tests;

/// Width of the colour-bar strip at the right of a heat map, pixels.
const COLOUR_BAR_PX: u32 = 120;
pub(crate) const FONT: &str = "sans-serif";

/// Okabe & Ito (2008), "Color Universal Design": eight colours told apart
/// under every common colour-vision deficiency; yellow last (weak on white).
pub(crate) const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
    RGBColor(240, 228, 66),  // yellow
];
/// A band with no statistic after it (e.g. a bistable range) is grey.
const BAND_GREY: RGBColor = RGBColor(150, 150, 150);
/// On a heat map, series start at vermillion (blue and green vanish in viridis).
const FIRST_ON_HEAT: usize = 1;

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
    x_scale: AxisScale,
    /// Heat-map cell edges and the z range, when there is a heat map.
    heat: Option<HeatPlan>,
    /// Palette colour of each series (bands: of the series they belong to).
    colours: Vec<RGBColor>,
}

#[derive(Debug)]
struct HeatPlan {
    x_edges: Vec<f64>,
    y_edges: Vec<f64>,
    z_range: (f64, f64),
}

impl Plan {
    /// Validates the spec and computes the axis ranges; `Err` says what is malformed.
    pub fn new(spec: &FigureSpec, x_scale: AxisScale) -> Result<Plan, String> {
        let (mut xe, mut ye) = (Extent::empty(), Extent::empty());
        let log_x = x_scale == AxisScale::Log10;
        for s in &spec.series {
            if s.x.len() != s.y.len() {
                return Err(format!("series {:?} has {} x values but {} y values", s.name, s.x.len(), s.y.len()));
            }
            if s.style == SeriesStyle::HatchCells && spec.heatmap.is_none() {
                return Err(format!("series {:?} hatches heat-map cells but the figure has no heat map", s.name));
            }
            for (&x, &y) in s.x.iter().zip(&s.y) {
                // A point is plotted only when both coordinates are finite (and x > 0 on a log axis).
                if x.is_finite() && y.is_finite() && (!log_x || x > 0.0) {
                    xe.add(if log_x { x.log10() } else { x });
                    ye.add(y);
                }
            }
        }
        let mut x_range = xe.padded(PAD_FRACTION);
        if log_x {
            x_range = (10f64.powf(x_range.0), 10f64.powf(x_range.1));
        }
        let mut y_range = ye.padded(PAD_FRACTION);
        let heat = match &spec.heatmap {
            None => None,
            Some(_) if log_x => return Err("a heat map needs a linear x axis".into()),
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
        let colours = series_colours(spec);
        Ok(Plan { x_range, y_range, x_scale, heat, colours })
    }
}

/// Palette colours in series order, counting only series that are drawn as
/// data (lines and markers). A band takes the colour of the next such series
/// (the statistic it is the interval of) and is grey when none follows; a
/// hatched region is black/white by the map's brightness (no palette entry).
fn series_colours(spec: &FigureSpec) -> Vec<RGBColor> {
    let first = if spec.heatmap.is_some() { FIRST_ON_HEAT } else { 0 };
    let mut k = 0;
    let own: Vec<Option<RGBColor>> = spec
        .series
        .iter()
        .map(|s| match s.style {
            SeriesStyle::Band | SeriesStyle::HatchCells => None,
            _ => {
                k += 1;
                Some(PALETTE[(first + k - 1) % PALETTE.len()])
            }
        })
        .collect();
    (0..own.len()).map(|i| own[i].or_else(|| own[i..].iter().flatten().next().copied()).unwrap_or(BAND_GREY)).collect()
}

/// Font sizes and margins: full size for a figure, compact for a small panel.
#[derive(Debug, Clone, Copy)]
struct Look {
    title: u32,
    label: u32,
    desc: u32,
    margin: u32,
    x_area: u32,
    y_area: u32,
}

impl Look {
    fn for_width(w: u32) -> Look {
        if w >= 560 {
            Look { title: 20, label: 14, desc: 16, margin: 14, x_area: 52, y_area: 78 }
        } else {
            Look { title: 14, label: 11, desc: 12, margin: 6, x_area: 38, y_area: 56 }
        }
    }
}

/// Where a panel's legend goes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum LegendAt {
    /// In the plot corner holding the fewest points.
    Inside,
    /// Drawn by the caller outside the plot area (or not at all).
    Outside,
}

/// Runs of consecutive plottable points: a NaN (or infinite) value ends a run,
/// so lines show a gap instead of bridging missing data.
fn finite_runs(x: &[f64], y: &[f64], log_x: bool) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur = Vec::new();
    for (&a, &b) in x.iter().zip(y) {
        if a.is_finite() && b.is_finite() && (!log_x || a > 0.0) {
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

/// Draws the whole figure on `root` and presents it. A heat map's legend
/// goes below the plot area, so it never covers a cell or a marker.
pub fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, spec: &FigureSpec, plan: &Plan) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let (w, h) = root.dim_in_pixel();
    let look = Look::for_width(w);
    let (mut plot_area, bar_area) = match &plan.heat {
        Some(_) => {
            let (a, b) = root.split_horizontally(w.saturating_sub(COLOUR_BAR_PX));
            (a, Some(b))
        }
        None => (root.clone(), None),
    };
    let entries = legend_entries(spec, plan);
    let outside = plan.heat.is_some() && !entries.is_empty();
    let mut legend_area = None;
    if outside {
        let strip = legend_height(&plot_area, &entries, look);
        let (a, b) = plot_area.split_vertically(h.saturating_sub(strip));
        plot_area = a;
        legend_area = Some(b);
    }
    draw_panel(&plot_area, spec, plan, look, if outside { LegendAt::Outside } else { LegendAt::Inside })?;
    if let Some(area) = legend_area {
        draw_legend_strip(&area, &entries, look)?;
    }
    if let (Some(bar), Some(hm), Some(heat)) = (bar_area, &spec.heatmap, &plan.heat) {
        draw_colour_bar(&bar, &hm.z_label, heat.z_range, look)?;
    }
    root.present()
}

/// Pixel size of a sheet: panels of a size that keeps their text readable.
pub fn sheet_size(sheet: &Sheet) -> (u32, u32) {
    let (cols, rows, pw, ph) = sheet_grid(sheet);
    let legend = if shared_legend(sheet) { SHEET_LEGEND_PX } else { 0 };
    (cols * pw, SHEET_TITLE_PX + rows * ph + legend)
}

const SHEET_TITLE_PX: u32 = 44;
const SHEET_LEGEND_PX: u32 = 40;

/// (columns, rows, panel width, panel height) in pixels.
fn sheet_grid(sheet: &Sheet) -> (u32, u32, u32, u32) {
    let cols = sheet.columns.clamp(1, sheet.panels.len().max(1)) as u32;
    let rows = (sheet.panels.len() as u32).div_ceil(cols).max(1);
    let (pw, ph) = match cols {
        1 if rows == 1 => (900, 560),
        1 => (900, 320),
        2 => (560, 380),
        _ => (320, 240),
    };
    (cols, rows, pw, ph)
}

/// Panels with the same named series in the same styles share one legend
/// below the grid instead of repeating it in every panel.
fn shared_legend(sheet: &Sheet) -> bool {
    let key = |s: &FigureSpec| -> Vec<(String, SeriesStyle)> {
        s.series.iter().filter(|x| !x.name.is_empty()).map(|x| (x.name.clone(), x.style)).collect()
    };
    sheet.panels.len() > 1
        && !key(&sheet.panels[0].spec).is_empty()
        && sheet.panels.iter().all(|p| key(&p.spec) == key(&sheet.panels[0].spec))
}

/// Draws a sheet: its title, then the panels in a grid, then a shared legend.
pub fn draw_sheet<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, sheet: &Sheet, plans: &[Plan]) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let (cols, rows, pw, ph) = sheet_grid(sheet);
    let (title, rest) = root.split_vertically(SHEET_TITLE_PX);
    title.draw(&Text::new(
        sheet.title.as_str(),
        (12, 10),
        (FONT, 22).into_font().color(&BLACK).pos(plotters::style::text_anchor::Pos::default()),
    ))?;
    let shared = shared_legend(sheet);
    let (grid, legend) = rest.split_vertically(rows * ph);
    for (i, (panel, plan)) in sheet.panels.iter().zip(plans).enumerate() {
        let (c, r) = (i as u32 % cols, i as u32 / cols);
        let area = grid.clone().shrink((c * pw, r * ph), (pw, ph));
        draw_panel(
            &area,
            &panel.spec,
            plan,
            Look::for_width(pw),
            if shared { LegendAt::Outside } else { LegendAt::Inside },
        )?;
    }
    if shared {
        let entries = legend_entries(&sheet.panels[0].spec, &plans[0]);
        draw_legend_strip(&legend, &entries, Look::for_width(900))?;
    }
    root.present()
}

/// The axes and everything in them, on one area.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    spec: &FigureSpec,
    plan: &Plan,
    look: Look,
    legend: LegendAt,
) -> DrawResult<DB> {
    let (x0, x1) = plan.x_range;
    let builder = |a| {
        let mut b = ChartBuilder::on(a);
        b.caption(&spec.title, (FONT, look.title))
            .margin(look.margin)
            .x_label_area_size(look.x_area)
            .y_label_area_size(look.y_area);
        b
    };
    let y = plan.y_range.0..plan.y_range.1;
    match plan.x_scale {
        AxisScale::Linear => {
            let x_dec = tick_decimals(x0, x1);
            let fmt = move |v: &f64| rig_types::fmt_fixed(*v, x_dec);
            fill_chart(builder(area).build_cartesian_2d(x0..x1, y)?, spec, plan, look, legend, &fmt)
        }
        AxisScale::Log10 => {
            // Our own ticks (crate::log_axis), so plotters' dense log mesh never draws.
            let ticks = log_x_ticks(area.dim_in_pixel().0, plan.x_range, look);
            let coord = (x0..x1)
                .log_scale()
                .with_key_points(ticks.labelled.iter().map(|t| t.0).collect())
                .with_light_points(ticks.minor.iter().copied());
            let fmt = |v: &f64| ticks.label_of(*v);
            let chart = builder(area).build_cartesian_2d(coord, y)?;
            // Short unlabelled ticks below the axis line at the minor values.
            let ends: Vec<((i32, i32), (i32, i32))> = ticks
                .minor
                .iter()
                .map(|&v| {
                    let (px, py) = chart.backend_coord(&(v, plan.y_range.0));
                    let (bx, by) = area.get_base_pixel();
                    ((px - bx, py - by), (px - bx, py - by + MINOR_TICK_PX))
                })
                .collect();
            fill_chart(chart, spec, plan, look, legend, &fmt)?;
            for (a, b) in ends {
                area.draw(&PathElement::new(vec![a, b], BLACK.stroke_width(1)))?;
            }
            Ok(())
        }
    }
}

/// Length of an unlabelled minor tick on a log axis, pixels (plotters' labelled ticks are 5).
const MINOR_TICK_PX: i32 = 3;

/// Plot-area width of a panel `panel_w` pixels wide: `draw_panel`'s builder
/// takes the margin on both sides and the y label area on the left.
fn plot_width_px(panel_w: u32, look: Look) -> u32 {
    panel_w.saturating_sub(2 * look.margin + look.y_area)
}

/// The log x axis of a panel `panel_w` pixels wide: [`crate::log_axis::log_ticks`]
/// with labels measured in the embedded font at the panel's label size.
fn log_x_ticks(panel_w: u32, x_range: (f64, f64), look: Look) -> LogTicks {
    let font = (FONT, look.label).into_font();
    let width = |s: &str| font.box_size(s).map(|b| b.0 as f64).unwrap_or(0.6 * look.label as f64 * s.len() as f64);
    log_ticks(x_range.0, x_range.1, plot_width_px(panel_w, look) as f64, &width)
}

fn fill_chart<'a, DB: DrawingBackend + 'a, X>(
    mut chart: ChartContext<'a, DB, Cartesian2d<X, RangedCoordf64>>,
    spec: &FigureSpec,
    plan: &Plan,
    look: Look,
    legend: LegendAt,
    x_fmt: &dyn Fn(&f64) -> String,
) -> DrawResult<DB>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    std::ops::Range<f64>: AsRangedCoord,
{
    let y_dec = tick_decimals(plan.y_range.0, plan.y_range.1);
    let y_fmt = move |v: &f64| rig_types::fmt_fixed(*v, y_dec);
    chart
        .configure_mesh()
        .x_desc(spec.x_label.as_str())
        .y_desc(spec.y_label.as_str())
        .x_label_formatter(x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT, look.label))
        .axis_desc_style((FONT, look.desc))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()?;

    let mut grid: Vec<Vec<Option<RGBColor>>> = Vec::new();
    if let (Some(h), Some(heat)) = (&spec.heatmap, &plan.heat) {
        let (z0, z1) = heat.z_range;
        grid =
            h.z.iter()
                .map(|row| row.iter().map(|&z| z.is_finite().then(|| viridis((z - z0) / (z1 - z0)))).collect())
                .collect();
        let mut cells = Vec::new();
        for (j, row) in grid.iter().enumerate() {
            for (i, c) in row.iter().enumerate() {
                // A non-finite cell (e.g. a simulation that did not converge) stays white.
                if let Some(c) = c {
                    cells.push(Rectangle::new(
                        [(heat.x_edges[i], heat.y_edges[j]), (heat.x_edges[i + 1], heat.y_edges[j + 1])],
                        c.filled(),
                    ));
                }
            }
        }
        chart.draw_series(cells)?;
    }
    let cell_colour = |i: usize, j: usize| grid.get(j).and_then(|r| r.get(i)).copied().flatten();

    let on_heat = plan.heat.is_some();
    let log_x = plan.x_scale == AxisScale::Log10;
    for (k, s) in spec.series.iter().enumerate() {
        let colour = plan.colours[k];
        let runs = finite_runs(&s.x, &s.y, log_x);
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
            SeriesStyle::Marker { shape, filled } => {
                // Drawn in pixels on the plotting area (a marker keeps its shape
                // whatever the axes' aspect); the empty series carries the legend entry.
                let r = if look.label >= 14 { 5 } else { 4 };
                let area = chart.plotting_area().strip_coord_spec();
                let (bx, by) = area.get_base_pixel();
                let pixels: Vec<(i32, i32)> = runs
                    .into_iter()
                    .flatten()
                    .map(|p| chart.backend_coord(&p))
                    .map(|(a, b)| (a - bx, b - by))
                    .collect();
                for &p in &pixels {
                    if on_heat {
                        area.draw(&glyph::<DB>(p, shape, true, HALO, r + 2, 1))?;
                    }
                    area.draw(&glyph::<DB>(p, shape, filled, colour, r, 2))?;
                }
                chart.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            }
            SeriesStyle::Band => {
                // The polygon as given (NaN vertices dropped): runs joined, in order.
                // Fewer than three vertices is an empty band: nothing drawn, still in the legend.
                let pts: Vec<(f64, f64)> = runs.into_iter().flatten().collect();
                let poly = (pts.len() >= 3).then(|| Polygon::new(pts, colour.mix(0.25).filled()));
                chart.draw_series(poly)?
            }
            SeriesStyle::HatchCells => {
                let heat = plan.heat.as_ref().expect("Plan::new rejects hatching without a heat map");
                let cells = hatched_cells(&s.x, &s.y, &heat.x_edges, &heat.y_edges);
                chart.draw_series(hatch_lines(&cells, heat, &cell_colour))?;
                chart.draw_series(outline(&cells, heat))?
            }
        };
        if !s.name.is_empty() && legend == LegendAt::Inside {
            let style = s.style;
            anno.label(s.name.as_str()).legend(move |(x, y)| legend_swatch::<DB>((x, y), style, colour));
        }
    }
    let any_label = spec.series.iter().any(|s| !s.name.is_empty());
    if any_label && legend == LegendAt::Inside {
        chart
            .configure_series_labels()
            .position(legend_corner(spec, plan))
            .label_font((FONT, look.label))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

/// (column, row) of the heat-map cell holding each finite point, sorted and
/// without repeats; points outside the map are ignored.
fn hatched_cells(x: &[f64], y: &[f64], xe: &[f64], ye: &[f64]) -> Vec<(usize, usize)> {
    let index = |edges: &[f64], v: f64| {
        let k = edges.partition_point(|&e| e <= v);
        (k >= 1 && k < edges.len()).then(|| k - 1)
    };
    let mut cells: Vec<(usize, usize)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .filter_map(|(&a, &b)| Some((index(xe, a)?, index(ye, b)?)))
        .collect();
    cells.sort_unstable();
    cells.dedup();
    cells
}

/// Three diagonal strokes per cell, black over a light cell and white over a
/// dark one so the hatching reads on every part of the colour scale.
fn hatch_lines(
    cells: &[(usize, usize)],
    heat: &HeatPlan,
    cell_colour: &dyn Fn(usize, usize) -> Option<RGBColor>,
) -> Vec<PathElement<(f64, f64)>> {
    let mut out = Vec::new();
    for &(i, j) in cells {
        let (x0, x1, y0, y1) = (heat.x_edges[i], heat.x_edges[i + 1], heat.y_edges[j], heat.y_edges[j + 1]);
        let at = |u: f64, v: f64| (x0 + u * (x1 - x0), y0 + v * (y1 - y0));
        let light =
            cell_colour(i, j).is_none_or(|c| 0.299 * c.0 as f64 + 0.587 * c.1 as f64 + 0.114 * c.2 as f64 > 128.0);
        let ink = if light { BLACK.mix(0.7) } else { WHITE.mix(0.9) };
        for c in [-0.5, 0.0, 0.5] {
            let (a, b) = if c >= 0.0 { (at(c, 0.0), at(1.0, 1.0 - c)) } else { (at(0.0, -c), at(1.0 + c, 1.0)) };
            out.push(PathElement::new(vec![a, b], ink.stroke_width(1)));
        }
    }
    out
}

/// The region's boundary: every cell edge between a hatched and an unhatched cell.
fn outline(cells: &[(usize, usize)], heat: &HeatPlan) -> Vec<PathElement<(f64, f64)>> {
    let inside = |i: isize, j: isize| i >= 0 && j >= 0 && cells.binary_search(&(i as usize, j as usize)).is_ok();
    let (xe, ye) = (&heat.x_edges, &heat.y_edges);
    let mut out = Vec::new();
    for &(i, j) in cells {
        let (ii, jj) = (i as isize, j as isize);
        let edges = [
            (!inside(ii - 1, jj), (xe[i], ye[j]), (xe[i], ye[j + 1])),
            (!inside(ii + 1, jj), (xe[i + 1], ye[j]), (xe[i + 1], ye[j + 1])),
            (!inside(ii, jj - 1), (xe[i], ye[j]), (xe[i + 1], ye[j])),
            (!inside(ii, jj + 1), (xe[i], ye[j + 1]), (xe[i + 1], ye[j + 1])),
        ];
        for (open, a, b) in edges {
            if open {
                out.push(PathElement::new(vec![a, b], BLACK.stroke_width(2)));
            }
        }
    }
    out
}
