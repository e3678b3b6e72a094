//! The artifact store: staged outputs checked against their declaration and
//! committed through a temporary file + rename, stale family members removed,
//! and the per-stage cache record (`<out>/.cache/<stage>.json`).

use crate::config::{OutputPattern, PipelineConfig, StageDecl};
use crate::error::PipelineError;
use crate::hash::{hash_bytes, hash_file, list_files};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Suffix of the temporary files a commit writes before renaming them.
pub const TMP_SUFFIX: &str = ".rigtmp";

/// An artifact's content hash and size.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileHash {
    pub blake3: String,
    pub size: u64,
}

/// What a stage's last successful run saw and wrote (`.cache/<stage>.json`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CacheRecord {
    pub stage: String,
    /// blake3 over everything below: equal keys mean equal inputs.
    pub key: String,
    /// Input label as in pipeline.toml -> content hash.
    pub inputs: BTreeMap<String, String>,
    /// Parameter name -> canonical TOML value.
    pub params: BTreeMap<String, String>,
    /// Code path -> content hash.
    pub code: BTreeMap<String, String>,
    /// Output path relative to the out dir -> hash and size.
    pub outputs: BTreeMap<String, FileHash>,
}

/// Where the cache record of `stage` lives.
pub fn record_path(out_dir: &Path, stage: &str) -> PathBuf {
    out_dir.join(".cache").join(format!("{stage}.json"))
}

/// The cache record, or `None` when absent or unreadable (then the stage simply re-runs).
pub fn load_record(out_dir: &Path, stage: &str) -> Option<CacheRecord> {
    let text = std::fs::read_to_string(record_path(out_dir, stage)).ok()?;
    serde_json::from_str(&text).ok()
}

pub fn save_record(out_dir: &Path, record: &CacheRecord) -> Result<(), PipelineError> {
    let path = record_path(out_dir, &record.stage);
    let mut text = serde_json::to_string_pretty(record)
        .map_err(|e| PipelineError::Json { path: path.clone(), reason: e.to_string() })?;
    text.push('\n');
    write_atomic(&path, text.as_bytes())
}

/// Which recorded outputs are missing or no longer hold what the stage wrote.
pub fn output_problems(out_dir: &Path, outputs: &BTreeMap<String, FileHash>) -> Vec<String> {
    let mut problems = Vec::new();
    for (rel, want) in outputs {
        let path = out_dir.join(rel);
        match hash_file(&path) {
            Err(_) => problems.push(format!("output {rel} is missing")),
            Ok(h) if h != want.blake3 => problems.push(format!("output {rel} was modified")),
            Ok(_) => {}
        }
    }
    problems
}

/// Writes `bytes` to a temporary sibling of `path`, then renames it over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PipelineError> {
    let tmp = temp_path(path);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| PipelineError::Io { path: dir.to_path_buf(), source })?;
    }
    std::fs::write(&tmp, bytes).map_err(|source| PipelineError::Io { path: tmp.clone(), source })?;
    std::fs::rename(&tmp, path).map_err(|source| PipelineError::Io { path: path.to_path_buf(), source })
}

/// `dir/.name.rigtmp`: hidden, so directory hashes and stale sweeps ignore it.
fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}{TMP_SUFFIX}"))
}

/// Test hook: make a commit fail after this many renames, as a kill would.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fault {
    pub fail_after_renames: Option<usize>,
}

/// Commits a stage's staged outputs into `out_dir`.
///
/// Every path must be declared by the stage (checked before anything is
/// written). All temporary files are written first and only then renamed, so
/// a failure while writing changes no artifact; a kill during the renames
/// leaves each file either whole-old or whole-new and the cache record old,
/// so the next run re-runs the stage. Files of the stage's declared outputs
/// that this run did not write (and that no other stage declares) are removed.
pub fn commit(
    config: &PipelineConfig,
    decl: &StageDecl,
    out_dir: &Path,
    staged: &BTreeMap<String, Vec<u8>>,
    fault: Fault,
) -> Result<BTreeMap<String, FileHash>, PipelineError> {
    for rel in staged.keys() {
        if !decl.declares_output(rel) {
            return Err(PipelineError::UndeclaredOutput { stage: decl.name.clone(), rel: rel.clone() });
        }
    }
    let mut temps = Vec::new();
    let written: Result<(), PipelineError> = staged.iter().try_for_each(|(rel, bytes)| {
        let path = out_dir.join(rel);
        let tmp = temp_path(&path);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|source| PipelineError::Io { path: dir.to_path_buf(), source })?;
        }
        std::fs::write(&tmp, bytes).map_err(|source| PipelineError::Io { path: tmp.clone(), source })?;
        temps.push((tmp, path));
        Ok(())
    });
    if let Err(e) = written {
        for (tmp, _) in &temps {
            let _ = std::fs::remove_file(tmp);
        }
        return Err(e);
    }
    for (i, (tmp, path)) in temps.iter().enumerate() {
        if fault.fail_after_renames == Some(i) {
            return Err(PipelineError::Io {
                path: path.clone(),
                source: std::io::Error::other("injected fault: commit interrupted"),
            });
        }
        std::fs::rename(tmp, path).map_err(|source| PipelineError::Io { path: path.clone(), source })?;
    }
    remove_stale(config, decl, out_dir, staged)?;
    Ok(staged
        .iter()
        .map(|(rel, bytes)| (rel.clone(), FileHash { blake3: hash_bytes(bytes), size: bytes.len() as u64 }))
        .collect())
}

fn remove_stale(
    config: &PipelineConfig,
    decl: &StageDecl,
    out_dir: &Path,
    staged: &BTreeMap<String, Vec<u8>>,
) -> Result<(), PipelineError> {
    // Only the folders the stage's patterns can reach are walked.
    let mut dirs: Vec<String> = decl
        .outputs
        .iter()
        .map(|p| {
            let (OutputPattern::Exact(s) | OutputPattern::Prefix(s)) = p;
            s.rsplit_once('/').map(|(d, _)| d.to_string()).unwrap_or_default()
        })
        .collect();
    dirs.sort();
    dirs.dedup();
    for dir in dirs {
        let abs = out_dir.join(&dir);
        if !abs.is_dir() {
            continue;
        }
        for name in list_files(&abs)? {
            let rel = if dir.is_empty() { name } else { format!("{dir}/{name}") };
            let others = config.stages.iter().any(|s| s.name != decl.name && s.declares_output(&rel));
            if decl.declares_output(&rel) && !staged.contains_key(&rel) && !others {
                let path = out_dir.join(&rel);
                std::fs::remove_file(&path).map_err(|source| PipelineError::Io { path, source })?;
            }
        }
    }
    Ok(())
}

/// Removes temporary files an interrupted run left under `dir`.
pub fn remove_temp_files(dir: &Path) -> Result<(), PipelineError> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Ok(()) };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            remove_temp_files(&path)?;
        } else if name.starts_with('.') && name.ends_with(TMP_SUFFIX) {
            std::fs::remove_file(&path).map_err(|source| PipelineError::Io { path: path.clone(), source })?;
        }
    }
    Ok(())
}
