//! `<out>/manifest.json`: every artifact with its hash, size and the stage that
//! made it, and each stage's input hashes, code hashes and params. Sorted keys,
//! no timestamps, no absolute paths: it is committed and must be reproducible.

use crate::config::PipelineConfig;
use crate::error::PipelineError;
use crate::runner::{Outcome, StageReport};
use crate::store::{self, CacheRecord};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Serialize)]
struct Manifest {
    format: &'static str,
    artifacts: BTreeMap<String, Artifact>,
    stages: BTreeMap<String, StageEntry>,
}

#[derive(Serialize)]
struct Artifact {
    blake3: String,
    size: u64,
    stage: String,
}

#[derive(Serialize)]
struct StageEntry {
    key: String,
    inputs: BTreeMap<String, String>,
    params: BTreeMap<String, String>,
    code: BTreeMap<String, String>,
}

/// Writes the manifest for the stages that ran or were up to date in this
/// run, plus every other stage whose recorded outputs are still intact on
/// disk (not selected by `--only`, skipped, or failed after an earlier success).
pub fn write(config: &PipelineConfig, out_dir: &Path, reports: &[StageReport]) -> Result<PathBuf, PipelineError> {
    let mut records: Vec<CacheRecord> = Vec::new();
    for decl in &config.stages {
        let fresh = reports.iter().find(|r| r.name == decl.name).and_then(|r| match r.outcome {
            Outcome::Ran | Outcome::UpToDate => r.record.clone(),
            _ => None,
        });
        let record = fresh.or_else(|| {
            store::load_record(out_dir, &decl.name).filter(|r| store::output_problems(out_dir, &r.outputs).is_empty())
        });
        records.extend(record);
    }
    let mut manifest = Manifest { format: "rig-lab-manifest/1", artifacts: BTreeMap::new(), stages: BTreeMap::new() };
    for r in records {
        for (rel, h) in &r.outputs {
            let a = Artifact { blake3: h.blake3.clone(), size: h.size, stage: r.stage.clone() };
            manifest.artifacts.insert(rel.clone(), a);
        }
        let entry = StageEntry { key: r.key, inputs: r.inputs, params: r.params, code: r.code };
        manifest.stages.insert(r.stage, entry);
    }
    let path = out_dir.join("manifest.json");
    let mut text = serde_json::to_string_pretty(&manifest)
        .map_err(|e| PipelineError::Json { path: path.clone(), reason: e.to_string() })?;
    text.push('\n');
    store::write_atomic(&path, text.as_bytes())?;
    Ok(path)
}
