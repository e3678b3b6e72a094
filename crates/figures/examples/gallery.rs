//! Writes one figure of each kind as PNG and SVG into the directory given as
//! the first argument, to look at by eye: `cargo run -p rig-figures --example gallery -- /tmp/g`.

use rig_types::{AxisScale, FigureSpec, Heatmap, MarkerShape, Panel, Series, SeriesStyle, Sheet, band, figure};
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
        series: vec![
            Series {
                name: "bistable (up ≠ down)".into(),
                x: (0..12).map(|i| 200.0 + 10.0 * i as f64).collect(),
                y: (0..12).map(|i| 30.0 + 2.0 * (i / 3) as f64).collect(),
                style: SeriesStyle::HatchCells,
            },
            Series {
                name: "measured: stick-slip".into(),
                x: vec![100.0, 250.0, 400.0],
                y: vec![20.0, 40.0, 60.0],
                style: SeriesStyle::Marker { shape: MarkerShape::Circle, filled: false },
            },
            Series {
                name: "thesis: stick-slip".into(),
                x: vec![150.0, 300.0],
                y: vec![25.0, 45.0],
                style: SeriesStyle::Marker { shape: MarkerShape::Square, filled: false },
            },
        ],
        x_decimals: 0,
        y_decimals: 1,
        heatmap: Some(Heatmap { x: xs, y: ys, z, z_label: "severity (Ω max − Ω min)/Ω mean".into() }),
    };
    // A sheet: FRF magnitude in dB over log frequency above its coherence,
    // and a bifurcation-style panel with up/down markers and a shaded band.
    let f: Vec<f64> = (0..300).map(|i| 0.05 * 1.02f64.powi(i)).collect();
    let mag_db: Vec<f64> = f
        .iter()
        .map(|f| -20.0 * (((1.0 - (f / 0.5f64).powi(2)).powi(2) + (0.1 * f / 0.5).powi(2)).sqrt()).log10())
        .collect();
    let coh: Vec<f64> = f.iter().map(|f| 1.0 - 0.5 * (-(f - 0.5f64).powi(2) * 40.0).exp()).collect();
    let mag = figure(
        "m",
        "(a) magnitude",
        "",
        ("frequency [Hz]", 3),
        ("|H| [dB]", 1),
        vec![
            band(
                "95 % interval",
                &f,
                &mag_db.iter().map(|v| v - 2.0).collect::<Vec<_>>(),
                &mag_db.iter().map(|v| v + 2.0).collect::<Vec<_>>(),
            ),
            Series { name: "H1 estimate".into(), x: f.clone(), y: mag_db, style: SeriesStyle::Line },
        ],
    );
    let cohp = figure(
        "c",
        "(b) coherence",
        "",
        ("frequency [Hz]", 3),
        ("γ² [-]", 3),
        vec![Series { name: "coherence".into(), x: f.clone(), y: coh, style: SeriesStyle::Line }],
    );
    let w: Vec<f64> = (0..30).map(|i| 10.0 + 4.0 * i as f64).collect();
    let up: Vec<f64> = w.iter().map(|w| if *w < 70.0 { 0.0 } else { w * 0.9 }).collect();
    let down: Vec<f64> = w.iter().map(|w| if *w < 50.0 { 0.0 } else { w * 0.9 }).collect();
    let bif = |title: &str| {
        figure(
            "b",
            title,
            "",
            ("motor set-point [rpm]", 1),
            ("rotor speed min [rpm]", 1),
            vec![
                Series {
                    name: "sweep up".into(),
                    x: w.clone(),
                    y: up.clone(),
                    style: SeriesStyle::Marker { shape: MarkerShape::TriangleUp, filled: true },
                },
                Series {
                    name: "sweep down".into(),
                    x: w.clone(),
                    y: down.clone(),
                    style: SeriesStyle::Marker { shape: MarkerShape::TriangleDown, filled: false },
                },
                band("bistable", &[50.0, 70.0], &[0.0, 0.0], &[120.0, 120.0]),
            ],
        )
    };
    let sheets = [
        Sheet {
            id: "gallery-frf".into(),
            title: "Fig. 4.26a (demo): frequency response".into(),
            caption: "demo".into(),
            columns: 1,
            panels: vec![
                Panel { spec: mag, x_scale: AxisScale::Log10 },
                Panel { spec: cohp, x_scale: AxisScale::Log10 },
            ],
        },
        Sheet {
            id: "gallery-grid".into(),
            title: "Fig. 4.18 (demo): one panel per model".into(),
            caption: "demo".into(),
            columns: 3,
            panels: ["thesis", "rig", "extended", "a", "b"]
                .iter()
                .map(|t| Panel { spec: bif(t), x_scale: AxisScale::Linear })
                .collect(),
        },
    ];
    for sh in &sheets {
        std::fs::write(dir.join(format!("{}.svg", sh.id)), rig_figures::render_sheet_svg(sh).expect("svg"))
            .expect("write svg");
        std::fs::write(dir.join(format!("{}.png", sh.id)), rig_figures::render_sheet_png(sh).expect("png"))
            .expect("write png");
    }
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
