//! The DAG runner: dependency order with independent stages in parallel, skip
//! by content hash, atomic commits, the manifest, and a report of what ran and why.

use crate::accepted::{self, AcceptedCampaign};
use crate::code::CodeIndex;
use crate::config::{Input, ParamsCheck, PipelineConfig, Registry, Sources, StageDecl};
use crate::error::PipelineError;
use crate::hash::{canonical_params, hash_path};
use crate::needs::{self, Needs};
use crate::store::{self, CacheRecord, Fault, FileHash};
use crate::timing::{Stopwatch, Timing};
use crate::{StageCtx, graph, manifest};
use rig_types::Campaign;
use std::collections::{BTreeMap, BTreeSet};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Arc, Mutex, OnceLock};

/// Reads and validates a campaign folder (`rig_ingest::read_campaign`).
pub type CampaignReader = fn(&Path) -> Result<Campaign, rig_ingest::IngestError>;

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

    fn is_broken(&self) -> bool {
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

/// Runs the DAG of a pipeline.toml (see the crate docs for the rules).
pub struct Runner {
    config: PipelineConfig,
    registry: Registry,
    sources: Sources,
    params_check: ParamsCheck,
    campaign_reader: Option<CampaignReader>,
    needs: Needs,
    /// The code the reader and the needs are (the sources' fingerprint) when
    /// they are the real ones: then an accepted campaign is remembered
    /// (module `accepted`); `None` with any other reader or needs table.
    accepted_code: Option<&'static str>,
    campaign: Option<PathBuf>,
    out: Option<PathBuf>,
    jobs: usize,
    /// Ready stages start in declaration order, not longest remaining path first.
    declaration_order: bool,
    dry_run: bool,
    only: Vec<String>,
    all: bool,
    progress: bool,
    faults: BTreeMap<String, Fault>,
}

/// The folders a run resolves `{campaign}`, `{thesis}`, `{shared}` and outputs against.
struct Dirs {
    campaign: PathBuf,
    thesis: PathBuf,
    shared: Option<PathBuf>,
    shared_declared: PathBuf,
    out: PathBuf,
}

impl Runner {
    /// The pipeline at `path` with the real stage bodies.
    pub fn new(path: &Path) -> Result<Self, PipelineError> {
        Ok(Self::with_registry(path, crate::stages::lookup)?
            .stage_sources(crate::stages::source)
            .params_check(crate::stages::check_params)
            .campaign_reader(rig_ingest::read_campaign)
            .campaign_needs(crate::stages::needs)
            .remember_accepted(crate::BUILT_FROM))
    }

    /// Remembers an accepted campaign (module `accepted`) for a reader and
    /// needs table whose code is `code` (`Runner::new`: the sources'
    /// fingerprint). Set after [`Runner::campaign_reader`] and
    /// [`Runner::campaign_needs`], which forget it; tests name their own code.
    #[doc(hidden)]
    pub fn remember_accepted(mut self, code: &'static str) -> Self {
        self.accepted_code = Some(code);
        self
    }

    /// The pipeline at `path` with another registry (tests use fake stages).
    pub fn with_registry(path: &Path, registry: Registry) -> Result<Self, PipelineError> {
        let config = PipelineConfig::load(path, registry)?;
        Ok(Runner {
            config,
            registry,
            sources: |_| None,
            params_check: |_, _| Ok(()),
            campaign_reader: None,
            needs: |_| &[],
            accepted_code: None,
            campaign: None,
            out: None,
            jobs: 2,
            declaration_order: false,
            dry_run: false,
            only: Vec::new(),
            all: false,
            progress: false,
            faults: BTreeMap::new(),
        })
    }

    /// Where each stage's body is (relative to the pipeline.toml folder): its
    /// code is computed from that file (see `crate::code`) and added to the
    /// stage's declared `code`. Without it (fake registries) only declared code counts.
    pub fn stage_sources(mut self, sources: Sources) -> Self {
        self.sources = sources;
        self
    }

    /// How each stage's `[stage.params]` is checked: every declared stage's
    /// params, after `--set` overrides, before any stage runs (`run` refuses
    /// the whole run, naming the stage and the key).
    pub fn params_check(mut self, check: ParamsCheck) -> Self {
        self.params_check = check;
        self
    }

    /// Reads and validates the campaign once per run, before any stage, when a
    /// selected stage has a `{campaign}` input: a bad campaign refuses the run
    /// with the reader's one message (file, line, rule). Without it (fake
    /// registries) stages read the campaign themselves.
    pub fn campaign_reader(mut self, read: CampaignReader) -> Self {
        self.campaign_reader = Some(read);
        self.accepted_code = None;
        self
    }

    /// What each stage needs of the campaign (run kinds, counts, metadata):
    /// the enabled stages' needs are checked against the campaign the reader
    /// accepted, before any stage runs or anything is written under the out
    /// dir; a campaign that falls short is refused naming the file, the rule
    /// and the stage ([`PipelineError::CampaignUnfit`]).
    pub fn campaign_needs(mut self, needs: Needs) -> Self {
        self.needs = needs;
        self.accepted_code = None;
        self
    }

    pub fn config(&self) -> &PipelineConfig {
        &self.config
    }

    /// Another campaign folder instead of `settings.campaign`.
    pub fn campaign(mut self, dir: &Path) -> Self {
        self.campaign = Some(dir.to_path_buf());
        self
    }

    /// Another out dir instead of `settings.out`.
    pub fn out(mut self, dir: &Path) -> Self {
        self.out = Some(dir.to_path_buf());
        self
    }

    /// Worker threads for stages, and the size of the rayon pool stage bodies use.
    pub fn jobs(mut self, n: usize) -> Self {
        self.jobs = n.max(1);
        self
    }

    pub fn dry_run(mut self, yes: bool) -> Self {
        self.dry_run = yes;
        self
    }

    /// Only these stages and what they depend on (empty: all).
    pub fn only(mut self, names: &[&str]) -> Self {
        self.only = names.iter().map(|s| s.to_string()).collect();
        self
    }

    /// Also run the `on_demand` stages (without it they run only when named in [`Runner::only`]).
    pub fn all(mut self, yes: bool) -> Self {
        self.all = yes;
        self
    }

    /// Overrides `[stage.params] key` of `stage` for this run (`value` is read
    /// as a TOML value, or as a string when it is not one), e.g. the sweeps
    /// stage's `shard = "2/4"` for one job of a job array. The override is part
    /// of the stage's key like any param.
    pub fn set_param(mut self, stage: &str, key: &str, value: &str) -> Result<Self, PipelineError> {
        let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| toml::Value::String(value.to_string()));
        let path = self.config.path.clone();
        let decl = self.config.stages.iter_mut().find(|s| s.name == stage).ok_or_else(|| PipelineError::Config {
            path,
            stage: Some(stage.to_string()),
            reason: format!("--set {stage}.{key}: no such stage"),
        })?;
        decl.params.insert(key.to_string(), parsed);
        self.config.hand_over_params();
        Ok(self)
    }

    /// Start ready stages in declaration order, ignoring `cpu_s` (to measure
    /// the schedule against the longest-remaining-path-first default).
    pub fn declaration_order(mut self, yes: bool) -> Self {
        self.declaration_order = yes;
        self
    }

    /// A progress bar on stderr (drawn only when stderr is a terminal).
    pub fn progress(mut self, yes: bool) -> Self {
        self.progress = yes;
        self
    }

    /// Test hook: `stage`'s commit fails after `renames` files, as if killed.
    #[doc(hidden)]
    pub fn inject_commit_fault(mut self, stage: &str, renames: usize) -> Self {
        self.faults.insert(stage.to_string(), Fault { fail_after_renames: Some(renames) });
        self
    }

    /// The out dir this run writes to.
    pub fn out_dir(&self) -> PathBuf {
        self.dirs().out
    }

    fn dirs(&self) -> Dirs {
        let root = &self.config.root;
        let s = &self.config.settings;
        let shared_declared = root.join(&s.shared);
        Dirs {
            campaign: self.campaign.clone().unwrap_or_else(|| root.join(&s.campaign)),
            thesis: root.join(&s.thesis),
            shared: shared_declared.is_dir().then(|| shared_declared.clone()),
            shared_declared,
            out: self.out.clone().unwrap_or_else(|| root.join(&s.out)),
        }
    }

    /// Runs (or with `dry_run` only assesses) every selected stage.
    /// Stage failures are in the report; an `Err` means the run could not start.
    pub fn run(&self) -> Result<RunReport, PipelineError> {
        let whole = Stopwatch::start();
        for decl in &self.config.stages {
            (self.params_check)(&decl.name, &decl.params).map_err(|reason| PipelineError::Config {
                path: self.config.path.clone(),
                stage: Some(decl.name.clone()),
                reason,
            })?;
        }
        let dirs = self.dirs();
        let selected: BTreeSet<String> = if self.only.is_empty() {
            self.config.stages.iter().map(|s| s.name.clone()).collect()
        } else {
            let names: Vec<&str> = self.only.iter().map(String::as_str).collect();
            graph::with_upstream(&self.config, &names)?
        };
        let order: Vec<String> =
            graph::topological_order(&self.config)?.into_iter().filter(|n| selected.contains(n)).collect();
        // Content hashes of this run, shared by the front door and every stage key.
        let memo = Mutex::new(BTreeMap::new());
        // The campaign is read and validated once, before any stage runs, when a
        // selected stage reads it (or, accepted before on the same bytes and code,
        // read when the first stage that reads it runs); stages share this copy.
        let reads_campaign = self
            .config
            .stages
            .iter()
            .filter(|s| selected.contains(&s.name))
            .any(|s| s.inputs.iter().any(|i| matches!(i, Input::Path(p) if p.starts_with("{campaign}"))));
        let mut accept = None;
        let campaign = match self.campaign_reader {
            Some(read) if reads_campaign && dirs.campaign.is_dir() => {
                // Every stage that may run this time: on-demand ones only when asked for.
                let enabled: Vec<&str> = order
                    .iter()
                    .filter(|n| self.may_run(self.config.stage(n).expect("validated")))
                    .map(String::as_str)
                    .collect();
                let (source, record) = self.front_door(read, &dirs, &enabled, &memo)?;
                accept = record;
                Some(source)
            }
            _ => None,
        };
        if !self.dry_run {
            std::fs::create_dir_all(&dirs.out)
                .map_err(|source| PipelineError::Io { path: dirs.out.clone(), source })?;
            store::remove_temp_files(&dirs.out)?;
            if let Some(record) = &accept {
                accepted::save(&dirs.out, record)?;
            }
        }
        let pool = rayon::ThreadPoolBuilder::new().num_threads(self.jobs).build().map_err(|e| {
            PipelineError::Config { path: self.config.path.clone(), stage: None, reason: format!("thread pool: {e}") }
        })?;
        let bar = if self.progress && std::io::stderr().is_terminal() {
            let bar = indicatif::ProgressBar::new(order.len() as u64);
            if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} stages {wide_msg}") {
                bar.set_style(style);
            }
            bar
        } else {
            indicatif::ProgressBar::hidden()
        };
        let index = CodeIndex::load(&self.config.root)?;
        // The manifest this run replaces: the record of an on-demand stage when
        // `.cache/` has none (a fresh clone), and entries kept for stages not run.
        let listed = manifest::load(&dirs.out);
        let mut done: BTreeMap<String, StageReport> = BTreeMap::new();
        let path_cpu_s = if self.declaration_order { BTreeMap::new() } else { self.config.path_cpu_s() };
        std::thread::scope(|scope| {
            let (tx, rx) = mpsc::channel::<StageReport>();
            let mut pending: Vec<String> = order.clone();
            let mut running: BTreeSet<String> = BTreeSet::new();
            loop {
                // Launch every ready stage while workers are free: the longest
                // remaining path first (`cpu_s`), declaration order on a tie.
                while running.len() < self.jobs {
                    let is_ready = |n: &String| {
                        let decl = self.config.stage(n).expect("validated");
                        decl.dependencies().iter().all(|d| done.contains_key(d) || !selected.contains(d))
                    };
                    let longest = |n: &String| path_cpu_s.get(n).copied().unwrap_or(0.0);
                    let ready = (pending.iter().enumerate())
                        .filter(|(_, n)| is_ready(n))
                        .fold(None, |best: Option<(usize, f64)>, (i, n)| match best {
                            Some((_, b)) if b >= longest(n) => best,
                            _ => Some((i, longest(n))),
                        })
                        .map(|(i, _)| i);
                    let Some(i) = ready else { break };
                    let name = pending.remove(i);
                    let decl = self.config.stage(&name).expect("validated");
                    let broken = decl.dependencies().into_iter().find(|d| done.get(d).is_some_and(|r| r.is_broken()));
                    if let Some(by) = broken {
                        let reasons = vec![format!("upstream {by} did not succeed")];
                        done.insert(
                            name.clone(),
                            StageReport {
                                name,
                                outcome: Outcome::Blocked { by },
                                reasons,
                                record: None,
                                timing: Timing::default(),
                            },
                        );
                        bar.inc(1);
                        continue;
                    }
                    // Dry run: an input from a stage that would run may change; so may the
                    // outputs of an `after` stage, which are hashed into this stage's key.
                    let upstream_runs: Vec<String> = decl
                        .dependencies()
                        .into_iter()
                        .filter(|d| done.get(d).is_some_and(|r| matches!(r.outcome, Outcome::WouldRun)))
                        .collect();
                    // Everything an `after` stage wrote counts as an input of this stage
                    // (the report reads every figure and page they make).
                    let after_outputs: Vec<(String, String)> = decl
                        .after
                        .iter()
                        .filter_map(|d| done.get(d).and_then(|r| r.record.as_ref()).map(|rec| (d, rec)))
                        .flat_map(|(d, rec)| {
                            rec.outputs.iter().map(move |(rel, h)| (format!("@{d}/{rel}"), h.blake3.clone()))
                        })
                        .collect();
                    // An on-demand stage runs only when asked for.
                    let may_run = self.may_run(decl);
                    running.insert(name.clone());
                    bar.set_message(running.iter().cloned().collect::<Vec<_>>().join(", "));
                    let (tx, pool, dirs, memo, index) = (tx.clone(), &pool, &dirs, &memo, &index);
                    let listed = listed.get(&name).map(|l| l.record.clone());
                    let campaign = campaign.as_ref();
                    scope.spawn(move || {
                        let watch = Stopwatch::start();
                        let mut report = pool.install(|| {
                            let up = (&upstream_runs[..], &after_outputs[..]);
                            self.run_one(decl, dirs, memo, index, campaign, up, listed, may_run)
                        });
                        report.timing = watch.stop();
                        // The receiver lives until every stage has reported.
                        let _ = tx.send(report);
                    });
                }
                if running.is_empty() {
                    break;
                }
                let report = rx.recv().expect("a running stage always reports");
                running.remove(&report.name);
                bar.inc(1);
                bar.set_message(running.iter().cloned().collect::<Vec<_>>().join(", "));
                done.insert(report.name.clone(), report);
            }
        });
        bar.finish_and_clear();
        let stages: Vec<StageReport> = order.iter().filter_map(|n| done.remove(n)).collect();
        let manifest =
            if self.dry_run { None } else { Some(manifest::write(&self.config, &dirs.out, &stages, &listed)?) };
        Ok(RunReport { stages, manifest, total: whole.stop() })
    }

    /// The front door (module `accepted`): the campaign read and validated and
    /// checked against the `enabled` stages' needs now, with the record to save
    /// once the out dir exists; or, when the out dir's record says these bytes
    /// were accepted by this code for these stages, a read deferred to the
    /// first stage that runs and reads it (a no-op rerun reads nothing).
    fn front_door(
        &self,
        read: CampaignReader,
        dirs: &Dirs,
        enabled: &[&str],
        memo: &Mutex<BTreeMap<PathBuf, String>>,
    ) -> Result<(CampaignSource, Option<AcceptedCampaign>), PipelineError> {
        let dir = &dirs.campaign;
        let source = |campaign: Option<Arc<Campaign>>| CampaignSource {
            dir: dir.clone(),
            read,
            cell: campaign.map(|c| OnceLock::from(Ok(c))).unwrap_or_default(),
        };
        // The folder's hash, remembered for the stage keys (a failure to hash: validate).
        let code_and_hash = self.accepted_code.and_then(|code| {
            let h = hash_path(dir).ok()?;
            memo.lock().expect("memo lock").insert(dir.clone(), h.clone());
            Some((code, h))
        });
        if let Some((code, h)) = &code_and_hash
            && let Some(last) = accepted::load(&dirs.out)
            && accepted::key(code, dir, h, &last.hidden_files, enabled).is_ok_and(|k| k == last.key)
        {
            return Ok((source(None), None));
        }
        let campaign = read(dir)?;
        let unmet = needs::unmet(self.needs, enabled.iter().copied(), &campaign);
        if !unmet.is_empty() {
            return Err(PipelineError::CampaignUnfit { path: dir.join("campaign.toml"), unmet });
        }
        let record = match code_and_hash {
            Some((code, h)) => {
                let hidden_files = accepted::hidden_files(campaign.runs.iter().map(|r| r.file.as_path()));
                let key = accepted::key(code, dir, &h, &hidden_files, enabled)?;
                Some(AcceptedCampaign { key, hidden_files })
            }
            None => None,
        };
        Ok((source(Some(Arc::new(campaign))), record))
    }

    /// An on-demand stage runs only when asked for (`--only NAME` or `--all`); every other may.
    fn may_run(&self, decl: &StageDecl) -> bool {
        !decl.on_demand || self.all || self.only.iter().any(|o| o == &decl.name)
    }

    /// Assesses one stage and, unless it is up to date (or this is a dry run,
    /// or it is on demand and `may_run` is false), runs and commits it.
    #[allow(clippy::too_many_arguments)]
    fn run_one(
        &self,
        decl: &StageDecl,
        dirs: &Dirs,
        memo: &Mutex<BTreeMap<PathBuf, String>>,
        index: &CodeIndex,
        campaign: Option<&CampaignSource>,
        (upstream_runs, after_outputs): (&[String], &[(String, String)]),
        listed: Option<CacheRecord>,
        may_run: bool,
    ) -> StageReport {
        let name = decl.name.clone();
        let report = |outcome, reasons, record| StageReport {
            name: name.clone(),
            outcome,
            reasons,
            record,
            timing: Timing::default(),
        };
        if !upstream_runs.is_empty() {
            // Dry run: the upstream outputs this stage reads do not exist yet or may change.
            let reasons =
                upstream_runs.iter().map(|u| format!("upstream {u} would run; its outputs may change")).collect();
            return report(if may_run { Outcome::WouldRun } else { Outcome::SkippedOnDemand }, reasons, None);
        }
        // Resolve and check the inputs.
        let mut resolved: Vec<(String, PathBuf, bool)> = Vec::new();
        for input in &decl.inputs {
            let (path, memoise) = match input {
                Input::Path(t) => (resolve(t, dirs, &self.config.root), true),
                Input::Upstream { rel, .. } => (dirs.out.join(rel), false),
            };
            if !path.exists() {
                let label = input.label();
                if decl.optional {
                    // Its last outputs, when intact, stay what stages after it read.
                    let last = store::load_record(&dirs.out, &name)
                        .or(listed)
                        .filter(|r| store::output_problems(&dirs.out, &r.outputs).is_empty());
                    let reasons = vec![format!("input {label} ({}) is missing", path.display())];
                    return report(Outcome::SkippedOptional, reasons, last);
                }
                let err = PipelineError::MissingInput { stage: name.clone(), label, path };
                return report(Outcome::Failed(err.into()), vec!["an input is missing".into()], None);
            }
            resolved.push((input.label(), path, memoise));
        }
        let record = match self.fingerprint(decl, &resolved, memo, index) {
            Ok(mut r) => {
                if !after_outputs.is_empty() {
                    let mut key = blake3::Hasher::new();
                    key.update(r.key.as_bytes());
                    for (label, h) in after_outputs {
                        key.update(format!("\0after {label} {h}").as_bytes());
                        r.inputs.insert(label.clone(), h.clone());
                    }
                    r.key = key.finalize().to_hex().to_string();
                }
                r
            }
            Err(e) => return report(Outcome::Failed(e.into()), vec!["hashing inputs failed".into()], None),
        };
        // An on-demand stage's record may be only in the manifest (a fresh clone has no
        // `.cache/`); every other stage re-runs without a cache record.
        let previous = store::load_record(&dirs.out, &name).or(listed.filter(|_| decl.on_demand));
        let reasons = reasons_to_run(&record, previous.as_ref(), &dirs.out);
        if reasons.is_empty() {
            let previous = previous.expect("no reasons implies a record");
            let n = previous.outputs.len();
            return report(
                Outcome::UpToDate,
                vec![format!("inputs, params and code unchanged; {n} outputs intact")],
                Some(previous),
            );
        }
        if !may_run {
            // Its last outputs, when intact, stay what stages after it read.
            let had_record = previous.is_some();
            let last = previous.filter(|r| store::output_problems(&dirs.out, &r.outputs).is_empty());
            let mut reasons = reasons;
            if had_record && last.is_none() {
                reasons.push("its last outputs are not intact".into());
            }
            return report(Outcome::SkippedOnDemand, reasons, last);
        }
        if self.dry_run {
            return report(Outcome::WouldRun, reasons, None);
        }
        match self.execute(decl, dirs, campaign, record) {
            Ok(Some(record)) => report(Outcome::Ran, reasons, Some(record)),
            Ok(None) => {
                report(Outcome::SkippedEmpty, vec!["the stage returned without writing any output".into()], None)
            }
            Err(e) => report(Outcome::Failed(e), reasons, None),
        }
    }

    /// The key and component hashes of a stage: name, canonical params, every
    /// input's content (directories recursively), every code path's content
    /// (computed from the stage's source, plus what pipeline.toml declares).
    fn fingerprint(
        &self,
        decl: &StageDecl,
        inputs: &[(String, PathBuf, bool)],
        memo: &Mutex<BTreeMap<PathBuf, String>>,
        index: &CodeIndex,
    ) -> Result<CacheRecord, PipelineError> {
        let hashed = |path: &Path, memoise: bool| -> Result<String, PipelineError> {
            if memoise && let Some(h) = memo.lock().expect("memo lock").get(path) {
                return Ok(h.clone());
            }
            let h = hash_path(path)?;
            if memoise {
                memo.lock().expect("memo lock").insert(path.to_path_buf(), h.clone());
            }
            Ok(h)
        };
        let mut key = blake3::Hasher::new();
        key.update(b"rig-lab stage v1\0");
        key.update(decl.name.as_bytes());
        let params = canonical_params(&decl.params);
        for (k, v) in &params {
            key.update(format!("\0param {k} = {v}").as_bytes());
        }
        let mut input_hashes = BTreeMap::new();
        for (label, path, memoise) in inputs {
            let h = hashed(path, *memoise)?;
            key.update(format!("\0input {label} {h}").as_bytes());
            input_hashes.insert(label.clone(), h);
        }
        let mut code = BTreeMap::new();
        for c in &index.stage_code((self.sources)(&decl.name), &decl.code)?.paths {
            let path = self.config.root.join(c);
            if !path.exists() {
                return Err(PipelineError::Config {
                    path: self.config.path.clone(),
                    stage: Some(decl.name.clone()),
                    reason: format!("code path {c} does not exist"),
                });
            }
            let h = hashed(&path, true)?;
            key.update(format!("\0code {c} {h}").as_bytes());
            code.insert(c.clone(), h);
        }
        Ok(CacheRecord {
            stage: decl.name.clone(),
            key: key.finalize().to_hex().to_string(),
            inputs: input_hashes,
            params,
            code,
            outputs: BTreeMap::new(),
        })
    }

    /// Runs the body (a panic counts as a failure) and commits what it staged.
    fn execute(
        &self,
        decl: &StageDecl,
        dirs: &Dirs,
        campaign: Option<&CampaignSource>,
        mut record: CacheRecord,
    ) -> anyhow::Result<Option<CacheRecord>> {
        let body = (self.registry)(&decl.name).expect("validated against the registry");
        // Only a stage that reads the campaign waits for (or triggers) its read.
        let reads = decl.inputs.iter().any(|i| matches!(i, Input::Path(p) if p.starts_with("{campaign}")));
        let campaign = match campaign.filter(|_| reads) {
            Some(source) => Some(source.get()?),
            None => None,
        };
        let shared = dirs.shared.as_deref();
        let mut ctx = StageCtx::new(&decl.name, &dirs.campaign, &dirs.thesis, shared, &dirs.out, decl.params.clone())
            .with_campaign(campaign);
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| body(&mut ctx)));
        match result {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(e),
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "non-string panic".into());
                anyhow::bail!("panicked: {msg}");
            }
        }
        let staged = ctx.into_staged();
        if staged.is_empty() {
            return Ok(None);
        }
        let fault = self.faults.get(&decl.name).copied().unwrap_or_default();
        record.outputs = store::commit(&self.config, decl, &dirs.out, &staged, fault)?;
        store::save_record(&dirs.out, &record)?;
        Ok(Some(record))
    }
}

/// The run's campaign: read and validated by the front door, or (accepted
/// before on the same bytes, module `accepted`) read by the first stage that
/// needs it; every stage gets the same copy.
struct CampaignSource {
    dir: PathBuf,
    read: CampaignReader,
    cell: OnceLock<Result<Arc<Campaign>, String>>,
}

impl CampaignSource {
    fn get(&self) -> anyhow::Result<Arc<Campaign>> {
        let got = self.cell.get_or_init(|| {
            (self.read)(&self.dir).map(Arc::new).map_err(|e| crate::describe(&PipelineError::Campaign(e).into()))
        });
        got.clone().map_err(|e| anyhow::anyhow!(e))
    }
}

/// `{campaign}/x` etc. against the run's folders; other paths against the pipeline.toml folder.
fn resolve(template: &str, dirs: &Dirs, root: &Path) -> PathBuf {
    let bases = [("{campaign}", &dirs.campaign), ("{thesis}", &dirs.thesis), ("{shared}", &dirs.shared_declared)];
    for (placeholder, base) in bases {
        if let Some(rest) = template.strip_prefix(placeholder) {
            let rest = rest.trim_start_matches('/');
            return if rest.is_empty() { base.clone() } else { base.join(rest) };
        }
    }
    root.join(template)
}

/// Why a stage must run: what changed since its record, which output is gone.
fn reasons_to_run(now: &CacheRecord, before: Option<&CacheRecord>, out_dir: &Path) -> Vec<String> {
    let Some(before) = before else {
        return vec!["no record of an earlier run in this out dir".into()];
    };
    if now.key == before.key {
        return store::output_problems(out_dir, &before.outputs);
    }
    let mut reasons = Vec::new();
    diff_maps("input", &before.inputs, &now.inputs, &mut reasons, false);
    diff_maps("param", &before.params, &now.params, &mut reasons, true);
    diff_maps("code", &before.code, &now.code, &mut reasons, false);
    if reasons.is_empty() {
        // Same components, different key: the key's recipe changed.
        reasons.push(format!("stage key changed ({} -> {})", short(&before.key), short(&now.key)));
    }
    reasons
}

fn diff_maps(
    what: &str,
    before: &BTreeMap<String, String>,
    now: &BTreeMap<String, String>,
    reasons: &mut Vec<String>,
    show: bool,
) {
    for (k, v) in now {
        match before.get(k) {
            None => reasons.push(format!("{what} {k} is new")),
            Some(old) if old != v && show => reasons.push(format!("{what} {k} changed ({old} -> {v})")),
            Some(old) if old != v => reasons.push(format!("{what} {k} changed")),
            Some(_) => {}
        }
    }
    for k in before.keys().filter(|k| !now.contains_key(*k)) {
        reasons.push(format!("{what} {k} was removed"));
    }
}

fn short(h: &str) -> &str {
    &h[..h.len().min(12)]
}
