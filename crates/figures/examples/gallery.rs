//! Writes one figure of each kind as PNG and SVG into the directory given as
//! the first argument, to look at by eye: `cargo run -p rig-figures --example gallery -- /tmp/g`.

use rig_types::{FigureSpec, Heatmap, Series, SeriesStyle};
use std::time::Instant;

fn main() {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).expect("usage: gallery OUT_DIR"));
    std::fs::create_dir_all(&dir).expect("creating the output directory");
    let t: Vec<f64> = (0..2000).map(|i| i as f64 * 0.005).collect();
    let y: Vec<f64> = t.iter().map(|t| (-0.3 * t).exp() * (6.0 * t).cos() * 40.0 + 60.0).collect();
    let mut y_gap = y.iter().map(|v| v - 10.0).collect::<Vec<_>>();
    y_gap[700..760].iter_mut().for_each(|v| *v = f64::NAN);
    let peaks_t: Vec<f64> = (0..9).map(|k| k as f64 * std::f64::consts::PI / 3.0).collect();
    let peaks_y: Vec<f64> = peaks_t.iter().map(|t| (-0.3 * t).exp() * 40.0 + 60.0).collect();
    let line = FigureSpec {
        id: "gallery-line".into(),
        title: "Fig. 4.10 (demo): free decay of rotor 1".into(),
        caption: "demo".into(),
        x_label: "time (s)".into(),
        y_label: "rotor speed Ω1 (rad/s)".into(),
        series: vec![
            Series { name: "measured".into(), x: t.clone(), y: y.clone(), style: SeriesStyle::Line },
            Series { name: "model (gap at 3.5 s)".into(), x: t.clone(), y: y_gap, style: SeriesStyle::Dashed },
            Series { name: "peaks".into(), x: peaks_t, y: peaks_y, style: SeriesStyle::Markers },
            Series {
                name: "samples".into(),
                x: t.iter().step_by(40).copied().collect(),
                y: y.iter().step_by(40).map(|v| v + 5.0).collect(),
                style: SeriesStyle::Points,
            },
        ],
        x_decimals: 3,
        y_decimals: 2,
        heatmap: None,
    };
    let xs: Vec<f64> = (0..40).map(|i| 50.0 + 10.0 * i as f64).collect();
    let ys: Vec<f64> = (0..30).map(|j| 5.0 + 2.0 * j as f64).collect();
    let z = ys.iter().map(|n| xs.iter().map(|w| ((n / 60.0) - (w / 500.0)).max(0.0)).collect()).collect();
    let heat = FigureSpec {
        id: "gallery-heat".into(),
        title: "Fig. 4.16 (demo): stick-slip severity".into(),
        caption: "demo".into(),
        x_label: "motor speed set-point (rpm)".into(),
        y_label: "normal force N (N)".into(),
        series: vec![Series {
            name: "measured operating points".into(),
            x: vec![100.0, 250.0, 400.0],
            y: vec![20.0, 40.0, 60.0],
            style: SeriesStyle::Markers,
        }],
        x_decimals: 0,
        y_decimals: 1,
        heatmap: Some(Heatmap { x: xs, y: ys, z, z_label: "severity (Ω max − Ω min)/Ω mean".into() }),
    };
    for spec in [line, heat] {
        let start = Instant::now();
        let svg = rig_figures::render_svg(&spec).expect("svg");
        let svg_ms = start.elapsed().as_millis();
        let start = Instant::now();
        let png = rig_figures::render_png(&spec).expect("png");
        let png_ms = start.elapsed().as_millis();
        let start = Instant::now();
        let _ = rig_figures::render_rgb(&spec).expect("rgb");
        let rgb_ms = start.elapsed().as_millis();
        std::fs::write(dir.join(format!("{}.svg", spec.id)), svg).expect("write svg");
        std::fs::write(dir.join(format!("{}.png", spec.id)), png).expect("write png");
        println!("{}: svg {svg_ms} ms, png {png_ms} ms (of which rgb {rgb_ms} ms)", spec.id);
    }
}
