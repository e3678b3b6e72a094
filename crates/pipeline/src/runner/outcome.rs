//! What a run reports: how each stage ended ([`Outcome`]), per stage
//! ([`StageReport`]) and for the whole run ([`RunReport`]), with its summary.

use super::*;

/// How a stage ended in one run.
#[derive(Debug)]
pub enum Outcome {
    /// The body ran and its outputs were committed.
    Ran,
    /// Inputs, params, code and outputs unchanged: not run.
    UpToDate,
    /// `--dry-run`: would run for the reasons given.
    WouldRun,
    /// An `optional` stage whose inputs are missing; stages after it read its
    /// last outputs, if intact.
    SkippedOptional,
    /// An `on_demand` stage not asked for (`--only NAME` or `--all`) whose
    /// inputs, params or code changed since its last run (the reasons say
    /// what); stages after it read its last outputs, if any.
    SkippedOnDemand,
    /// The body returned Ok without staging any output.
    SkippedEmpty,
    /// The body, its inputs or its commit failed; nothing of it was written.
    Failed(anyhow::Error),
    /// Not run because the named upstream stage failed or was blocked.
    Blocked { by: String },
}

/// One stage's line in the run report.
#[derive(Debug)]
pub struct StageReport {
    pub name: String,
    pub outcome: Outcome,
    /// Why it ran, would run, was skipped or up to date (for `--why`).
    pub reasons: Vec<String>,
    /// The record of its outputs when it ran or was up to date, or of its
    /// last intact outputs when it was skipped (on demand or optional).
    pub record: Option<CacheRecord>,
    /// How long it took (not reproducible: kept out of every artifact, see `timing`).
    pub timing: Timing,
}

impl StageReport {
    /// The stage's outputs (relative to the out dir), as [`StageReport::record`] has them.
    pub fn outputs(&self) -> BTreeMap<String, FileHash> {
        self.record.as_ref().map(|r| r.outputs.clone()).unwrap_or_default()
    }

    pub(super) fn is_broken(&self) -> bool {
        matches!(self.outcome, Outcome::Failed(_) | Outcome::Blocked { .. })
    }
}

/// Every selected stage in dependency order.
#[derive(Debug)]
pub struct RunReport {
    pub stages: Vec<StageReport>,
    /// `<out>/manifest.json`, unless this was a dry run.
    pub manifest: Option<PathBuf>,
    /// Wall and CPU time of the whole run.
    pub total: Timing,
}

impl RunReport {
    pub fn stage(&self, name: &str) -> Option<&StageReport> {
        self.stages.iter().find(|s| s.name == name)
    }

    /// Names of the stages that ran (or would run, in a dry run).
    pub fn ran(&self) -> Vec<&str> {
        let ran = |s: &&StageReport| matches!(s.outcome, Outcome::Ran | Outcome::WouldRun);
        self.stages.iter().filter(ran).map(|s| s.name.as_str()).collect()
    }

    /// One line per stage: outcome and, with `why`, the reasons.
    pub fn summary(&self, why: bool) -> String {
        let mut s = String::new();
        for st in &self.stages {
            let what = match &st.outcome {
                Outcome::Ran => "ran".to_string(),
                Outcome::UpToDate => "up to date".to_string(),
                Outcome::WouldRun => "would run".to_string(),
                Outcome::SkippedOptional => "skipped (optional, input missing)".to_string(),
                Outcome::SkippedOnDemand => {
                    format!("skipped (on demand, stale: `cargo xtask reproduce --only {}` or `--all` runs it)", st.name)
                }
                Outcome::SkippedEmpty => "skipped (wrote no output)".to_string(),
                Outcome::Failed(_) => "FAILED".to_string(),
                Outcome::Blocked { by } => format!("not run: upstream {by} failed"),
            };
            s.push_str(&format!("{:<22} {what}\n", st.name));
            let always = matches!(st.outcome, Outcome::SkippedOptional | Outcome::SkippedOnDemand | Outcome::WouldRun);
            if why || always {
                for r in &st.reasons {
                    s.push_str(&format!("{:<22}   - {r}\n", ""));
                }
            }
        }
        s
    }

    /// Ok when no stage failed; else an error naming each failed stage with its error chain.
    pub fn into_result(self) -> anyhow::Result<Self> {
        let failed: Vec<String> = self
            .stages
            .iter()
            .filter_map(|s| match &s.outcome {
                Outcome::Failed(e) => Some(format!("stage {}: {}", s.name, crate::describe(e))),
                _ => None,
            })
            .collect();
        if failed.is_empty() { Ok(self) } else { Err(anyhow::anyhow!("{}", failed.join("\n"))) }
    }
}
