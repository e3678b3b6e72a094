//! The context a stage runs in: where its inputs are, its parameters, and a
//! staging area for its outputs. Its errors do not name the stage: the runner
//! prefixes every stage error with `stage <name>:` once.

use anyhow::{Context, Result, anyhow};
use rig_types::{Campaign, FigureSpec, Sheet, Table};
use serde::{Serialize, de::DeserializeOwned};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A stage body: reads through the context, writes through the context.
pub type StageFn = fn(&mut StageCtx) -> Result<()>;

pub struct StageCtx {
    /// The stage's name in pipeline.toml.
    pub name: String,
    /// The campaign folder (`{campaign}`).
    pub campaign_dir: PathBuf,
    /// The thesis tables folder (`{thesis}`).
    pub thesis_dir: PathBuf,
    /// `../shared` when present (`{shared}`), else `None`.
    pub shared_dir: Option<PathBuf>,
    /// The output root; upstream stages' outputs are read from here.
    pub out_dir: PathBuf,
    /// `[stage.params]` of pipeline.toml.
    pub params: toml::Table,
    /// Relative path -> bytes, committed by the runner after success.
    staged: BTreeMap<String, Vec<u8>>,
    campaign: Option<Arc<Campaign>>,
}

impl StageCtx {
    pub fn new(
        name: &str,
        campaign_dir: &Path,
        thesis_dir: &Path,
        shared_dir: Option<&Path>,
        out_dir: &Path,
        params: toml::Table,
    ) -> Self {
        StageCtx {
            name: name.to_string(),
            campaign_dir: campaign_dir.to_path_buf(),
            thesis_dir: thesis_dir.to_path_buf(),
            shared_dir: shared_dir.map(Path::to_path_buf),
            out_dir: out_dir.to_path_buf(),
            params,
            staged: BTreeMap::new(),
            campaign: None,
        }
    }

    /// `[stage.params]` as a typed struct. Declare it
    /// `#[derive(Deserialize)] #[serde(deny_unknown_fields)]` in the analysis
    /// crate that owns the knobs: an unknown, missing or mistyped key is then an
    /// error that names the stage and the key.
    pub fn typed_params<T: DeserializeOwned>(&self) -> Result<T> {
        parse_params(&self.params).map_err(|e| anyhow!("pipeline.toml: {e}"))
    }

    /// A numeric parameter from `[stage.params]` (integers are accepted as floats).
    #[deprecated(
        note = "declare a #[serde(deny_unknown_fields)] Params struct, read it with typed_params and register it in stages/mod.rs"
    )]
    pub fn param_f64(&self, key: &str) -> Result<f64> {
        match self.params.get(key) {
            Some(toml::Value::Float(x)) => Ok(*x),
            Some(toml::Value::Integer(i)) => Ok(*i as f64),
            Some(v) => Err(anyhow!("pipeline.toml: param {key} = {v} is not a number")),
            None => Err(anyhow!("pipeline.toml: param {key} is missing")),
        }
    }

    #[deprecated(
        note = "declare a #[serde(deny_unknown_fields)] Params struct, read it with typed_params and register it in stages/mod.rs"
    )]
    pub fn param_usize(&self, key: &str) -> Result<usize> {
        match self.params.get(key) {
            Some(toml::Value::Integer(i)) if *i >= 0 => Ok(*i as usize),
            Some(v) => Err(anyhow!("pipeline.toml: param {key} = {v} is not a non-negative integer")),
            None => Err(anyhow!("pipeline.toml: param {key} is missing")),
        }
    }

    #[deprecated(
        note = "declare a #[serde(deny_unknown_fields)] Params struct, read it with typed_params and register it in stages/mod.rs"
    )]
    pub fn param_str(&self, key: &str) -> Result<String> {
        match self.params.get(key) {
            Some(toml::Value::String(s)) => Ok(s.clone()),
            Some(v) => Err(anyhow!("pipeline.toml: param {key} = {v} is not a string")),
            None => Err(anyhow!("pipeline.toml: param {key} is missing")),
        }
    }

    /// Gives the stage the campaign the runner has already read and validated
    /// (once per run, before any stage), so `campaign()` does not read it again.
    pub fn with_campaign(mut self, campaign: Option<Arc<Campaign>>) -> Self {
        self.campaign = campaign;
        self
    }

    /// The campaign: the runner's validated copy, or read and validated here by `rig-ingest`.
    pub fn campaign(&mut self) -> Result<&Campaign> {
        if self.campaign.is_none() {
            let c = rig_ingest::read_campaign(&self.campaign_dir).context("reading the campaign")?;
            self.campaign = Some(Arc::new(c));
        }
        Ok(self.campaign.as_ref().expect("just loaded"))
    }

    /// An upstream stage's JSON output, by path relative to the out dir.
    pub fn read_json<T: DeserializeOwned>(&self, rel: &str) -> Result<T> {
        let path = self.out_dir.join(rel);
        let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
    }

    /// Stages raw bytes for `rel` (relative to the out dir).
    pub fn write_bytes(&mut self, rel: &str, bytes: Vec<u8>) -> Result<()> {
        if rel.starts_with('/') || rel.split('/').any(|p| p == ".." || p.is_empty()) {
            return Err(anyhow!("output path {rel} must be relative and stay inside the out dir"));
        }
        if self.staged.insert(rel.to_string(), bytes).is_some() {
            return Err(anyhow!("output {rel} written twice"));
        }
        Ok(())
    }

    pub fn write_text(&mut self, rel: &str, text: &str) -> Result<()> {
        self.write_bytes(rel, text.as_bytes().to_vec())
    }

    /// `tables/<name>.csv` (pass the full relative path, e.g. `tables/thesis-table-4-2.csv`).
    pub fn write_table(&mut self, rel: &str, table: &Table) -> Result<()> {
        self.write_text(rel, &table.to_csv())
    }

    /// A large table: `rel` (`tables/<name>.csv`) and, beside it,
    /// `tables/<name>.parquet` with the same cells, typed
    /// ([`crate::parquet`]), for loading into polars or pandas in one line.
    pub fn write_table_with_parquet(&mut self, rel: &str, table: &Table) -> Result<()> {
        let stem = rel.strip_suffix(".csv").ok_or_else(|| anyhow!("table path {rel} must end in .csv"))?;
        let parquet = crate::parquet::table_parquet(table).with_context(|| format!("table {rel}"))?;
        self.write_table(rel, table)?;
        self.write_bytes(&format!("{stem}.parquet"), parquet)
    }

    /// Pretty JSON with a trailing newline.
    pub fn write_json<T: Serialize>(&mut self, rel: &str, value: &T) -> Result<()> {
        let mut s = serde_json::to_string_pretty(value)?;
        s.push('\n');
        self.write_text(rel, &s)
    }

    /// `figures/<id>.svg`, `.png`, `.txt` (caption) and `.csv` (data series).
    pub fn write_figure(&mut self, spec: &FigureSpec) -> Result<()> {
        let svg = rig_figures::render_svg(spec).with_context(|| format!("figure {}", spec.id))?;
        let png = rig_figures::render_png(spec).with_context(|| format!("figure {}", spec.id))?;
        let csv = rig_figures::series_csv(spec);
        self.write_figure_files(&spec.id, svg, png, (&spec.title, &spec.caption), csv)
    }

    /// A multi-panel sheet: the same four files as [`Self::write_figure`];
    /// its `.csv` holds every panel's series with a `panel` column.
    pub fn write_sheet(&mut self, sheet: &Sheet) -> Result<()> {
        for (rel, bytes) in sheet_files(sheet)? {
            self.write_bytes(&rel, bytes)?;
        }
        Ok(())
    }

    fn write_figure_files(
        &mut self,
        id: &str,
        svg: String,
        png: Vec<u8>,
        (title, caption): (&str, &str),
        csv: String,
    ) -> Result<()> {
        for (rel, bytes) in figure_files(id, svg, png, (title, caption), csv) {
            self.write_bytes(&rel, bytes)?;
        }
        Ok(())
    }

    /// Everything staged so far (the runner commits these).
    pub fn into_staged(self) -> BTreeMap<String, Vec<u8>> {
        self.staged
    }

    pub fn staged(&self) -> &BTreeMap<String, Vec<u8>> {
        &self.staged
    }
}

/// `params` (a stage's `[stage.params]`) as `T`, or a one-line reason naming
/// the key: `[stage.params] rtol: invalid type: …` (callers add the stage).
/// The runner calls this for every stage before any stage runs
/// (`stages::check_params`); `StageCtx::typed_params` calls it in the body.
pub fn parse_params<T: DeserializeOwned>(params: &toml::Table) -> std::result::Result<T, String> {
    // Through TOML text, so a type error carries a span that points at its key.
    let text = toml::to_string(params).map_err(|e| format!("[stage.params]: {e}"))?;
    toml::from_str::<T>(&text).map_err(|e| {
        let key = e.span().and_then(|span| {
            let line_start = text[..span.start.min(text.len())].rfind('\n').map_or(0, |i| i + 1);
            let line = &text[line_start..];
            let (k, _) = line.split_once('=')?;
            Some(k.trim().trim_matches('"').to_string())
        });
        let msg = e.message().trim().to_string();
        match key {
            // "missing field `x`" and "unknown field `x`" name their key already.
            Some(k) if !k.is_empty() && !msg.contains("field `") => format!("[stage.params] {k}: {msg}"),
            _ => format!("[stage.params]: {msg}"),
        }
    })
}

/// The four files of a multi-panel sheet (as [`StageCtx::write_sheet`]
/// stages them), for writers outside a stage (`cargo xtask merge-shards`).
pub(crate) fn sheet_files(sheet: &Sheet) -> Result<Vec<(String, Vec<u8>)>> {
    let svg = rig_figures::render_sheet_svg(sheet).with_context(|| format!("figure {}", sheet.id))?;
    let png = rig_figures::render_sheet_png(sheet).with_context(|| format!("figure {}", sheet.id))?;
    let csv = rig_figures::sheet_csv(sheet);
    Ok(figure_files(&sheet.id, svg, png, (&sheet.title, &sheet.caption), csv))
}

/// `figures/<id>.svg`, `.png`, `.txt` (title and caption) and `.csv`.
fn figure_files(
    id: &str,
    svg: String,
    png: Vec<u8>,
    (title, caption): (&str, &str),
    csv: String,
) -> Vec<(String, Vec<u8>)> {
    vec![
        (format!("figures/{id}.svg"), svg.into_bytes()),
        (format!("figures/{id}.png"), png),
        (format!("figures/{id}.txt"), format!("{title}\n\n{caption}\n").into_bytes()),
        (format!("figures/{id}.csv"), csv.into_bytes()),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct P {
        rtol: f64,
        points: usize,
        name: String,
    }

    fn err(text: &str) -> String {
        parse_params::<P>(&toml::from_str(text).unwrap()).unwrap_err()
    }

    #[test]
    fn parse_params_names_the_key() {
        let ok = parse_params::<P>(&toml::from_str("rtol = 1e-8\npoints = 3\nname = \"a\"").unwrap()).unwrap();
        assert_eq!(ok.points, 3);
        let e = err("rtol = 1e-8\npoints = 3\nname = \"a\"\nrtoll = 2.0");
        assert!(e.starts_with("[stage.params]") && e.contains("`rtoll`"), "{e}");
        let e = err("rtol = \"x\"\npoints = 3\nname = \"a\"");
        assert!(e.starts_with("[stage.params] rtol: "), "{e}");
        let e = err("rtol = 1.0\npoints = -3\nname = \"a\"");
        assert!(e.starts_with("[stage.params] points: "), "{e}");
        let e = err("rtol = 1.0\nname = \"a\"");
        assert_eq!(e, "[stage.params]: missing field `points`");
    }
}
