//! The drawing's tests.

use super::*;

use rig_types::{Panel, series};

/// Panel widths a log axis is drawn at: a single figure, a 2-column and a 3-column sheet.
const WIDTHS: [u32; 3] = [900, 560, 320];

/// Ranges of the workspace's log axes (battery sizes, FRF band) and harder ones.
const RANGES: [(f64, f64); 10] = [
    (0.004, 0.25),
    (0.008, 0.45),
    (0.0085, 0.32),
    (0.1, 10.0),
    (0.05, 50.0),
    (0.3, 0.45),
    (1.12, 1.9),
    (20.0, 2000.0),
    (1e-3, 1e3),
    (1e-6, 1e6),
];

#[test]
fn log_axis_labels_never_overlap_at_any_panel_size() {
    crate::ensure_font().unwrap();
    for w in WIDTHS {
        let look = Look::for_width(w);
        let font = (FONT, look.label).into_font();
        let axis_px = plot_width_px(w, look) as f64;
        for (lo, hi) in RANGES {
            let t = log_x_ticks(w, (lo, hi), look);
            assert!(!t.labelled.is_empty(), "{w} px, {lo}..{hi}: no label");
            let extents: Vec<(f64, f64, &str)> = t
                .labelled
                .iter()
                .map(|(v, s)| {
                    let x = crate::log_axis::position_px(*v, lo, hi, axis_px);
                    let half = font.box_size(s).unwrap().0 as f64 / 2.0;
                    (x - half, x + half, s.as_str())
                })
                .collect();
            for p in extents.windows(2) {
                assert!(p[0].1 < p[1].0, "{w} px, {lo}..{hi}: {:?} overlaps {:?}", p[0], p[1]);
            }
            let decades = hi.log10() - lo.log10();
            let mantissas: Vec<char> =
                t.labelled.iter().map(|(_, s)| s.trim_start_matches(['0', '.']).chars().next().unwrap()).collect();
            if decades >= crate::log_axis::LABEL_2_5_BELOW_DECADES {
                assert!(mantissas.iter().all(|&c| c == '1'), "{w} px, {lo}..{hi}: {:?}", t.labelled);
            }
            // Minor lines never crowd into a grey block.
            let mut lines: Vec<f64> = t.labelled.iter().map(|l| l.0).chain(t.minor.iter().copied()).collect();
            lines.sort_by(f64::total_cmp);
            for p in lines.windows(2) {
                let gap = crate::log_axis::position_px(p[1], lo, hi, axis_px)
                    - crate::log_axis::position_px(p[0], lo, hi, axis_px);
                assert!(
                    gap >= crate::log_axis::MINOR_MIN_SPACING_PX - 1e-9,
                    "{w} px, {lo}..{hi}: lines {p:?} {gap} px apart"
                );
            }
        }
    }
}

#[test]
fn plot_width_is_the_one_plotters_draws() {
    crate::ensure_font().unwrap();
    for w in WIDTHS {
        let look = Look::for_width(w);
        let mut buf = vec![0u8; (w * 400 * 3) as usize];
        let root = BitMapBackend::with_buffer(&mut buf, (w, 400)).into_drawing_area();
        let chart = ChartBuilder::on(&root)
            .caption("t", (FONT, look.title))
            .margin(look.margin)
            .x_label_area_size(look.x_area)
            .y_label_area_size(look.y_area)
            .build_cartesian_2d((0.1..10.0).log_scale(), 0.0..1.0)
            .unwrap();
        assert_eq!(chart.plotting_area().dim_in_pixel().0, plot_width_px(w, look), "{w} px panel");
    }
}

#[test]
fn a_log_panel_draws_its_own_ticks_only() {
    crate::ensure_font().unwrap();
    let spec = rig_types::figure(
        "log",
        "log",
        "",
        ("size", 3),
        ("p", 2),
        vec![series("p", vec![0.005, 0.01, 0.02, 0.2], vec![0.1, 0.5, 1.0, 1.0], SeriesStyle::Line)],
    );
    let sheet = Sheet {
        id: "s".into(),
        title: "s".into(),
        caption: String::new(),
        columns: 2,
        panels: vec![Panel { spec: spec.clone(), x_scale: AxisScale::Log10 }; 2],
    };
    let plan = Plan::new(&spec, AxisScale::Log10).unwrap();
    let ticks = log_x_ticks(560, plan.x_range, Look::for_width(560));
    let svg = crate::render_sheet_svg(&sheet).unwrap();
    for (_, label) in &ticks.labelled {
        assert_eq!(svg.matches(&format!(">\n{label}\n<")).count(), 2, "{label} once per panel");
    }
    // Nothing else is printed along x: plotters' own log labels (0.03, 0.04 …) are gone.
    for stray in ["0.03", "0.04", "0.06", "0.07", "0.08", "0.09"] {
        assert!(!svg.contains(&format!(">\n{stray}\n<")), "{stray} printed");
    }
}
