//! Another lab's protocol runs end to end: a campaign the virtual rig records
//! at another sample rate (1 kHz, 250 Hz), with 14 other operating points,
//! 30 s runs, a 3 s ramp and other run ids, goes through the runner (what
//! `cargo xtask reproduce --campaign DIR` runs) with every campaign stage
//! succeeding. Windows are in seconds and the protocol is read from the
//! campaign, so nothing here is tuned to the shipped 500 Hz, 40 s, 2 s ramp.
//!
//! The sweeps stage's maps and diagrams are simulations on a grid that does
//! not depend on the campaign's protocol; their grids are coarsened here
//! (4 × 3 map points, 4 diagram points) only to keep the test's time down.

use rig_pipeline::Runner;
use rig_pipeline::testing::workspace_root;
use rig_virtual_rig::{Protocol, draw_rig, generate, write_campaign};
use std::path::PathBuf;

/// The campaign stages (their upstream, thesis-tables, runs first).
const STAGES: [&str; 7] =
    ["campaign-calibration", "estimation", "simulation", "sweeps", "spectra", "harmonic", "diagnosis"];

fn other_lab(sample_rate_hz: f64) -> Protocol {
    let mut op_points = Vec::new();
    for rpm in [12.0, 28.0, 42.0, 60.0, 78.0, 100.0, 120.0] {
        for n in [3.0, 8.0] {
            op_points.push((rpm, n));
        }
    }
    Protocol {
        sample_rate_hz,
        force_loads_n: vec![1.0, 2.5, 4.0, 5.5],
        twist_torques_nm: vec![0.1, 0.2, 0.3, 0.4],
        step_voltages_v: vec![7.0, 9.0, 11.0],
        step_duration_s: 15.0,
        op_points,
        op_duration_s: 30.0,
        ramp_s: 3.0,
    }
}

/// New ids for every run (the file follows the id).
fn rename(id: &str) -> String {
    let (kind, n) = id.rsplit_once('-').unwrap_or((id, ""));
    let kind = match kind {
        "op" => "point",
        "cal" => "load",
        "twist" => "torque",
        "step" => "volt",
        k => k,
    };
    format!("lab2-{kind}-{n}")
}

fn run_protocol(sample_rate_hz: f64, seed: u64) {
    let truth = draw_rig(seed);
    let mut c = generate("other-lab", &truth, &other_lab(sample_rate_hz), seed).expect("generate");
    for r in &mut c.runs {
        r.id = rename(&r.id);
        r.file = PathBuf::from(format!("runs/{}.csv", r.id));
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let campaign = dir.path().join("campaign");
    write_campaign(&campaign, &c).expect("write campaign");
    let out = dir.path().join("out");
    let mut runner = Runner::new(&workspace_root().join("pipeline.toml"))
        .expect("pipeline.toml")
        .campaign(&campaign)
        .out(&out)
        .only(&STAGES)
        .jobs(2);
    for (key, value) in [("map_rpm_points", "4"), ("map_force_points", "3"), ("diagram_points", "4")] {
        runner = runner.set_param("sweeps", key, value).expect("sweeps param");
    }
    let report = runner.run().expect("the run starts");
    let summary = report.summary(false);
    if let Err(e) = report.into_result() {
        panic!("{sample_rate_hz} Hz campaign: {e:#}\n{summary}");
    }
    for f in ["data/rig-params.json", "diagnosis.json", "estimation.md", "tables/campaign-simulation-misfit.csv"] {
        assert!(out.join(f).is_file(), "{sample_rate_hz} Hz campaign: {f} missing\n{summary}");
    }
}

#[test]
fn a_1khz_campaign_of_another_protocol_runs_end_to_end() {
    run_protocol(1000.0, 2601);
}

#[test]
fn a_250hz_campaign_of_another_protocol_runs_end_to_end() {
    run_protocol(250.0, 2602);
}
