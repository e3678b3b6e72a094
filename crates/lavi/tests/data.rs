//! The reader and the glitch repair as the study uses them (rig_lavi::data),
//! on synthetic recordings, and on run 175 when ../shared holds it.

use rig_lavi::StudyParams;
use rig_lavi::data::{Split, prepare, windows};
use std::path::PathBuf;

fn params() -> StudyParams {
    StudyParams {
        window_start_s: 5.0,
        window_end_s: 7.0,
        heldout_starts_s: vec![2.0],
        heldout_length_s: 2.0,
        warmup_s: 1.0,
        cutoff_hz: 10.0,
        transition_hz: 2.0,
        glitch_median_window: 101,
        glitch_threshold_rpm: 30.0,
        glitch_floor_rpm: 0.0,
        glitch_dilate: 10,
        slip_speed_rpm: 5.0,
        bins: 20,
        stick_speed_rpm: 5.0,
        substeps: 5,
        fit_evaluations: 50,
        drive_ref_window_s: 2.0,
        selection: rig_types::contract::SelectionRule { min_relative_gain: 0.05 },
        significance: 0.05,
        adequacy_threshold: 1.0,
        figure_window_start_s: 2.0,
    }
}

/// 8 s at 1 kHz: top speed 80 rpm with two sensor dips to −263 rpm (20 samples each).
fn write_csv(name: &str, corrupt_line: Option<usize>) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let mut s = String::from("time_s,top_speed_rpm,bit_speed_rpm,bit_torque_nm,wob_n\n");
    for i in 0..8000 {
        let t = i as f64 / 1000.0;
        let top = if (2000..2020).contains(&i) || (6000..6020).contains(&i) { -263.0 } else { 80.0 };
        let bit = 80.0 + 60.0 * (std::f64::consts::TAU * 2.0 * t).sin();
        if corrupt_line == Some(i + 2) {
            s.push_str(&format!("{t:.3},{top},abc,1.0,500\n"));
        } else {
            s.push_str(&format!(
                "{t:.3},{top},{bit:.4},{:.4},500\n",
                1.0 + 0.1 * (std::f64::consts::TAU * 2.0 * t).cos()
            ));
        }
    }
    std::fs::write(&path, s).unwrap();
    path
}

#[test]
fn glitches_are_found_and_bridged() {
    let path = write_csv("lavi-glitch.csv", None);
    let (rec, d) = prepare(&path, &params()).unwrap();
    assert_eq!(rec.len(), 8000);
    assert_eq!(d.glitches.runs, 2, "{:?}", d.glitches);
    // Each dip of 20 samples widened by 10 each side.
    assert_eq!(d.glitches.samples, 80, "{:?}", d.glitches);
    assert!(d.top_repaired_rpm.iter().all(|v| (v - 80.0).abs() < 1e-9));
    assert!(d.top_rpm[1000..7000].iter().all(|v| (v - 80.0).abs() < 0.5));
}

#[test]
fn a_bad_cell_is_refused_with_file_and_line() {
    let path = write_csv("lavi-bad.csv", Some(5));
    let e = prepare(&path, &params()).unwrap_err().to_string();
    assert!(e.contains("lavi-bad.csv") && e.contains('5'), "{e}");
}

#[test]
fn windows_are_checked_and_ordered() {
    let path = write_csv("lavi-windows.csv", None);
    let (_, d) = prepare(&path, &params()).unwrap();
    let w = windows(&d, &params()).unwrap();
    assert_eq!(
        (w[0].label.as_str(), w[0].split, w[1].label.as_str(), w[1].split),
        ("5-7", Split::Train, "2-4", Split::Heldout)
    );
    assert_eq!((w[1].span.clone(), w[1].window.clone()), (1000..4000, 1000..3000));
    let overlap = StudyParams { heldout_starts_s: vec![4.0], ..params() };
    assert!(windows(&d, &overlap).unwrap_err().to_string().contains("overlaps the calibration window"));
    let outside = StudyParams { heldout_starts_s: vec![0.5], ..params() };
    assert!(windows(&d, &outside).unwrap_err().to_string().contains("inside the record"));
}

#[test]
fn run_175_reads_and_repairs() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/ufrj-lavi-2018/run-175.csv");
    if !path.exists() {
        println!("skipped: {} is absent (../shared not mounted)", path.display());
        return;
    }
    let p = StudyParams {
        window_start_s: 37.0,
        window_end_s: 41.0,
        heldout_starts_s: vec![4.0, 45.0],
        heldout_length_s: 4.0,
        warmup_s: 3.0,
        ..params()
    };
    let (rec, d) = prepare(&path, &p).unwrap();
    assert_eq!(rec.len(), 59_000);
    // The top speed dips to about −263 rpm; after the repair nothing is below the floor.
    assert!(rec.top_speed_rpm.iter().any(|v| *v < -200.0));
    assert!(d.glitches.runs > 0 && d.top_repaired_rpm.iter().all(|v| *v >= 0.0), "{:?}", d.glitches);
    assert_eq!(windows(&d, &p).unwrap().len(), 3);
}
