//! Snapshot of the `confusion` stage outputs (seeded hidden-effect campaigns).

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("confusion");
}
