//! Marker glyphs and legend swatches, in pixels around a point: the same
//! shapes on the plot and in the legend, whatever the legend's placement.

use plotters::element::{DynElement, IntoDynElement};
use plotters::prelude::*;
use rig_types::{MarkerShape, SeriesStyle};

/// Under a marker on a heat map: a white halo so it reads on every cell.
pub const HALO: RGBColor = WHITE;

/// The vertices of `shape` of half-size `r` around (0, 0), pixel y down.
fn outline(shape: MarkerShape, r: i32) -> Vec<(i32, i32)> {
    // Triangles and the diamond a little larger than the square: equal visual weight.
    let t = r + 1;
    match shape {
        MarkerShape::Circle | MarkerShape::Square => vec![(-r, -r), (r, -r), (r, r), (-r, r)],
        MarkerShape::Diamond => vec![(0, -t), (t, 0), (0, t), (-t, 0)],
        MarkerShape::TriangleUp => vec![(0, -t), (t, t - 1), (-t, t - 1)],
        MarkerShape::TriangleDown => vec![(0, t), (t, 1 - t), (-t, 1 - t)],
    }
}

/// A marker centred at pixel `at`: filled, or open with a `stroke`-pixel
/// outline. Built from elements that do not name the backend, so it can be
/// boxed for the legend and drawn on any area.
pub fn glyph<DB: DrawingBackend>(
    (x, y): (i32, i32),
    shape: MarkerShape,
    filled: bool,
    colour: RGBColor,
    r: i32,
    stroke: u32,
) -> DynElement<'static, DB, (i32, i32)> {
    let style = if filled { colour.filled() } else { colour.stroke_width(stroke) };
    if shape == MarkerShape::Circle {
        return Circle::new((x, y), r, style).into_dyn();
    }
    let mut pts: Vec<(i32, i32)> = outline(shape, r).into_iter().map(|(a, b)| (x + a, y + b)).collect();
    if filled {
        Polygon::new(pts, style).into_dyn()
    } else {
        pts.push(pts[0]);
        PathElement::new(pts, style).into_dyn()
    }
}

/// The legend swatch of a series of `style`, its left end at `(x, y)`.
pub fn legend_swatch<DB: DrawingBackend>(
    (x, y): (i32, i32),
    style: SeriesStyle,
    colour: RGBColor,
) -> DynElement<'static, DB, (i32, i32)> {
    match style {
        SeriesStyle::Line => PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)).into_dyn(),
        SeriesStyle::Dashed => PathElement::new(vec![(x, y), (x + 7, y)], colour.stroke_width(2)).into_dyn(),
        SeriesStyle::Points => Circle::new((x + 10, y), 3, colour.filled()).into_dyn(),
        SeriesStyle::Markers => Cross::new((x + 10, y), 6, colour.stroke_width(2)).into_dyn(),
        SeriesStyle::Marker { shape, filled } => glyph((x + 10, y), shape, filled, colour, 5, 2),
        SeriesStyle::Band => Rectangle::new([(x, y - 6), (x + 20, y + 6)], colour.mix(0.25).filled()).into_dyn(),
        // The region's look: a black outline crossed by a hatch stroke.
        SeriesStyle::HatchCells => PathElement::new(
            vec![(x, y + 7), (x, y - 7), (x + 20, y - 7), (x + 20, y + 7), (x, y + 7), (x + 14, y - 7)],
            BLACK.stroke_width(2),
        )
        .into_dyn(),
    }
}
