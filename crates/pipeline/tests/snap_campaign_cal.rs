//! Snapshot of every output of the `campaign-calibration` stage.

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("campaign-calibration");
}
