//! The legend: entries laid out in rows inside the emptiest corner or in a
//! strip outside the plot area, and the heat map's colour bar.

use super::{DrawResult, FONT, Look, Plan, viridis};
use crate::glyph::legend_swatch;
use crate::range::tick_decimals;
use plotters::coord::Shift;
use plotters::prelude::*;
use rig_types::{AxisScale, FigureSpec, SeriesStyle};

/// (name, style, colour) of every named series, in order.
pub(super) fn legend_entries(spec: &FigureSpec, plan: &Plan) -> Vec<(String, SeriesStyle, RGBColor)> {
    spec.series
        .iter()
        .zip(&plan.colours)
        .filter(|(s, _)| !s.name.is_empty())
        .map(|(s, c)| (s.name.clone(), s.style, *c))
        .collect()
}

const LEGEND_ROW_PX: u32 = 22;
const SWATCH_PX: i32 = 24;

/// Entries laid out left to right, wrapping: (row, x offset) of each.
fn legend_layout<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, SeriesStyle, RGBColor)],
    look: Look,
) -> Vec<(u32, i32)> {
    let width = area.dim_in_pixel().0 as i32 - 2 * look.margin as i32;
    let font = TextStyle::from((FONT, look.label).into_font());
    let (mut row, mut x) = (0u32, 0i32);
    let mut out = Vec::new();
    for (name, _, _) in entries {
        let text_w = area.estimate_text_size(name, &font).map(|s| s.0 as i32).unwrap_or(8 * name.len() as i32);
        let w = SWATCH_PX + 6 + text_w + 18;
        if x > 0 && x + w > width {
            row += 1;
            x = 0;
        }
        out.push((row, x));
        x += w;
    }
    out
}

pub(super) fn legend_height<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, SeriesStyle, RGBColor)],
    look: Look,
) -> u32 {
    let rows = legend_layout(area, entries, look).last().map_or(0, |e| e.0 + 1);
    rows * LEGEND_ROW_PX + 10
}

/// A legend outside the plot area: one swatch and name per entry, in rows.
pub(super) fn draw_legend_strip<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, SeriesStyle, RGBColor)],
    look: Look,
) -> DrawResult<DB> {
    let left = look.margin as i32 + look.y_area as i32;
    for ((name, style, colour), (row, x)) in entries.iter().zip(legend_layout(area, entries, look)) {
        let y = 4 + (row * LEGEND_ROW_PX) as i32 + LEGEND_ROW_PX as i32 / 2;
        area.draw(&legend_swatch::<DB>((left + x, y), *style, *colour))?;
        area.draw(&Text::new(
            name.as_str(),
            (left + x + SWATCH_PX + 6, y - look.label as i32 / 2 - 1),
            (FONT, look.label).into_font(),
        ))?;
    }
    Ok(())
}

/// The legend goes in the plot corner holding the fewest data points, ties
/// broken in the fixed order upper right, upper left, lower right, lower left.
pub(super) fn legend_corner(spec: &FigureSpec, plan: &Plan) -> SeriesLabelPosition {
    let (x0, x1) = plan.x_range;
    let (y0, y1) = plan.y_range;
    let log_x = plan.x_scale == AxisScale::Log10;
    let pos_x =
        |x: f64| if log_x { (x.log10() - x0.log10()) / (x1.log10() - x0.log10()) } else { (x - x0) / (x1 - x0) };
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
                let u = pos_x(**x);
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
pub(super) fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    z_label: &str,
    z: (f64, f64),
    look: Look,
) -> DrawResult<DB> {
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
        .label_style((FONT, look.label.min(13)))
        .axis_desc_style((FONT, look.desc.min(14)))
        .draw()?;
    const STEPS: usize = 100;
    let dz = (z.1 - z.0) / STEPS as f64;
    bar.draw_series((0..STEPS).map(|i| {
        let lo = z.0 + dz * i as f64;
        Rectangle::new([(0.0, lo), (1.0, lo + dz)], viridis((i as f64 + 0.5) / STEPS as f64).filled())
    }))?;
    Ok(())
}
