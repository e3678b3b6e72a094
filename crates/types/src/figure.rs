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

/// One named data series.
pub fn series(name: &str, x: Vec<f64>, y: Vec<f64>, style: SeriesStyle) -> Series {
    Series { name: name.to_string(), x, y, style }
}
