//! Snapshot of the `lavi` stage outputs (derived numbers only; skipped without ../shared).

#[test]
fn snap() {
    rig_pipeline::testing::snapshot_stage("lavi");
}

/// Developer aid, ignored: runs only this stage on an out dir that already
/// holds its upstream outputs (env RIG_DEV_OUT) and writes what it staged to
/// RIG_DEV_OUT/dev-lavi/, without re-running (or re-checking) upstream stages.
#[test]
#[ignore]
fn dev_run_only() {
    let Ok(out) = std::env::var("RIG_DEV_OUT") else { return };
    let root = rig_pipeline::testing::workspace_root();
    let text = std::fs::read_to_string(root.join("pipeline.toml")).unwrap();
    let cfg: toml::Table = toml::from_str(&text).unwrap();
    let stages = cfg["stage"].as_array().unwrap();
    let decl = stages.iter().find(|s| s["name"].as_str() == Some("lavi")).unwrap();
    let params = decl.get("params").and_then(|p| p.as_table()).cloned().unwrap_or_default();
    let out = std::path::PathBuf::from(out);
    let shared = root.join("../shared");
    let mut ctx = rig_pipeline::StageCtx::new(
        "lavi",
        &root.join("data/emulated-rig-2026"),
        &root.join("data/thesis"),
        shared.exists().then_some(shared.as_path()),
        &out,
        params,
    );
    rig_pipeline::stages::lookup("lavi").unwrap()(&mut ctx).unwrap();
    for (rel, bytes) in ctx.into_staged() {
        let path = out.join("dev-lavi").join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
}
