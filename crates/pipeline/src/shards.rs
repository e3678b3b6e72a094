//! `cargo xtask merge-shards`: joins the severity-map slices that
//! `cargo xtask reproduce --only sweeps --set sweeps.shard=i/n` wrote in
//! separate out dirs (one per job of a job array) into the map tables the
//! unsharded stage writes, byte for byte.

use anyhow::{Context, Result, bail};
use rig_sweep::{MapSlice, map_table, merge_slices};
use std::path::{Path, PathBuf};

/// The models whose maps the sweeps stage shards (its table names).
const MODELS: [&str; 2] = ["thesis", "rig"];

/// Merges every `tables/sweep-map-<model>.shard-<i>-of-<n>.json` found in
/// `shard_dirs` and writes `tables/sweep-map-<model>.csv` under `out`
/// (temporary file + rename). Returns the files written.
pub fn merge(shard_dirs: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    for model in MODELS {
        let prefix = format!("sweep-map-{model}.shard-");
        let mut slices: Vec<(PathBuf, MapSlice)> = Vec::new();
        for dir in shard_dirs {
            let tables = dir.join("tables");
            let entries = std::fs::read_dir(&tables).with_context(|| format!("reading {}", tables.display()))?;
            let mut names: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".json"))
                })
                .collect();
            names.sort();
            for path in names {
                let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
                let slice: MapSlice =
                    serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
                slices.push((path, slice));
            }
        }
        if slices.is_empty() {
            bail!(
                "no {prefix}*.json slice in {}",
                shard_dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ")
            );
        }
        let files: Vec<String> = slices.iter().map(|(p, _)| p.display().to_string()).collect();
        let merged = merge_slices(slices.into_iter().map(|(_, s)| s).collect())
            .with_context(|| format!("merging {}", files.join(", ")))?;
        let dest = out.join("tables").join(format!("sweep-map-{model}.csv"));
        write_atomic(&dest, map_table(&merged).to_csv().as_bytes())?;
        written.push(dest);
    }
    Ok(written)
}

fn write_atomic(dest: &Path, bytes: &[u8]) -> Result<()> {
    let dir = dest.parent().context("a table path has a parent")?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let name = dest.file_name().and_then(|n| n.to_str()).context("a table path has a file name")?;
    let tmp = dir.join(format!(".{name}.rigtmp"));
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, dest).with_context(|| format!("renaming {} to {}", tmp.display(), dest.display()))?;
    Ok(())
}
