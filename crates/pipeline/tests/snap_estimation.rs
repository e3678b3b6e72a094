//! Snapshot of every output of the `estimation` stage.

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("estimation");
}
