//! The DAG runner: dependency order with independent stages in parallel, skip
//! by content hash, atomic commits, the manifest, and a report of what ran and why.

mod outcome;
mod stage;

use crate::accepted::{self, AcceptedCampaign};
use crate::code::CodeIndex;
use crate::config::{Input, ParamsCheck, PipelineConfig, Registry, Sources, StageDecl};
use crate::error::PipelineError;
use crate::hash::{canonical_params, hash_path};
use crate::needs::{self, Needs};
use crate::store::{self, CacheRecord, Fault, FileHash};
use crate::timing::{Stopwatch, Timing};
use crate::{StageCtx, graph, manifest};
pub use outcome::{Outcome, RunReport, StageReport};
use rig_types::Campaign;
use stage::CampaignSource;
use std::collections::{BTreeMap, BTreeSet};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Arc, Mutex, OnceLock};

/// Reads and validates a campaign folder (`rig_ingest::read_campaign`).
pub type CampaignReader = fn(&Path) -> Result<Campaign, rig_ingest::IngestError>;

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
}
