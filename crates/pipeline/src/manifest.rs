//! `<out>/manifest.json`: every artifact with its hash, size and the stage that
//! made it, and each stage's input hashes, code hashes and params. Sorted keys,
//! no timestamps, no absolute paths: it is committed and must be reproducible.
//!
//! A stage this run did not run or confirm keeps its entry while its outputs
//! are intact on disk (from its cache record, else from the manifest being
//! replaced: a fresh clone has no `.cache/`), so the manifest always lists
//! every artifact in the out dir. On-demand stages are marked `on_demand`;
//! an entry this run found stale or could not assess says so in `kept`.

use crate::config::PipelineConfig;
use crate::error::PipelineError;
use crate::runner::{Outcome, StageReport};
use crate::store::{self, CacheRecord, FileHash};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const FORMAT: &str = "rig-lab-manifest/1";

#[derive(Serialize, Deserialize)]
struct Manifest {
    format: String,
    artifacts: BTreeMap<String, Artifact>,
    stages: BTreeMap<String, StageEntry>,
}

#[derive(Serialize, Deserialize)]
struct Artifact {
    blake3: String,
    size: u64,
    stage: String,
}

#[derive(Serialize, Deserialize)]
struct StageEntry {
    key: String,
    inputs: BTreeMap<String, String>,
    params: BTreeMap<String, String>,
    code: BTreeMap<String, String>,
    /// Run only when asked for (`--only NAME`, `--all`): its outputs are those of its last such run.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    on_demand: bool,
    /// Why these are the outputs of an earlier run that this run did not confirm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    kept: Option<String>,
}

/// A stage's last record as the manifest has it, with its `kept` note.
#[derive(Debug, Clone)]
pub struct Listed {
    pub record: CacheRecord,
    pub kept: Option<String>,
}

/// The stages of `<out>/manifest.json` as records (empty when it is absent,
/// unreadable or of another format: nothing is then kept from it).
pub fn load(out_dir: &Path) -> BTreeMap<String, Listed> {
    let Some(m) = std::fs::read_to_string(out_dir.join("manifest.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<Manifest>(&t).ok())
        .filter(|m| m.format == FORMAT)
    else {
        return BTreeMap::new();
    };
    let mut out = BTreeMap::new();
    for (stage, e) in m.stages {
        let outputs = m
            .artifacts
            .iter()
            .filter(|(_, a)| a.stage == stage)
            .map(|(rel, a)| (rel.clone(), FileHash { blake3: a.blake3.clone(), size: a.size }))
            .collect();
        let record =
            CacheRecord { stage: stage.clone(), key: e.key, inputs: e.inputs, params: e.params, code: e.code, outputs };
        out.insert(stage, Listed { record, kept: e.kept });
    }
    out
}

/// Writes the manifest: the stages that ran or were up to date in this run;
/// an on-demand stage not run, with its last intact outputs (marked stale);
/// an optional stage skipped for a missing input, with its last intact
/// outputs (marked); every other stage (not selected by `--only`, failed
/// after an earlier success) whose recorded outputs are still intact, from its
/// cache record or else from `previous` (the manifest this one replaces).
pub fn write(
    config: &PipelineConfig,
    out_dir: &Path,
    reports: &[StageReport],
    previous: &BTreeMap<String, Listed>,
) -> Result<PathBuf, PipelineError> {
    let intact = |r: &CacheRecord| store::output_problems(out_dir, &r.outputs).is_empty();
    let last = |name: &str| -> Option<Listed> {
        let cached = store::load_record(out_dir, name).map(|record| Listed { record, kept: None });
        cached.or_else(|| previous.get(name).cloned()).filter(|l| intact(&l.record))
    };
    let mut listed: Vec<(Listed, bool)> = Vec::new();
    for decl in &config.stages {
        let report = reports.iter().find(|r| r.name == decl.name);
        let entry = match report.map(|r| (&r.outcome, r)) {
            Some((Outcome::Ran | Outcome::UpToDate, r)) => r.record.clone().map(|record| Listed { record, kept: None }),
            Some((Outcome::SkippedOnDemand, r)) => r.record.clone().map(|record| Listed {
                record,
                kept: Some(format!(
                    "stale, not rerun ({}): `cargo xtask reproduce --only {}` reruns it",
                    r.reasons.join("; "),
                    decl.name
                )),
            }),
            Some((Outcome::SkippedOptional, r)) => r.record.clone().map(|record| Listed {
                record,
                kept: Some("optional, skipped: an input is missing in this run; these are its last outputs".into()),
            }),
            _ => last(&decl.name),
        };
        listed.extend(entry.map(|l| (l, decl.on_demand)));
    }
    let mut manifest = Manifest { format: FORMAT.into(), artifacts: BTreeMap::new(), stages: BTreeMap::new() };
    for (Listed { record: r, kept }, on_demand) in listed {
        for (rel, h) in &r.outputs {
            let a = Artifact { blake3: h.blake3.clone(), size: h.size, stage: r.stage.clone() };
            manifest.artifacts.insert(rel.clone(), a);
        }
        let entry = StageEntry { key: r.key, inputs: r.inputs, params: r.params, code: r.code, on_demand, kept };
        manifest.stages.insert(r.stage, entry);
    }
    let path = out_dir.join("manifest.json");
    let mut text = serde_json::to_string_pretty(&manifest)
        .map_err(|e| PipelineError::Json { path: path.clone(), reason: e.to_string() })?;
    text.push('\n');
    store::write_atomic(&path, text.as_bytes())?;
    Ok(path)
}
