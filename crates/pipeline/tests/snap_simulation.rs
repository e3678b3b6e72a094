//! Snapshot of every output of the `simulation` stage.

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("simulation");
}
