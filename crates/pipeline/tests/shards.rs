//! A severity map run as a job array (`--set sweeps.shard=i/n`, one out dir
//! per job) and joined by `shards::merge` equals the unsharded stage's map
//! tables byte for byte; an incomplete set of shards is refused.

use rig_pipeline::Runner;
use rig_pipeline::testing::workspace_root;
use std::path::Path;

/// A small map (4 × 3 points) keeps the test to seconds.
fn run_sweeps(out: &Path, shard: &str) {
    let mut runner = Runner::new(&workspace_root().join("pipeline.toml")).unwrap().out(out).only(&["sweeps"]).jobs(2);
    for (k, v) in [("map_rpm_points", "4"), ("map_force_points", "3"), ("diagram_points", "4"), ("shard", shard)] {
        runner = runner.set_param("sweeps", k, v).unwrap();
    }
    runner.run().unwrap().into_result().unwrap();
}

#[test]
fn sharded_and_merged_map_equals_the_unsharded_map() {
    let tmp = tempfile::tempdir().unwrap();
    let (whole, merged) = (tmp.path().join("whole"), tmp.path().join("merged"));
    run_sweeps(&whole, "\"1/1\"");
    let shard_dirs: Vec<_> = (1..=3).map(|i| tmp.path().join(format!("shard-{i}"))).collect();
    for (i, dir) in shard_dirs.iter().enumerate() {
        run_sweeps(dir, &format!("\"{}/3\"", i + 1));
    }
    let written = rig_pipeline::shards::merge(&shard_dirs, &merged).unwrap();
    assert_eq!(written.len(), 2);
    for model in ["thesis", "rig"] {
        let rel = format!("tables/sweep-map-{model}.csv");
        let a = std::fs::read(whole.join(&rel)).unwrap();
        let b = std::fs::read(merged.join(&rel)).unwrap();
        assert!(a == b, "{rel}: merged shards differ from the unsharded map");
        assert_eq!(a.iter().filter(|&&c| c == b'\n').count(), 1 + 4 * 3 * 2, "{rel}: header + 12 points up and down");
    }
    let err = rig_pipeline::shards::merge(&shard_dirs[..2], &tmp.path().join("partial")).unwrap_err();
    assert!(format!("{err:#}").contains("missing or duplicate shard"), "{err:#}");
}

#[test]
fn set_param_names_an_unknown_stage() {
    let err =
        Runner::new(&workspace_root().join("pipeline.toml")).unwrap().set_param("nosuch", "x", "1").err().unwrap();
    assert!(err.to_string().contains("--set nosuch.x: no such stage"), "{err}");
}
