//! Figure specs (data only; rig-figures draws them) for the calibration plots:
//! Figs. 4.8, 4.10 and 4.14, for the thesis tables and for a campaign.

use crate::signal::DecayAnalysis;
use crate::stats::LineFit;
use rig_types::{FigureSpec, Series, SeriesStyle};

/// Most points a series may carry (rig-lab rule: ≤ ~2000 per series).
pub const MAX_POINTS: usize = 2000;

/// Keeps every k-th sample (k = ⌈n / MAX_POINTS⌉), always from the first: deterministic.
pub fn decimate(x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = x.len().min(y.len());
    let k = n.div_ceil(MAX_POINTS).max(1);
    ((0..n).step_by(k).map(|i| x[i]).collect(), (0..n).step_by(k).map(|i| y[i]).collect())
}

fn line(fit: &LineFit, x_max: f64, name: &str, style: SeriesStyle) -> Series {
    let xs = [0.0, x_max];
    Series { name: name.into(), x: xs.to_vec(), y: xs.iter().map(|x| fit.intercept + fit.slope * x).collect(), style }
}

/// Points with the two least-squares lines (through the origin, with offset).
#[allow(clippy::too_many_arguments)]
pub fn fit_figure(
    id: &str,
    title: &str,
    caption: &str,
    (x_label, y_label): (&str, &str),
    points: &[(f64, f64)],
    (origin, offset): (&LineFit, &LineFit),
    slope_label: &str,
    decimals: (usize, usize),
) -> FigureSpec {
    let x_max = points.iter().map(|p| p.0).fold(0.0, f64::max) * 1.1;
    FigureSpec {
        id: id.into(),
        title: title.into(),
        caption: caption.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        series: vec![
            Series {
                name: "measured".into(),
                x: points.iter().map(|p| p.0).collect(),
                y: points.iter().map(|p| p.1).collect(),
                style: SeriesStyle::Points,
            },
            line(origin, x_max, &format!("LS through origin, {slope_label} = {:.4}", origin.slope), SeriesStyle::Line),
            line(offset, x_max, &format!("LS with offset, {slope_label} = {:.4}", offset.slope), SeriesStyle::Dashed),
        ],
        x_decimals: decimals.0,
        y_decimals: decimals.1,
        heatmap: None,
    }
}

/// A free-decay record with the extrema used by the log decrement marked.
#[allow(clippy::too_many_arguments)]
pub fn decay_figure(
    id: &str,
    title: &str,
    caption: &str,
    y_label: &str,
    time_s: &[f64],
    curves: &[(&str, &[f64], SeriesStyle)],
    analysis: Option<&DecayAnalysis>,
    y_decimals: usize,
) -> FigureSpec {
    let mut series: Vec<Series> = curves
        .iter()
        .map(|(name, y, style)| {
            let (x, y) = decimate(time_s, y);
            Series { name: (*name).into(), x, y, style: *style }
        })
        .collect();
    if let Some(a) = analysis {
        // The extrema that entered at least one pair (k and k+1 of the first swing, k+2 and k+3 of the second).
        let last_used = a.pairs.len() + 3;
        let used = &a.extrema[..last_used.min(a.extrema.len())];
        series.push(Series {
            name: "extrema used for δ".into(),
            x: used.iter().map(|e| e.time_s).collect(),
            y: used.iter().map(|e| e.value).collect(),
            style: SeriesStyle::Markers,
        });
    }
    FigureSpec {
        id: id.into(),
        title: title.into(),
        caption: caption.into(),
        x_label: "time [s]".into(),
        y_label: y_label.into(),
        series,
        x_decimals: 3,
        y_decimals,
        heatmap: None,
    }
}
