//! Calibration results as artifacts: the campaign calibration as tables (the
//! `campaign-calibration` stage's CSVs, at the decimals the data support) and
//! the figure specs (data only; rig-figures draws them) of the calibration
//! plots, Figs. 4.8, 4.10 and 4.14, for the thesis tables and for a campaign.

use crate::campaign::CampaignCalibration;
use crate::signal::DecayAnalysis;
use crate::stats::LineFit;
use rig_types::{FigureSpec, Series, SeriesStyle};
use rig_types::{Table, fmt_fixed};

/// `ci95` for a 95 % interval: column names carry the level actually used.
fn ci_tag(c: &CampaignCalibration) -> String {
    format!("ci{}", fmt_fixed(100.0 * c.settings.confidence, 0))
}

/// Force runs (mean and spread of each run's mV, Table 4.6's ratio) and the
/// least-squares line mV = offset + factor·N with its CI and standard errors.
pub fn force_table(c: &CampaignCalibration) -> Table {
    let ci = ci_tag(c);
    let mut t = Table::new([
        "run".to_string(),
        "load_n".into(),
        "mean_mv".into(),
        "std_mv".into(),
        "samples".into(),
        "ratio_mv_per_n".into(),
        "factor_mv_per_n".into(),
        "factor_stderr_mv_per_n".into(),
        format!("factor_{ci}_low_mv_per_n"),
        format!("factor_{ci}_high_mv_per_n"),
        "offset_mv".into(),
        "offset_stderr_mv".into(),
    ]);
    for r in &c.force_runs {
        t.push([
            r.id.clone(),
            fmt_fixed(r.load_n, 3),
            fmt_fixed(r.mean_mv, 3),
            fmt_fixed(r.std_mv, 3),
            r.samples.to_string(),
            r.ratio_mv_per_n.map(|x| fmt_fixed(x, 3)).unwrap_or_default(),
            String::new(),
            String::new(),
            String::new(),
            String::new(),
            String::new(),
            String::new(),
        ]);
    }
    t.push([
        "mean_of_ratios".to_string(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        fmt_fixed(c.force_ratio_mean_mv_per_n, 3),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
    ]);
    t.push([
        "least_squares_with_offset".to_string(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        fmt_fixed(c.force_factor_mv_per_n, 3),
        fmt_fixed(c.force_factor_mv_per_n_stderr, 3),
        fmt_fixed(c.force_factor_mv_per_n_ci[0], 3),
        fmt_fixed(c.force_factor_mv_per_n_ci[1], 3),
        fmt_fixed(c.force_offset_mv, 3),
        fmt_fixed(c.force_offset_mv_stderr, 3),
    ]);
    t
}

fn fit_cells(f: &LineFit) -> [String; 6] {
    let icpt = |x: f64| if f.through_origin { String::new() } else { fmt_fixed(x, 5) };
    [
        fmt_fixed(f.slope, 5),
        fmt_fixed(f.slope_stderr, 5),
        fmt_fixed(f.slope_ci[0], 5),
        fmt_fixed(f.slope_ci[1], 5),
        icpt(f.intercept),
        icpt(f.intercept_stderr),
    ]
}

/// Static twist runs (Table 4.3's procedure) and the stiffness fits.
pub fn stiffness_table(c: &CampaignCalibration) -> Table {
    let ci = ci_tag(c);
    let mut t = Table::new([
        "run".to_string(),
        "torque_nm".into(),
        "angle_rad".into(),
        "angle_std_rad".into(),
        "k_nm_rad".into(),
        "k_stderr_nm_rad".into(),
        format!("k_{ci}_low_nm_rad"),
        format!("k_{ci}_high_nm_rad"),
        "offset_nm".into(),
        "offset_stderr_nm".into(),
    ]);
    for r in &c.twist_runs {
        let mut row = vec![
            r.id.clone(),
            fmt_fixed(r.torque_nm, 4),
            fmt_fixed(r.angle_rad, 4),
            fmt_fixed(r.angle_std_rad, 4),
            r.stiffness_nm_rad.map(|x| fmt_fixed(x, 4)).unwrap_or_default(),
        ];
        row.extend(std::iter::repeat_n(String::new(), 5));
        t.push(row);
    }
    let origin = LineFit {
        slope: c.stiffness_nm_rad,
        slope_stderr: c.stiffness_nm_rad_stderr,
        slope_ci: c.stiffness_nm_rad_ci,
        intercept: 0.0,
        intercept_stderr: 0.0,
        intercept_ci: [0.0, 0.0],
        residual_std: 0.0,
        dof: 0,
        confidence: c.settings.confidence,
        through_origin: true,
    };
    for (name, f) in
        [("least_squares_through_origin", &origin), ("least_squares_with_offset", &c.stiffness_with_offset)]
    {
        let mut row = vec![name.to_string(), String::new(), String::new(), String::new()];
        let cells = fit_cells(f);
        row.push(cells[0].clone());
        row.extend(cells[1..].iter().cloned());
        t.push(row);
    }
    t
}

/// Per voltage step: pairs used, δ, ξ, ω_d, ω_n (mean ± std over pairs), J1,
/// and the rotor-speed cross-check δ; steps without a measurable decay (0 pairs);
/// then the campaign values (mean ± stderr over steps).
pub fn log_decrement_table(c: &CampaignCalibration) -> Table {
    let mut t = Table::new([
        "run",
        "voltage_v",
        "pairs",
        "log_decrement",
        "log_decrement_spread",
        "damping_ratio",
        "damping_ratio_spread",
        "damped_rad_s",
        "damped_rad_s_spread",
        "natural_rad_s",
        "natural_rad_s_spread",
        "rotor_inertia_kgm2",
        "rotor_inertia_kgm2_spread",
        "speed_log_decrement",
        "speed_pairs",
    ]);
    for s in &c.steps {
        let a = &s.twist;
        t.push([
            s.id.clone(),
            fmt_fixed(s.voltage_v, 1),
            a.pairs.len().to_string(),
            fmt_fixed(a.log_decrement_mean, 4),
            fmt_fixed(a.log_decrement_std, 4),
            fmt_fixed(a.damping_ratio_mean, 5),
            fmt_fixed(a.damping_ratio_std, 5),
            fmt_fixed(a.damped_rad_s_mean, 4),
            fmt_fixed(a.damped_rad_s_std, 4),
            fmt_fixed(a.natural_rad_s_mean, 4),
            fmt_fixed(a.natural_rad_s_std, 4),
            fmt_fixed(s.rotor_inertia_kgm2, 5),
            String::new(),
            s.rotor_speed.as_ref().map(|r| fmt_fixed(r.log_decrement_mean, 4)).unwrap_or_default(),
            s.rotor_speed.as_ref().map(|r| r.pairs.len().to_string()).unwrap_or_default(),
        ]);
    }
    for k in &c.steps_without_decay {
        let mut row = vec![k.id.clone(), fmt_fixed(k.voltage_v, 1), "0".to_string()];
        row.extend(std::iter::repeat_n(String::new(), 12));
        t.push(row);
    }
    t.push([
        "campaign (mean, stderr over steps)".to_string(),
        String::new(),
        c.steps.iter().map(|s| s.twist.pairs.len()).sum::<usize>().to_string(),
        fmt_fixed(c.log_decrement, 4),
        fmt_fixed(c.log_decrement_stderr, 4),
        fmt_fixed(c.damping_ratio, 5),
        fmt_fixed(c.damping_ratio_stderr, 5),
        fmt_fixed(c.damped_frequency_rad_s, 4),
        fmt_fixed(c.damped_frequency_rad_s_stderr, 4),
        fmt_fixed(c.natural_frequency_rad_s, 4),
        fmt_fixed(c.natural_frequency_rad_s_stderr, 4),
        fmt_fixed(c.rotor_inertia_kgm2, 5),
        fmt_fixed(c.rotor_inertia_kgm2_stderr, 5),
        String::new(),
        String::new(),
    ]);
    t
}

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
