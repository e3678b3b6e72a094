//! Snapshot of the `diagnosis` stage outputs on the shipped campaign.

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("diagnosis");
}
