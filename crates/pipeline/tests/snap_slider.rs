//! Snapshot of the `slider` stage outputs (derived numbers only; skipped without ../shared).

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("slider");
}
