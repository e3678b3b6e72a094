//! One stage of a run: assessed (its fingerprint against the cache record),
//! run and committed atomically ([`Runner::run_one`], `fingerprint`,
//! `execute`), with the campaign source every stage shares and the reasons
//! a stage runs.

use super::*;

impl Runner {
    /// Assesses one stage and, unless it is up to date (or this is a dry run,
    /// or it is on demand and `may_run` is false), runs and commits it.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run_one(
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
pub(super) struct CampaignSource {
    pub(super) dir: PathBuf,
    pub(super) read: CampaignReader,
    pub(super) cell: OnceLock<Result<Arc<Campaign>, String>>,
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
pub(super) fn resolve(template: &str, dirs: &Dirs, root: &Path) -> PathBuf {
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
pub(super) fn reasons_to_run(now: &CacheRecord, before: Option<&CacheRecord>, out_dir: &Path) -> Vec<String> {
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
