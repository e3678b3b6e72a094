//! Renders a small spec of each kind and checks what a reader relies on:
//! labels present, gaps in lines, legends, deterministic pixels and text.

use rig_figures::{
    FigureError, SIZE_PX, render_png, render_rgb, render_sheet_rgb, render_sheet_svg, render_svg, series_csv,
    sheet_csv, sheet_size_px,
};
use rig_types::{AxisScale, FigureSpec, Heatmap, MarkerShape, Panel, Series, SeriesStyle, Sheet, band};

fn series(name: &str, style: SeriesStyle, x: &[f64], y: &[f64]) -> Series {
    Series { name: name.into(), x: x.to_vec(), y: y.to_vec(), style }
}

fn spec(id: &str, series: Vec<Series>, heatmap: Option<Heatmap>) -> FigureSpec {
    FigureSpec {
        id: id.into(),
        title: format!("Test figure {id}"),
        caption: "A test.".into(),
        x_label: "time (s)".into(),
        y_label: "rotor speed (rad/s)".into(),
        series,
        x_decimals: 3,
        y_decimals: 2,
        heatmap,
    }
}

/// A decaying oscillation sampled at 50 points, like a log-decrement record.
fn decay() -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.02).collect();
    let y = t.iter().map(|t| (-2.0 * t).exp() * (12.0 * t).cos()).collect();
    (t, y)
}

fn all_kinds() -> Vec<FigureSpec> {
    let (t, y) = decay();
    let peaks_t = [0.0, 0.52, 1.04 - 0.06];
    let peaks_y: Vec<f64> = peaks_t.iter().map(|t: &f64| (-2.0 * t).exp()).collect();
    let heat = Heatmap {
        x: vec![1.0, 2.0, 3.0],
        y: vec![10.0, 20.0],
        z: vec![vec![0.0, 0.5, 1.0], vec![f64::NAN, 1.5, 2.0]],
        z_label: "severity (-)".into(),
    };
    vec![
        spec("line", vec![series("measured", SeriesStyle::Line, &t, &y)], None),
        spec("dashed", vec![series("model", SeriesStyle::Dashed, &t, &y)], None),
        spec("points", vec![series("samples", SeriesStyle::Points, &t, &y)], None),
        spec("markers", vec![series("peaks", SeriesStyle::Markers, &peaks_t, &peaks_y)], None),
        spec("heat", vec![series("operating points", SeriesStyle::Markers, &[1.0, 3.0], &[10.0, 20.0])], Some(heat)),
    ]
}

/// FNV-1a 64: a dependency-free fingerprint of the RGB buffer.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

#[test]
fn every_kind_renders_to_svg_png_and_rgb() {
    for s in all_kinds() {
        let svg = render_svg(&s).unwrap();
        assert!(svg.starts_with("<svg"), "{}: not SVG", s.id);
        for text in [s.title.as_str(), "time (s)", "rotor speed (rad/s)", s.series[0].name.as_str()] {
            assert!(svg.contains(text), "{}: SVG lacks {text:?}", s.id);
        }
        let png = render_png(&s).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{}: not PNG", s.id);
        let rgb = render_rgb(&s).unwrap();
        assert_eq!(rgb.len(), (SIZE_PX.0 * SIZE_PX.1 * 3) as usize);
        // Something other than white background was drawn.
        assert!(rgb.iter().filter(|&&b| b < 128).count() > 1000, "{}: bitmap nearly blank", s.id);
    }
}

#[test]
fn heat_map_has_a_colour_bar_with_its_label() {
    let s = &all_kinds()[4];
    let svg = render_svg(s).unwrap();
    assert!(svg.contains("severity (-)"));
    // 5 finite cells + 100 colour-bar steps are filled rectangles.
    let filled_rects = svg.matches("<rect").count();
    assert!(filled_rects >= 105, "{filled_rects} rects");
}

#[test]
fn nan_splits_a_line_into_two_pieces() {
    let x = [0.0, 1.0, 2.0, 3.0, 4.0];
    let whole = spec("whole", vec![series("s", SeriesStyle::Line, &x, &[0.0, 1.0, 0.0, 1.0, 0.0])], None);
    let gap = spec("gap", vec![series("s", SeriesStyle::Line, &x, &[0.0, 1.0, f64::NAN, 1.0, 0.0])], None);
    let lines = |s: &FigureSpec| render_svg(s).unwrap().matches("<polyline").count();
    assert_eq!(lines(&gap), lines(&whole) + 1);
}

#[test]
fn rendering_is_deterministic() {
    for s in all_kinds() {
        assert_eq!(render_svg(&s).unwrap(), render_svg(&s).unwrap(), "{}", s.id);
        assert_eq!(fnv1a(&render_rgb(&s).unwrap()), fnv1a(&render_rgb(&s).unwrap()), "{}", s.id);
        assert_eq!(render_png(&s).unwrap(), render_png(&s).unwrap(), "{}", s.id);
    }
}

#[test]
fn pixels_are_pinned() {
    // Pins plotters' rasterisation of the embedded font and our layout; a
    // change here is a visible change of every figure: look at the PNGs.
    let hashes: Vec<String> =
        all_kinds().iter().map(|s| format!("{}: {:016x}", s.id, fnv1a(&render_rgb(s).unwrap()))).collect();
    insta::assert_snapshot!(hashes.join("\n"));
}

#[test]
fn small_line_figure_svg_is_pinned() {
    let s = spec(
        "small",
        vec![
            series("measured", SeriesStyle::Line, &[0.0, 1.0, 2.0], &[0.0, 2.0, 1.0]),
            series("model", SeriesStyle::Dashed, &[0.0, 2.0], &[0.5, 1.5]),
        ],
        None,
    );
    insta::assert_snapshot!(render_svg(&s).unwrap());
    insta::assert_snapshot!(series_csv(&s));
}

#[test]
fn mismatched_lengths_are_a_spec_error() {
    let s = spec("bad", vec![series("s", SeriesStyle::Line, &[0.0, 1.0], &[0.0])], None);
    match render_svg(&s) {
        Err(FigureError::Spec { id, reason }) => {
            assert_eq!(id, "bad");
            assert!(reason.contains("2 x values but 1 y values"), "{reason}");
        }
        other => panic!("expected a spec error, got {other:?}"),
    }
    let bad_heat = Heatmap { x: vec![1.0, 2.0], y: vec![1.0], z: vec![vec![1.0]], z_label: "z".into() };
    assert!(matches!(render_png(&spec("badheat", vec![], Some(bad_heat))), Err(FigureError::Spec { .. })));
}

#[test]
fn empty_figure_still_draws_axes() {
    let svg = render_svg(&spec("empty", vec![], None)).unwrap();
    assert!(svg.contains("time (s)"));
}

fn panel(spec: FigureSpec, x_scale: AxisScale) -> Panel {
    Panel { spec, x_scale }
}

#[test]
fn a_sheet_draws_every_panel_and_grows_with_its_grid() {
    let (t, y) = decay();
    let mk = |title: &str| {
        let mut s = spec("p", vec![series("measured", SeriesStyle::Line, &t, &y)], None);
        s.title = title.into();
        s
    };
    let sheet = Sheet {
        id: "sheet".into(),
        title: "Sheet title".into(),
        caption: String::new(),
        columns: 2,
        panels: ["(a) one", "(b) two", "(c) three"].iter().map(|t| panel(mk(t), AxisScale::Linear)).collect(),
    };
    let svg = render_sheet_svg(&sheet).unwrap();
    for text in ["Sheet title", "(a) one", "(b) two", "(c) three"] {
        assert!(svg.contains(text), "SVG lacks {text:?}");
    }
    // Panels share their series, so the legend is drawn once, below the grid.
    assert_eq!(svg.matches(">\nmeasured\n<").count() + svg.matches(">measured<").count(), 1, "one shared legend entry");
    let (w, h) = sheet_size_px(&sheet);
    assert_eq!(render_sheet_rgb(&sheet).unwrap().len(), (w * h * 3) as usize);
    let two_rows = h;
    let one_row = sheet_size_px(&Sheet { panels: sheet.panels[..2].to_vec(), ..sheet.clone() }).1;
    assert!(two_rows > one_row, "{two_rows} vs {one_row}");
    let csv = sheet_csv(&sheet);
    assert!(csv.starts_with("panel,series,x,y\n(a) one,measured,0.000,1.00\n"), "{}", &csv[..60]);
}

#[test]
fn a_log_axis_skips_non_positive_x_and_keeps_decades() {
    let s = spec("log", vec![series("H", SeriesStyle::Line, &[0.0, 0.1, 1.0, 10.0], &[1.0, 2.0, 3.0, 4.0])], None);
    let sheet = Sheet {
        id: "log".into(),
        title: "t".into(),
        caption: String::new(),
        columns: 1,
        panels: vec![panel(s, AxisScale::Log10)],
    };
    let svg = render_sheet_svg(&sheet).unwrap();
    for tick in [">\n0.1\n<", ">\n1\n<", ">\n10\n<"] {
        assert!(svg.contains(tick), "no decade tick {tick:?}");
    }
}

#[test]
fn new_styles_render_and_hatching_needs_a_heat_map() {
    let heat = Heatmap {
        x: vec![1.0, 2.0, 3.0],
        y: vec![10.0, 20.0],
        z: vec![vec![0.0, 0.5, 1.0], vec![0.2, 1.5, 2.0]],
        z_label: "severity (-)".into(),
    };
    let open = SeriesStyle::Marker { shape: MarkerShape::TriangleDown, filled: false };
    let s = spec(
        "styles",
        vec![
            series("bistable", SeriesStyle::HatchCells, &[2.0, 3.0], &[20.0, 20.0]),
            series("down", open, &[1.0], &[10.0]),
        ],
        Some(heat),
    );
    let svg = render_svg(&s).unwrap();
    // Outside legend: both names are drawn below the plot.
    assert!(svg.contains("bistable") && svg.contains("down"));
    let no_heat = spec("nh", vec![series("r", SeriesStyle::HatchCells, &[1.0], &[1.0])], None);
    match render_svg(&no_heat) {
        Err(FigureError::Spec { reason, .. }) => assert!(reason.contains("no heat map"), "{reason}"),
        other => panic!("expected a spec error, got {other:?}"),
    }
    let b = band("spread", &[0.0, 1.0, 2.0], &[0.0, 0.5, 0.2], &[1.0, 1.5, 1.2]);
    let with_band = spec("band", vec![b, series("mean", SeriesStyle::Line, &[0.0, 1.0, 2.0], &[0.5, 1.0, 0.7])], None);
    let svg = render_svg(&with_band).unwrap();
    assert!(svg.contains("<polygon"), "band drawn as a polygon");
}
