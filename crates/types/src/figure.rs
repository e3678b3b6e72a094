//! A figure as data: what `rig-figures` draws and what snapshots pin.
//! Producers fill it; only `rig-figures` turns it into SVG/PNG.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SeriesStyle {
    Line,
    Dashed,
    Points,
    /// Markers drawn larger, e.g. the peaks used by a log decrement.
    Markers,
    /// Point markers of one shape, filled or open: up and down sweeps,
    /// measured and thesis labels told apart by shape, not only by colour.
    Marker {
        shape: MarkerShape,
        filled: bool,
    },
    /// A shaded region: the points are the vertices of one polygon in order
    /// (build it with [`band`]); an uncertainty band, a bistable band.
    Band,
    /// A region of a heat map: every point marks the cell that contains it;
    /// those cells are hatched and the region's outline drawn, so the map
    /// underneath stays readable.
    HatchCells,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MarkerShape {
    Circle,
    Square,
    Diamond,
    TriangleUp,
    TriangleDown,
}

/// How an axis maps values to positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisScale {
    #[default]
    Linear,
    /// Decades; only positive values are plotted.
    Log10,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    pub name: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub style: SeriesStyle,
}

/// One panel. Multi-panel thesis figures ((a), (b)) are several specs with
/// ids like `fig-4-17a`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FigureSpec {
    /// File stem, e.g. `fig-4-08-thesis`.
    pub id: String,
    pub title: String,
    /// One paragraph: what is shown, from which data, and how it was computed.
    pub caption: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// Decimals the data supports on each axis: the series CSV (and so the
    /// snapshots and `xtask diff`) round to these.
    pub x_decimals: usize,
    pub y_decimals: usize,
    /// Optional heat map: (x centres, y centres, z[row y][col x]) with a z label.
    pub heatmap: Option<Heatmap>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Heatmap {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<Vec<f64>>,
    pub z_label: String,
}

/// A figure with no heat map: `x` and `y` are (axis label, decimals printed).
pub fn figure(
    id: &str,
    title: &str,
    caption: &str,
    x: (&str, usize),
    y: (&str, usize),
    series: Vec<Series>,
) -> FigureSpec {
    FigureSpec {
        id: id.to_string(),
        title: title.to_string(),
        caption: caption.to_string(),
        x_label: x.0.to_string(),
        y_label: y.0.to_string(),
        series,
        x_decimals: x.1,
        y_decimals: y.1,
        heatmap: None,
    }
}

/// A figure of several panels on one sheet, `columns` panels per row, read
/// left to right then top to bottom: a magnitude panel over a coherence
/// panel, one panel per model, one panel per operating point. Each panel is a
/// whole [`FigureSpec`] (its `title` heads the panel; its `id` and `caption`
/// are not drawn) with the options a single figure does not need.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sheet {
    /// File stem of the sheet.
    pub id: String,
    pub title: String,
    pub caption: String,
    pub columns: usize,
    pub panels: Vec<Panel>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Panel {
    pub spec: FigureSpec,
    #[serde(default)]
    pub x_scale: AxisScale,
}

/// One named data series.
pub fn series(name: &str, x: Vec<f64>, y: Vec<f64>, style: SeriesStyle) -> Series {
    Series { name: name.to_string(), x, y, style }
}

/// A shaded band between `lo` and `hi` over `x` ([`SeriesStyle::Band`]): the
/// polygon along `lo` left to right and back along `hi`. Points where a bound
/// is not finite are left out.
pub fn band(name: &str, x: &[f64], lo: &[f64], hi: &[f64]) -> Series {
    let keep: Vec<usize> = (0..x.len().min(lo.len()).min(hi.len()))
        .filter(|&i| x[i].is_finite() && lo[i].is_finite() && hi[i].is_finite())
        .collect();
    let px = keep.iter().map(|&i| x[i]).chain(keep.iter().rev().map(|&i| x[i])).collect();
    let py = keep.iter().map(|&i| lo[i]).chain(keep.iter().rev().map(|&i| hi[i])).collect();
    Series { name: name.to_string(), x: px, y: py, style: SeriesStyle::Band }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn old_specs_still_parse() {
        let old = r#"{"name":"a","x":[1.0],"y":[2.0],"style":"markers"}"#;
        let s: Series = serde_json::from_str(old).unwrap();
        assert_eq!(s.style, SeriesStyle::Markers);
        let m = Series { style: SeriesStyle::Marker { shape: MarkerShape::TriangleDown, filled: false }, ..s };
        let text = serde_json::to_string(&m).unwrap();
        assert!(text.contains(r#"{"marker":{"shape":"triangle_down","filled":false}}"#), "{text}");
        assert_eq!(serde_json::from_str::<Series>(&text).unwrap(), m);
        let p: Panel = serde_json::from_str(&format!(
            r#"{{"spec":{}}}"#,
            serde_json::to_string(&figure("f", "t", "", ("x", 1), ("y", 1), vec![])).unwrap()
        ))
        .unwrap();
        assert_eq!(p.x_scale, AxisScale::Linear);
    }

    #[test]
    fn band_goes_out_along_lo_and_back_along_hi() {
        let b = band("b", &[0.0, 1.0, 2.0], &[1.0, f64::NAN, 3.0], &[2.0, 5.0, 4.0]);
        assert_eq!(b.x, vec![0.0, 2.0, 2.0, 0.0]);
        assert_eq!(b.y, vec![1.0, 3.0, 4.0, 2.0]);
    }
}
