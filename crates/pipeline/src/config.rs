//! `pipeline.toml`: settings and `[[stage]]` declarations, parsed and checked
//! against the stage registry before anything runs.

use crate::StageFn;
use crate::error::PipelineError;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The stage registry: a pipeline.toml name -> its body (injectable for tests).
pub type Registry = fn(&str) -> Option<StageFn>;

/// Where a stage's body lives: a pipeline.toml name -> its source file,
/// relative to the pipeline.toml folder (the stage's code is computed from it).
pub type Sources = fn(&str) -> Option<&'static str>;

/// Checks the `[stage.params]` of the stage called by the first argument;
/// `Err` is a reason naming the key (see `stages::check_params`).
pub type ParamsCheck = fn(&str, &toml::Table) -> Result<(), String>;

/// `[settings]`: folders relative to the directory holding pipeline.toml.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    pub campaign: String,
    pub thesis: String,
    pub shared: String,
    pub out: String,
    /// Code every stage depends on that no source names (the lockfile): hashed
    /// into every stage's key with the code computed from its source (`crate::code`).
    #[serde(default)]
    pub common_code: Vec<String>,
}

/// One input of a stage as written in pipeline.toml.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Input {
    /// A path with `{campaign}`, `{thesis}` or `{shared}` placeholders.
    Path(String),
    /// `@stage/rel`: the output `rel` (relative to the out dir) of `stage`.
    Upstream { stage: String, rel: String },
}

impl Input {
    /// The text as written in pipeline.toml (also the label in caches and the manifest).
    pub fn label(&self) -> String {
        match self {
            Input::Path(p) => p.clone(),
            Input::Upstream { stage, rel } => format!("@{stage}/{rel}"),
        }
    }
}

/// A declared output: an exact relative path or a `prefix*` family.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OutputPattern {
    Exact(String),
    Prefix(String),
}

impl OutputPattern {
    fn parse(s: &str) -> Self {
        match s.strip_suffix('*') {
            Some(prefix) => OutputPattern::Prefix(prefix.to_string()),
            None => OutputPattern::Exact(s.to_string()),
        }
    }

    pub fn matches(&self, rel: &str) -> bool {
        match self {
            OutputPattern::Exact(p) => p == rel,
            OutputPattern::Prefix(p) => rel.starts_with(p.as_str()),
        }
    }
}

/// One `[[stage]]` block.
#[derive(Debug, Clone)]
pub struct StageDecl {
    pub name: String,
    pub summary: String,
    pub inputs: Vec<Input>,
    /// Stages that must finish first although no data flows (`after`).
    pub after: Vec<String>,
    /// Paths (relative to the pipeline.toml directory) hashed as the stage's code
    /// in addition to the code computed from its source (data files it embeds
    /// are found too; list here only what no source names).
    pub code: Vec<String>,
    pub outputs: Vec<OutputPattern>,
    /// Skipped with a message, not an error, when an input is missing.
    pub optional: bool,
    /// Run only when asked for by name (`--only NAME`) or with `--all`; a
    /// default run assesses it (up to date, or stale and why) without running
    /// it, and stages listing it in `after` read its last outputs. No stage
    /// that is not on demand may read its outputs as `inputs`.
    pub on_demand: bool,
    /// Stages whose params (with their `[shared.<name>]` tables) this stage
    /// gets as `[stage.params.<stage>]` (`params_of`): a stage that reruns
    /// another stages' chain (the confusion battery: calibration, estimation,
    /// diagnosis) runs it with their options, and its key covers them.
    pub params_of: Vec<String>,
    /// CPU seconds the stage takes alone (`cpu_s`, measured with `--jobs 1`;
    /// 0 when not given): only the schedule reads it, to start the longest
    /// remaining path first ([`PipelineConfig::path_cpu_s`]); no key covers it
    /// and no output depends on it.
    pub cpu_s: f64,
    pub params: toml::Table,
}

impl StageDecl {
    /// Stages this one reads from or must run after, in declaration order, without repeats.
    pub fn dependencies(&self) -> Vec<String> {
        let mut deps: Vec<String> = Vec::new();
        let upstream = self.inputs.iter().filter_map(|i| match i {
            Input::Upstream { stage, .. } => Some(stage.clone()),
            Input::Path(_) => None,
        });
        for d in upstream.chain(self.after.iter().cloned()) {
            if !deps.contains(&d) {
                deps.push(d);
            }
        }
        deps
    }

    pub fn declares_output(&self, rel: &str) -> bool {
        self.outputs.iter().any(|p| p.matches(rel))
    }
}

/// The whole file, validated.
#[derive(Debug, Clone)]
pub struct PipelineConfig {
    /// The pipeline.toml path (named in errors).
    pub path: PathBuf,
    /// The directory holding pipeline.toml: settings and code paths are relative to it.
    pub root: PathBuf,
    pub settings: Settings,
    /// In declaration order.
    pub stages: Vec<StageDecl>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    settings: Settings,
    /// Tables declared once (`[shared.<name>]`); a stage listing `<name>`
    /// in its `shared` gets the table as `[stage.params.<name>]`.
    #[serde(default)]
    shared: std::collections::BTreeMap<String, toml::Table>,
    #[serde(default)]
    stage: Vec<RawStage>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStage {
    name: String,
    #[serde(default)]
    summary: String,
    #[serde(default)]
    inputs: Vec<String>,
    #[serde(default)]
    after: Vec<String>,
    #[serde(default)]
    code: Vec<String>,
    #[serde(default)]
    outputs: Vec<String>,
    #[serde(default)]
    optional: bool,
    #[serde(default)]
    on_demand: bool,
    /// Names of `[shared.<name>]` tables handed to this stage as `params.<name>`.
    #[serde(default)]
    shared: Vec<String>,
    /// Names of stages whose params are handed to this stage as `params.<stage>`.
    #[serde(default)]
    params_of: Vec<String>,
    /// CPU seconds alone, for the schedule.
    #[serde(default)]
    cpu_s: f64,
    #[serde(default)]
    params: toml::Table,
}

impl PipelineConfig {
    /// Reads and validates `path` against `registry`.
    pub fn load(path: &Path, registry: Registry) -> Result<Self, PipelineError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| PipelineError::Io { path: path.to_path_buf(), source })?;
        let root = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let root = if root.as_os_str().is_empty() { PathBuf::from(".") } else { root };
        Self::parse(&text, path, &root, registry)
    }

    /// Parses `text` (as if read from `path`) and validates it.
    pub fn parse(text: &str, path: &Path, root: &Path, registry: Registry) -> Result<Self, PipelineError> {
        let raw: RawFile = toml::from_str(text).map_err(|e| PipelineError::Config {
            path: path.to_path_buf(),
            stage: None,
            reason: e.to_string(),
        })?;
        let common_code = raw.settings.common_code.clone();
        let stages = raw
            .stage
            .into_iter()
            .map(|mut s| {
                let inputs = s.inputs.iter().map(|i| parse_input(path, &s.name, i)).collect::<Result<Vec<_>, _>>()?;
                for name in &s.shared {
                    let err = |reason: String| PipelineError::Config {
                        path: path.to_path_buf(),
                        stage: Some(s.name.clone()),
                        reason,
                    };
                    let table = raw.shared.get(name).cloned().ok_or_else(|| {
                        err(format!("shared = [\"{name}\"] but pipeline.toml has no [shared.{name}] table"))
                    })?;
                    if s.params.contains_key(name) {
                        return Err(err(format!(
                            "[stage.params] {name}: declared once in [shared.{name}], not per stage"
                        )));
                    }
                    s.params.insert(name.clone(), toml::Value::Table(table));
                }
                Ok(StageDecl {
                    outputs: s.outputs.iter().map(|o| OutputPattern::parse(o)).collect(),
                    name: s.name,
                    summary: s.summary,
                    inputs,
                    after: s.after,
                    code: s.code.iter().chain(common_code.iter().filter(|c| !s.code.contains(c))).cloned().collect(),
                    optional: s.optional,
                    on_demand: s.on_demand,
                    params_of: s.params_of,
                    cpu_s: s.cpu_s,
                    params: s.params,
                })
            })
            .collect::<Result<Vec<_>, PipelineError>>()?;
        let mut config =
            PipelineConfig { path: path.to_path_buf(), root: root.to_path_buf(), settings: raw.settings, stages };
        for s in &config.stages {
            for other in &s.params_of {
                let reason = match config.stage(other) {
                    None => Some(format!("params_of = [\"{other}\"]: no stage named {other}")),
                    Some(o) if !o.params_of.is_empty() => {
                        Some(format!("params_of = [\"{other}\"]: stage {other} has params_of itself (one level only)"))
                    }
                    Some(_) if s.params.contains_key(other) => {
                        Some(format!("[stage.params] {other}: the params of stage {other} come from params_of"))
                    }
                    Some(_) => None,
                };
                if let Some(reason) = reason {
                    return Err(config.err(&s.name, reason));
                }
            }
        }
        config.hand_over_params();
        config.validate(registry)?;
        Ok(config)
    }

    /// Copies the params of every stage named in a `params_of` into the
    /// listing stage's `[stage.params.<stage>]`; run again after a `--set`,
    /// so the copy is what the named stage runs.
    pub(crate) fn hand_over_params(&mut self) {
        let copies: Vec<(usize, String, toml::Table)> = (self.stages.iter().enumerate())
            .flat_map(|(i, s)| s.params_of.iter().map(move |o| (i, o.clone())))
            .filter_map(|(i, o)| self.stage(&o).map(|d| (i, o, d.params.clone())))
            .collect();
        for (i, name, params) in copies {
            self.stages[i].params.insert(name, toml::Value::Table(params));
        }
    }

    pub fn stage(&self, name: &str) -> Option<&StageDecl> {
        self.stages.iter().find(|s| s.name == name)
    }

    /// Each stage's longest remaining path, in CPU seconds: its own `cpu_s`
    /// plus the longest path of the stages that depend on it (`inputs` and
    /// `after`). The runner starts the ready stage with the longest first
    /// (declaration order on a tie), so the critical path is never queued
    /// behind shorter work.
    pub fn path_cpu_s(&self) -> std::collections::BTreeMap<String, f64> {
        let mut path = std::collections::BTreeMap::new();
        let order = crate::graph::topological_order(self).unwrap_or_default();
        for name in order.iter().rev() {
            let own = self.stage(name).map_or(0.0, |s| s.cpu_s);
            let after = (self.stages.iter())
                .filter(|s| s.dependencies().contains(name))
                .filter_map(|s| path.get(&s.name).copied())
                .fold(0.0, f64::max);
            path.insert(name.clone(), own + after);
        }
        path
    }

    fn err(&self, stage: &str, reason: String) -> PipelineError {
        PipelineError::Config { path: self.path.clone(), stage: Some(stage.to_string()), reason }
    }

    fn validate(&self, registry: Registry) -> Result<(), PipelineError> {
        for (i, s) in self.stages.iter().enumerate() {
            if self.stages[..i].iter().any(|p| p.name == s.name) {
                return Err(self.err(&s.name, "declared twice".into()));
            }
            if registry(&s.name).is_none() {
                return Err(self.err(&s.name, "unknown stage name: no body registered in stages::lookup".into()));
            }
            if s.outputs.is_empty() {
                return Err(self.err(&s.name, "declares no outputs".into()));
            }
            if !(s.cpu_s.is_finite() && s.cpu_s >= 0.0) {
                return Err(self.err(&s.name, format!("cpu_s = {}: must be a finite number >= 0", s.cpu_s)));
            }
            for o in &s.outputs {
                let (OutputPattern::Exact(p) | OutputPattern::Prefix(p)) = o;
                if p.starts_with('/') || p.split('/').any(|c| c == "..") || p.starts_with('.') {
                    return Err(
                        self.err(&s.name, format!("output {p:?} must be relative, inside the out dir, not hidden"))
                    );
                }
            }
            for input in &s.inputs {
                if let Input::Upstream { stage, rel } = input {
                    let Some(up) = self.stage(stage) else {
                        return Err(self.err(&s.name, format!("input @{stage}/{rel}: no stage named {stage}")));
                    };
                    if !up.declares_output(rel) {
                        return Err(
                            self.err(&s.name, format!("input @{stage}/{rel}: stage {stage} declares no such output"))
                        );
                    }
                    if up.on_demand && !s.on_demand {
                        return Err(self.err(
                            &s.name,
                            format!(
                                "input @{stage}/{rel}: stage {stage} is on_demand, so a default run may not have its \
                                 outputs; name it in `after` or make this stage on_demand too"
                            ),
                        ));
                    }
                }
            }
            for a in &s.after {
                if self.stage(a).is_none() {
                    return Err(self.err(&s.name, format!("after: no stage named {a}")));
                }
            }
        }
        crate::graph::topological_order(self).map(|_| ())
    }
}

fn parse_input(path: &Path, stage: &str, text: &str) -> Result<Input, PipelineError> {
    let bad =
        |reason: String| PipelineError::Config { path: path.to_path_buf(), stage: Some(stage.to_string()), reason };
    if let Some(rest) = text.strip_prefix('@') {
        let Some((up, rel)) = rest.split_once('/') else {
            return Err(bad(format!("input {text:?}: expected @stage/relative-path")));
        };
        if up.is_empty() || rel.is_empty() {
            return Err(bad(format!("input {text:?}: expected @stage/relative-path")));
        }
        return Ok(Input::Upstream { stage: up.to_string(), rel: rel.to_string() });
    }
    // Only the three known placeholders may appear.
    let mut rest = text;
    while let Some(open) = rest.find('{') {
        let close = rest[open..].find('}').ok_or_else(|| bad(format!("input {text:?}: unclosed placeholder")))?;
        let key = &rest[open + 1..open + close];
        if !matches!(key, "campaign" | "thesis" | "shared") {
            return Err(bad(format!("input {text:?}: unknown placeholder {{{key}}} (campaign, thesis, shared)")));
        }
        rest = &rest[open + close + 1..];
    }
    Ok(Input::Path(text.to_string()))
}
