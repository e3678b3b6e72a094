//! Snapshot of every output of the `sweeps` stage.

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("sweeps");
}
