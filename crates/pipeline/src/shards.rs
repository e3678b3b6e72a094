//! `cargo xtask merge-shards`: joins the slices that a job array wrote in
//! separate out dirs (one per job) into what the unsharded stage writes,
//! byte for byte: the severity maps of
//! `cargo xtask reproduce --only sweeps --set sweeps.shard=i/n` and the
//! battery of `--only confusion --set confusion.shard=i/n`.

use anyhow::{Context, Result, anyhow, bail};
use rig_sweep::{MapSlice, map_table, merge_slices};
use rig_virtual_rig::battery::{Battery, BatterySlice, Outcome, battery_outputs};
use std::path::{Path, PathBuf};

/// The models whose maps the sweeps stage shards (its table names).
const MODELS: [&str; 2] = ["thesis", "rig"];

/// The battery slices' file-name prefix under `tables/`.
const BATTERY_PREFIX: &str = "confusion-slice.shard-";

/// Every `tables/<prefix>*.json` of `shard_dirs`, parsed, with its path
/// (dirs in the order given, files sorted by name).
fn read_slices<T: serde::de::DeserializeOwned>(shard_dirs: &[PathBuf], prefix: &str) -> Result<Vec<(PathBuf, T)>> {
    let mut slices = Vec::new();
    for dir in shard_dirs {
        let tables = dir.join("tables");
        let entries = std::fs::read_dir(&tables).with_context(|| format!("reading {}", tables.display()))?;
        let mut names: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with(prefix) && n.ends_with(".json"))
            })
            .collect();
        names.sort();
        for path in names {
            let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
            let slice: T = serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
            slices.push((path, slice));
        }
    }
    Ok(slices)
}

/// Merges every slice found in `shard_dirs` — the severity maps'
/// `tables/sweep-map-<model>.shard-<i>-of-<n>.json` into
/// `tables/sweep-map-<model>.csv`, the battery's
/// `tables/confusion-slice.shard-<i>-of-<n>.json` into the confusion stage's
/// tables, figure and confusion.md — and writes them under `out`
/// (temporary file + rename). Returns the files written; refuses dirs
/// with no slice of either kind.
pub fn merge(shard_dirs: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>> {
    let dirs = || shard_dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ");
    let maps = !read_slices::<serde_json::Value>(shard_dirs, "sweep-map-")?.is_empty();
    let battery: Vec<(PathBuf, BatterySlice)> = read_slices(shard_dirs, BATTERY_PREFIX)?;
    if !maps && battery.is_empty() {
        bail!("no sweep-map-*.shard-*.json or {BATTERY_PREFIX}*.json slice in {}", dirs());
    }
    let mut written = if maps { merge_maps(shard_dirs, out)? } else { Vec::new() };
    if !battery.is_empty() {
        let files: Vec<String> = battery.iter().map(|(p, _)| p.display().to_string()).collect();
        let (b, outcomes) = rig_virtual_rig::battery::merge_slices(battery.into_iter().map(|(_, s)| s).collect())
            .map_err(|e| anyhow!("merging {}: {e}", files.join(", ")))?;
        for (rel, bytes) in battery_files(&b, &outcomes)? {
            let dest = out.join(rel);
            write_atomic(&dest, &bytes)?;
            written.push(dest);
        }
    }
    Ok(written)
}

/// What the confusion stage writes for a whole battery (tables, confusion.md,
/// the detection sheet's four files), path → bytes, in a fixed order.
pub(crate) fn battery_files(battery: &Battery, outcomes: &[Outcome]) -> Result<Vec<(String, Vec<u8>)>> {
    let (texts, sheet) = battery_outputs(battery, outcomes);
    let mut files: Vec<(String, Vec<u8>)> = texts.into_iter().map(|(p, t)| (p.to_string(), t.into_bytes())).collect();
    if let Some(sheet) = sheet {
        files.extend(crate::ctx::sheet_files(&sheet)?);
    }
    Ok(files)
}

/// The confusion stage's outputs for a whole battery, staged in `ctx`.
pub(crate) fn write_battery(ctx: &mut crate::StageCtx, battery: &Battery, outcomes: &[Outcome]) -> Result<()> {
    for (rel, bytes) in battery_files(battery, outcomes)? {
        ctx.write_bytes(&rel, bytes)?;
    }
    Ok(())
}

/// The severity maps' slices merged into `tables/sweep-map-<model>.csv`.
fn merge_maps(shard_dirs: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    for model in MODELS {
        let prefix = format!("sweep-map-{model}.shard-");
        let slices: Vec<(PathBuf, MapSlice)> = read_slices(shard_dirs, &prefix)?;
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
