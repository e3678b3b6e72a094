//! The front door's memory: the last campaign the reader accepted and the
//! needs check passed, recorded in `<out>/.cache/accepted-campaign.json`, so
//! that a rerun on the same bytes with the same code does not validate them
//! again (the validation, polars over every CSV, was most of a no-op rerun).
//!
//! # Why skipping is sound
//!
//! The reader's verdict and the needs check are functions of the campaign's
//! bytes, the reader's and the needs table's code, and the set of stages the
//! run enables; nothing else (no clock, no environment). The record's key is
//! blake3 over all of them:
//!
//! - the campaign folder's content hash (`hash::hash_path`: every file's
//!   bytes, by relative path; the same hash the stage keys use, computed once
//!   per run), plus the content hash of every file the reader read that the
//!   folder hash leaves out (a hidden path: `hash_path` skips dot entries);
//!   the reader refuses run files outside the folder, so nothing it reads is
//!   elsewhere;
//! - the code: the fingerprint of every workspace source the binary was built
//!   from (`crate::BUILT_FROM`: rig-ingest's rules and `stages::needs` among
//!   them); a runner with another reader or needs table (tests) records nothing;
//! - the enabled stages' names, in run order.
//!
//! Content, not size and modification time: the hash of the folder is needed
//! for the stage keys anyway, so a content key costs nothing more and cannot
//! be fooled by an edit that keeps the size and the time stamp. A changed,
//! truncated or corrupted file changes the key, so the campaign is read and
//! validated again and refused with the reader's message (file, line, rule).
//! The record is written (temporary file + rename) only after the campaign
//! was accepted and the out dir exists; a refused campaign writes nothing.

use crate::error::PipelineError;
use crate::hash::hash_file;
use crate::store::write_atomic;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `<out>/.cache/accepted-campaign.json`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct AcceptedCampaign {
    /// blake3 of everything the reader's verdict and the needs check depend on (module docs).
    pub key: String,
    /// Files the reader read that the folder hash does not cover (hidden
    /// paths), relative to the campaign folder; their hashes are in the key.
    pub hidden_files: Vec<String>,
}

fn path(out_dir: &Path) -> PathBuf {
    out_dir.join(".cache").join("accepted-campaign.json")
}

/// The key for a campaign whose folder hashes to `dir_hash`, read by code
/// `code`, for the `enabled` stages; `hidden` are the files of the reader
/// the folder hash leaves out (hashed here).
pub fn key(
    code: &str,
    campaign_dir: &Path,
    dir_hash: &str,
    hidden: &[String],
    enabled: &[&str],
) -> Result<String, PipelineError> {
    let mut h = blake3::Hasher::new();
    h.update(b"rig-lab accepted campaign v1\0");
    h.update(code.as_bytes());
    h.update(b"\0campaign ");
    h.update(dir_hash.as_bytes());
    for rel in hidden {
        h.update(format!("\0hidden {rel} {}", hash_file(&campaign_dir.join(rel))?).as_bytes());
    }
    for stage in enabled {
        h.update(format!("\0stage {stage}").as_bytes());
    }
    Ok(h.finalize().to_hex().to_string())
}

/// The files of `runs` (paths relative to the folder, as campaign.toml names
/// them) that the folder hash does not cover: those with a hidden component.
pub fn hidden_files<'a>(runs: impl IntoIterator<Item = &'a Path>) -> Vec<String> {
    let hidden = |p: &Path| p.components().any(|c| c.as_os_str().to_string_lossy().starts_with('.'));
    let mut out: Vec<String> =
        runs.into_iter().filter(|p| hidden(p)).map(|p| p.to_string_lossy().replace('\\', "/")).collect();
    out.sort();
    out.dedup();
    out
}

/// The last record in `out_dir`, or `None` (absent or unreadable: validate).
pub fn load(out_dir: &Path) -> Option<AcceptedCampaign> {
    serde_json::from_str(&std::fs::read_to_string(path(out_dir)).ok()?).ok()
}

/// Records an accepted campaign (temporary file + rename).
pub fn save(out_dir: &Path, record: &AcceptedCampaign) -> Result<(), PipelineError> {
    let p = path(out_dir);
    let mut text = serde_json::to_string_pretty(record)
        .map_err(|e| PipelineError::Json { path: p.clone(), reason: e.to_string() })?;
    text.push('\n');
    write_atomic(&p, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_hidden_run_files_are_hashed_on_their_own() {
        let runs = [Path::new("runs/a.csv"), Path::new(".hidden/b.csv"), Path::new("runs/.c.csv")];
        assert_eq!(hidden_files(runs), [".hidden/b.csv", "runs/.c.csv"]);
    }

    #[test]
    fn the_key_moves_with_the_bytes_the_code_and_the_stages() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(".h.csv"), "a\n").unwrap();
        let hidden = vec![".h.csv".to_string()];
        let k = |code: &str, hash: &str, stages: &[&str]| key(code, dir.path(), hash, &hidden, stages).unwrap();
        let base = k("c1", "d1", &["a", "b"]);
        assert_eq!(base, k("c1", "d1", &["a", "b"]));
        assert_ne!(base, k("c2", "d1", &["a", "b"]));
        assert_ne!(base, k("c1", "d2", &["a", "b"]));
        assert_ne!(base, k("c1", "d1", &["a"]));
        std::fs::write(dir.path().join(".h.csv"), "b\n").unwrap();
        assert_ne!(base, k("c1", "d1", &["a", "b"]), "a hidden run file is in the key");
    }
}
