//! Snapshot of every output of the `thesis-tables` stage.

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("thesis-tables");
}
