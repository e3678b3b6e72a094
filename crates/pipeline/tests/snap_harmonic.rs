//! Snapshot of the `harmonic` stage outputs.

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("harmonic");
}

/// Developer aid, ignored: runs only this stage on an out dir that already
/// holds its upstream outputs (env RIG_DEV_OUT); see `testing::dev_run_only`.
#[test]
#[ignore]
fn dev_run_only() {
    let Ok(out) = std::env::var("RIG_DEV_OUT") else { return };
    rig_pipeline::testing::dev_run_only("harmonic", std::path::Path::new(&out)).unwrap();
}
