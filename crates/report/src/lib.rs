//! The report: one self-contained HTML page (reports/index.html) a
//! researcher reads first — the findings summary on the first screen
//! (`summary.rs`), how to rerun, the audit of the thesis' published
//! numbers, every chapter-4 figure with its caption (or why it is not
//! reproduced), the estimation, the diagnosis and the other stages' reports —
//! plus figures.md, the figure list with its reproducibility status. The
//! `report` stage writes what [`build`] returns.
//!
//! Not an analysis crate: it reads whatever the other stages left in the out
//! dir (their tables, figures and `.md` files, by the file layout the runner
//! defines) and knows no physics. [`diff`] compares an out dir with the one a
//! git revision committed (`cargo xtask diff`); both read CSV with
//! [`diff::parse_csv`], one parser.
//!
//! The page has no network dependency: inline CSS, figures as inline SVG, no
//! fonts or scripts from elsewhere. A file an upstream stage did not write
//! is shown as a visible "not produced" note, never a failure, so the page
//! can be read while the pipeline is incomplete. Deterministic: files are
//! listed in sorted order, nothing reads the clock.

mod audit;
pub mod diff;
mod markdown;
mod summary;

use crate::diff::parse_csv;
use anyhow::{Context, Result};
use audit::{audit_badges, audit_counts, csv_table, section_audit, status_column};
use markdown::{escape, to_html};
use serde::Deserialize;
use std::path::Path;

/// The figure catalogue of chapter 4 (data/figures.toml), compiled in so the
/// stage needs no path to the repository; its key covers it (`code.rs` follows `include_str!`).
static CATALOGUE: &str = include_str!("../../../data/figures.toml");

/// Tables longer than this show their first rows only (the CSV is beside the page).
const TABLE_ROWS_SHOWN: usize = 200;

#[derive(Debug, Deserialize)]
struct Catalogue {
    figure: Vec<CatalogueEntry>,
}

#[derive(Debug, Deserialize)]
struct CatalogueEntry {
    number: String,
    caption: String,
    reproducible: bool,
    #[serde(default)]
    reason: Option<String>,
    /// File-stem prefix in figures/ (e.g. `fig-4-17` for fig-4-17a, fig-4-17b).
    #[serde(default)]
    files: Option<String>,
    #[serde(default)]
    stages: Vec<String>,
}

fn catalogue() -> Result<Vec<CatalogueEntry>> {
    let c: Catalogue = toml::from_str(CATALOGUE).context("data/figures.toml: not a valid figure catalogue")?;
    for e in &c.figure {
        if e.reproducible && e.files.is_none() {
            anyhow::bail!("data/figures.toml: figure {} is reproducible but names no `files` prefix", e.number);
        }
        if !e.reproducible && e.reason.is_none() {
            anyhow::bail!("data/figures.toml: figure {} is not reproducible but gives no `reason`", e.number);
        }
    }
    Ok(c.figure)
}

/// The report's two files.
pub struct Report {
    /// `index.html`.
    pub index_html: String,
    /// `figures.md`.
    pub figures_md: String,
}

/// The report of the out dir `out` (campaign folder `campaign_dir`, named on
/// the page when diagnosis.json does not name the campaign).
pub fn build(out: &Path, campaign_dir: &Path) -> Result<Report> {
    let entries = catalogue()?;
    let figures = FigureFiles::scan(&out.join("figures"));
    let index_html = page(out, campaign_dir, &entries, &figures)?;
    Ok(Report { index_html, figures_md: figures_md(&entries, &figures) })
}

/// The figure stems (file names without `.svg`) found in the out dir, sorted.
struct FigureFiles {
    dir: std::path::PathBuf,
    stems: Vec<String>,
}

impl FigureFiles {
    fn scan(dir: &Path) -> FigureFiles {
        let mut stems: Vec<String> = std::fs::read_dir(dir)
            .map(|rd| {
                rd.flatten()
                    .filter_map(|e| e.file_name().to_str().and_then(|n| n.strip_suffix(".svg")).map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        stems.sort();
        FigureFiles { dir: dir.to_path_buf(), stems }
    }

    /// Stems belonging to a catalogue prefix: the prefix itself, or the
    /// prefix followed by a panel letter or `-` (so `fig-4-1` never takes `fig-4-10`).
    fn matching(&self, prefix: &str) -> Vec<&str> {
        self.stems
            .iter()
            .filter(|s| {
                s.strip_prefix(prefix).is_some_and(|rest| {
                    rest.is_empty() || rest.starts_with(|c: char| c == '-' || c.is_ascii_lowercase())
                })
            })
            .map(String::as_str)
            .collect()
    }
}

fn read_opt(dir: &Path, rel: &str) -> Option<String> {
    std::fs::read_to_string(dir.join(rel)).ok()
}

fn not_produced(rel: &str, stage: &str) -> String {
    format!(
        "<p class=\"missing\">Not produced: <code>{}</code> (stage <code>{}</code> has not written it in this out dir).</p>\n",
        escape(rel),
        escape(stage)
    )
}

fn page(out: &Path, campaign_dir: &Path, entries: &[CatalogueEntry], figures: &FigureFiles) -> Result<String> {
    let diagnosis: Option<serde_json::Value> =
        read_opt(out, "diagnosis.json").and_then(|t| serde_json::from_str(&t).ok());
    let campaign = diagnosis
        .as_ref()
        .and_then(|d| d.get("campaign")?.as_str().map(str::to_string))
        .or_else(|| campaign_dir.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "campaign".to_string());

    let mut body = String::new();
    let sections = [
        ("rerun", "How to rerun"),
        ("audit", "Published numbers, recomputed"),
        ("figures", "Figures of chapter 4"),
        ("more-figures", "Further figures"),
        ("estimation", "Estimation"),
        ("diagnosis", "Diagnosis"),
        ("sweeps", "Sweeps"),
        ("harmonic", "Eq. 4-11 (harmonic friction)"),
        ("lavi", "UFRJ LAVI 2018 recording"),
        ("confusion", "Blind diagnosis of hidden effects"),
        ("tables", "All tables"),
    ];
    body.push_str(&format!("<h1>rig-lab report — campaign <code>{}</code></h1>\n", escape(&campaign)));
    let others = other_diagnoses(out);
    body.push_str(&section_summary(out, diagnosis.as_ref(), &others));
    body.push_str(
        "<p>Chapter 4 of the thesis (torsional-vibration test rig) recomputed from its published tables and from a \
         measuring campaign: calibrated models, the chapter's figures and a diagnosis of what the model gets wrong.</p>\n",
    );
    // A `<stem>-diagnosis.json` whose stem has no section of its own gets one
    // (its `<stem>.md`, titled by its campaign), before the tables.
    let extra: Vec<(&str, &str)> = others
        .iter()
        .filter(|(stem, _)| !sections.iter().any(|(id, _)| id == stem))
        .map(|(stem, d)| (stem.as_str(), d.get("campaign").and_then(|c| c.as_str()).unwrap_or(stem.as_str())))
        .collect();
    body.push_str("<nav><ol>");
    let (fixed, tables) = sections.split_at(sections.len() - 1);
    for (id, title) in fixed.iter().chain(&extra).chain(tables) {
        body.push_str(&format!("<li><a href=\"#{id}\">{}</a></li>", escape(title)));
    }
    body.push_str("</ol></nav>\n");

    body.push_str(&section_rerun());
    body.push_str(&section_audit(out));
    let (figs, more) = section_figures(entries, figures);
    body.push_str(&figs);
    body.push_str(&more);
    body.push_str(&section_md(out, "estimation", "Estimation", "estimation.md", "estimation"));
    body.push_str(&section_diagnosis(out, diagnosis.as_ref()));
    body.push_str(&section_md(out, "sweeps", "Sweeps", "sweeps.md", "sweeps"));
    body.push_str(&section_md(out, "harmonic", "Eq. 4-11 (harmonic friction)", "harmonic.md", "harmonic"));
    body.push_str(&section_md(out, "lavi", "UFRJ LAVI 2018 recording", "lavi.md", "lavi"));
    body.push_str(&section_md(out, "confusion", "Blind diagnosis of hidden effects", "confusion.md", "confusion"));
    for (stem, title) in extra {
        body.push_str(&section_md(out, stem, title, &format!("{stem}.md"), stem));
    }
    body.push_str(&section_tables(out));

    let n_svg = body.matches("<svg").count();
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>rig-lab report — {}</title>\n<style>\n{CSS}</style>\n</head>\n<body data-figures=\"{n_svg}\">\n<main>\n{body}\
         <p id=\"page-check\" hidden>script did not run</p>\n<p id=\"summary-check\" hidden>script did not run</p>\n</main>\n<script>\n{CHECK_SCRIPT}</script>\n</body>\n</html>\n",
        escape(&campaign)
    ))
}

/// Every `<stem>-diagnosis.json` of the out dir but the campaign's own
/// diagnosis.json (the real recordings: lavi, slider …), sorted by stem; a file
/// that is not valid JSON is skipped here and named in the summary.
fn other_diagnoses(out: &Path) -> Vec<(String, serde_json::Value)> {
    diagnosis_files(out)
        .into_iter()
        .filter_map(|(stem, name)| {
            let v = serde_json::from_str(&read_opt(out, &name)?).ok()?;
            Some((stem, v))
        })
        .collect()
}

/// (stem, file name) of every `<stem>-diagnosis.json` in the out dir, sorted.
fn diagnosis_files(out: &Path) -> Vec<(String, String)> {
    let mut files: Vec<(String, String)> = std::fs::read_dir(out)
        .map(|rd| {
            rd.flatten()
                .filter_map(|e| {
                    let name = e.file_name().to_str()?.to_string();
                    let stem = name.strip_suffix("-diagnosis.json").filter(|s| !s.is_empty())?.to_string();
                    Some((stem, name))
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// The findings summary (`summary.rs`): the first thing on the page.
fn section_summary(
    out: &Path,
    diagnosis: Option<&serde_json::Value>,
    others: &[(String, serde_json::Value)],
) -> String {
    let mut rows = String::new();
    match diagnosis {
        Some(d) => rows.push_str(&summary::diagnosis_rows(d, "diagnosis", "Verdict", true)),
        None => rows.push_str(&format!(
            "<tr><th><a href=\"#diagnosis\">Verdict</a></th><td class=\"missing\">{}</td></tr>\n",
            if out.join("diagnosis.json").exists() { "diagnosis.json is not valid JSON" } else { "not produced" }
        )),
    }
    let audit = match read_opt(out, "audit.csv").map(|t| parse_csv(&t)) {
        Some(rows) => match audit_counts(&rows) {
            Some((counts, total)) => {
                format!("{} of {total} numbers and statements the chapter prints, recomputed", audit_badges(counts))
            }
            None => "audit.csv has no status column".to_string(),
        },
        None => "not produced".to_string(),
    };
    rows.push_str(&format!("<tr><th><a href=\"#audit\">Published numbers</a></th><td>{audit}</td></tr>\n"));
    for (stem, d) in others {
        let campaign = d.get("campaign").and_then(|c| c.as_str()).unwrap_or(stem.as_str());
        rows.push_str(&summary::diagnosis_rows(d, stem, &format!("Real data: {campaign}"), false));
    }
    for (stem, name) in diagnosis_files(out).iter().filter(|(stem, _)| !others.iter().any(|(s, _)| s == stem)) {
        rows.push_str(&format!(
            "<tr><th>{}</th><td class=\"missing\">{} is not valid JSON</td></tr>\n",
            escape(stem),
            escape(name)
        ));
    }
    format!(
        "<section id=\"summary\">\n<h2>What was found</h2>\n<table class=\"summary\">\n<tbody>\n{rows}</tbody>\n</table>\n</section>\n"
    )
}

/// Inline style: system fonts only, audit colours, figures scaled to the column.
const CSS: &str = "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:0;background:#fafafa;color:#222;line-height:1.45}
main{max-width:1180px;margin:0 auto;padding:1.5em 2em;background:#fff}
h1{font-size:1.6em}h2{border-bottom:2px solid #ddd;padding-bottom:.2em;margin-top:2em}
code,pre{font-family:ui-monospace,'DejaVu Sans Mono',monospace;font-size:.92em}
pre{background:#f3f3f3;padding:.7em 1em;overflow-x:auto}
table{border-collapse:collapse;margin:.8em 0;font-size:.9em}
th,td{border:1px solid #ccc;padding:.25em .55em;vertical-align:top}th{background:#f0f0f0}
td.num{text-align:right;font-variant-numeric:tabular-nums}
tr.ok td{background:#e3f4e6}tr.rounding td{background:#fff1cc}tr.inconsistent td{background:#fbdcdc}tr.note td{background:#e6eef8}
span.ok,span.rounding,span.inconsistent,span.note{padding:0 .4em;border-radius:3px}
span.ok{background:#bfe6c6}span.rounding{background:#ffe08a}span.inconsistent{background:#f5b5b5}span.note{background:#c9d9ef}
#summary{margin:.4em 0 1em}#summary h2{margin-top:.2em;font-size:1.25em}
table.summary{font-size:.92em;margin:.3em 0;width:100%}table.summary th{text-align:left;white-space:nowrap;width:1%}
table.summary th a{color:inherit}table.summary td{line-height:1.35}
ul.findings{margin:.1em 0 0;padding-left:1.3em}
.missing{color:#8a5a00;background:#fff6e0;border-left:4px solid #e0a000;padding:.4em .8em}
figure{margin:1.2em 0;padding:.6em;border:1px solid #e4e4e4}figure svg{max-width:100%;height:auto;display:block}
figcaption{font-size:.92em;color:#333}figcaption .thesis{color:#555;font-style:italic}
.fig-head{font-weight:bold;margin-top:1.6em}.fig-skip{margin:.3em 0;color:#555}.verdict{font-size:1.2em}
details{margin:.4em 0}summary{cursor:pointer}
";

/// Proves in a browser that the page parsed, every inline figure is an SVG
/// element with a size and nothing external is loaded, and measures where the
/// findings summary ends (it must fit the first screen);
/// scripts/check-report.sh reads both results from the DOM.
const CHECK_SCRIPT: &str = "(function(){
  var el=document.getElementById('page-check');
  var want=parseInt(document.body.getAttribute('data-figures'),10);
  var figs=document.querySelectorAll('svg');
  var bad=0;
  for(var i=0;i<figs.length;i++){var b=figs[i].getBoundingClientRect();if(!(b.width>0&&b.height>0)){bad++;}}
  // A self-contained page loads nothing: no element that fetches a resource.
  var ext=document.querySelectorAll('img,link,iframe,object,embed,script[src],use[href]').length+performance.getEntriesByType('resource').length;
  el.textContent=(figs.length===want&&bad===0&&ext===0)?('page-check ok: '+figs.length+' figures'):('page-check FAILED: '+figs.length+' of '+want+' figures, '+bad+' without size, '+ext+' external resources');
  // Where the findings summary ends, in CSS pixels from the top of the page at this window's width.
  var sum=document.getElementById('summary');
  document.getElementById('summary-check').textContent=sum?('summary-bottom '+Math.ceil(sum.getBoundingClientRect().bottom+window.scrollY)+' width '+window.innerWidth):'summary missing';
})();
";

fn section_rerun() -> String {
    "<h2 id=\"rerun\">How to rerun</h2>\n\
     <pre><code>cargo xtask reproduce          # the pipeline → reports/ (tables, figures, audit, diagnosis, index.html)\n\
     cargo nextest run --workspace  # the tests (snapshot regression included)</code></pre>\n\
     <p>The confusion battery (13 blind diagnoses, about a minute) runs on demand; a default run says whether its section is current:</p>\n\
     <pre><code>cargo xtask reproduce --all</code></pre>\n\
     <p>Any campaign folder in the <code>rig-campaign/1</code> format, into any out dir:</p>\n\
     <pre><code>cargo xtask reproduce --campaign DIR --out OUT</code></pre>\n\
     <p>Compare every table and figure series with a git revision, at printed precision:</p>\n\
     <pre><code>cargo xtask diff --baseline REV</code></pre>\n"
        .to_string()
}

/// One figure: inline SVG (PNG only if the SVG is missing would need base64;
/// every stage writes both through `write_figure`) and the stage's caption.
fn figure_block(figures: &FigureFiles, stem: &str) -> String {
    let svg = read_opt(&figures.dir, &format!("{stem}.svg")).unwrap_or_default();
    let mut s = format!("<figure id=\"{}\">\n{}", escape(stem), svg.trim_end());
    s.push_str("\n<figcaption>");
    if let Some(txt) = read_opt(&figures.dir, &format!("{stem}.txt")) {
        // write_figure's caption file: title, blank line, caption paragraph.
        let (title, caption) = txt.split_once("\n\n").unwrap_or((txt.as_str(), ""));
        s.push_str(&format!("<strong>{}</strong> {}", escape(title.trim()), escape(caption.trim())));
    }
    s.push_str(&format!(
        " <br><small><code>figures/{0}.svg</code> · <a href=\"figures/{0}.png\">PNG</a> · <a href=\"figures/{0}.csv\">data</a></small>",
        escape(stem)
    ));
    s.push_str("</figcaption>\n</figure>\n");
    s
}

/// The chapter's figures in catalogue order, then every other figure file.
fn section_figures(entries: &[CatalogueEntry], figures: &FigureFiles) -> (String, String) {
    let mut s = String::from("<h2 id=\"figures\">Figures of chapter 4</h2>\n");
    let reproduced =
        entries.iter().filter(|e| e.files.as_deref().is_some_and(|p| !figures.matching(p).is_empty())).count();
    let reproducible = entries.iter().filter(|e| e.reproducible).count();
    s.push_str(&format!(
        "<p>{} figures in the chapter; {} reproducible from data, {} reproduced in this out dir; \
         the others are photographs or schematics.</p>\n",
        entries.len(),
        reproducible,
        reproduced
    ));
    let mut claimed = std::collections::BTreeSet::new();
    for e in entries {
        if !e.reproducible {
            // One line: there is nothing to compute for a photograph or a schematic.
            s.push_str(&format!(
                "<p class=\"fig-skip\" id=\"fig-{}\"><strong>Figure {}</strong> <em>{}</em> — not reproducible: {}.</p>\n",
                escape(&e.number),
                escape(&e.number),
                escape(&e.caption),
                escape(e.reason.as_deref().unwrap_or("no reason given"))
            ));
            continue;
        }
        s.push_str(&format!(
            "<div class=\"fig-head\" id=\"fig-{0}\">Figure {0}</div>\n<p class=\"thesis\">Thesis caption: <em>{1}</em></p>\n",
            escape(&e.number),
            escape(&e.caption)
        ));
        let prefix = e.files.as_deref().unwrap_or_default();
        let stems = figures.matching(prefix);
        if stems.is_empty() {
            let stage = e.stages.join(", ");
            s.push_str(&not_produced(&format!("figures/{prefix}*.svg"), &stage));
        }
        for stem in stems {
            claimed.insert(stem.to_string());
            s.push_str(&figure_block(figures, stem));
        }
    }
    let mut more = String::from("<h2 id=\"more-figures\">Further figures</h2>\n");
    let others: Vec<&String> = figures.stems.iter().filter(|s| !claimed.contains(*s)).collect();
    if others.is_empty() {
        more.push_str(
            "<p>None in this out dir (overlays, diagnosis and LAVI figures appear here when produced).</p>\n",
        );
    }
    for stem in others {
        more.push_str(&figure_block(figures, stem));
    }
    (s, more)
}

fn section_md(out: &Path, id: &str, title: &str, rel: &str, stage: &str) -> String {
    let mut s = format!("<h2 id=\"{id}\">{}</h2>\n", escape(title));
    match read_opt(out, rel) {
        Some(md) => s.push_str(&to_html(&md, 2)),
        None => s.push_str(&not_produced(rel, stage)),
    }
    s
}

/// A JSON value as short text: strings bare, numbers as serde_json prints them.
fn json_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Null => "—".to_string(),
        other => other.to_string(),
    }
}

fn section_diagnosis(out: &Path, diagnosis: Option<&serde_json::Value>) -> String {
    let mut s = String::from("<h2 id=\"diagnosis\">Diagnosis</h2>\n");
    match diagnosis {
        None if out.join("diagnosis.json").exists() => {
            s.push_str("<p class=\"missing\">diagnosis.json exists but is not valid JSON.</p>\n");
        }
        None => s.push_str(&not_produced("diagnosis.json", "diagnosis")),
        Some(d) => {
            let verdict = d.get("verdict").map(json_text).unwrap_or_else(|| "(no verdict field)".into());
            s.push_str(&format!(
                "<p class=\"verdict\">Verdict: <strong><code>{}</code></strong></p>\n",
                escape(&verdict)
            ));
            let findings = d.get("findings").and_then(|f| f.as_array()).cloned().unwrap_or_default();
            if findings.is_empty() {
                s.push_str(
                    "<p>No finding: the calibrated baseline explains the campaign, or nothing was identified.</p>\n",
                );
            }
            for f in &findings {
                let effect = f.get("effect").map(json_text).unwrap_or_default();
                s.push_str(&format!("<h3>Finding: <code>{}</code></h3>\n", escape(&effect)));
                if let Some(e) = f.get("evidence") {
                    s.push_str(&format!("<p>{}</p>\n", escape(&json_text(e))));
                }
                if let Some(params) = f.get("params").and_then(|p| p.as_object()) {
                    let stderr = f.get("params_stderr").and_then(|p| p.as_object());
                    s.push_str("<table>\n<thead><tr><th>parameter</th><th>estimate</th><th>standard error</th></tr></thead>\n<tbody>\n");
                    for (k, v) in params {
                        let se = stderr.and_then(|m| m.get(k)).map(json_text).unwrap_or_else(|| "—".into());
                        s.push_str(&format!(
                            "<tr><td><code>{}</code></td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>\n",
                            escape(k),
                            escape(&json_text(v)),
                            escape(&se)
                        ));
                    }
                    s.push_str("</tbody>\n</table>\n");
                }
                let mut facts = Vec::new();
                if let Some(runs) = f.get("heldout_runs").and_then(|r| r.as_array()) {
                    let names: Vec<String> = runs.iter().map(json_text).collect();
                    facts.push(format!("held-out runs: {}", names.join(", ")));
                }
                for (key, label) in [
                    ("heldout_misfit_baseline", "held-out misfit, baseline"),
                    ("heldout_misfit_extended", "held-out misfit, extended"),
                    ("relative_gain", "relative gain"),
                ] {
                    if let Some(v) = f.get(key) {
                        facts.push(format!("{label}: {}", json_text(v)));
                    }
                }
                if !facts.is_empty() {
                    s.push_str("<ul>");
                    for fact in facts {
                        s.push_str(&format!("<li>{}</li>", escape(&fact)));
                    }
                    s.push_str("</ul>\n");
                }
            }
            let candidates = d.get("candidates").and_then(|c| c.as_array()).cloned().unwrap_or_default();
            if !candidates.is_empty() {
                s.push_str("<h3>Candidates tried</h3>\n");
                // Columns: `effect` first, then every other key in sorted order.
                let mut keys: Vec<String> = candidates
                    .iter()
                    .filter_map(|c| c.as_object())
                    .flat_map(|o| o.keys().cloned())
                    .filter(|k| k != "effect")
                    .collect::<std::collections::BTreeSet<_>>()
                    .into_iter()
                    .collect();
                keys.insert(0, "effect".to_string());
                let mut rows = vec![keys.clone()];
                for c in &candidates {
                    rows.push(keys.iter().map(|k| c.get(k).map(json_text).unwrap_or_default()).collect());
                }
                s.push_str(&csv_table(&rows, None));
            }
        }
    }
    match read_opt(out, "diagnosis.md") {
        Some(md) => s.push_str(&to_html(&md, 2)),
        None => s.push_str(&not_produced("diagnosis.md", "diagnosis")),
    }
    s
}

fn section_tables(out: &Path) -> String {
    let mut s = String::from("<h2 id=\"tables\">All tables</h2>\n");
    let mut names: Vec<String> = std::fs::read_dir(out.join("tables"))
        .map(|rd| {
            rd.flatten()
                .filter_map(|e| e.file_name().to_str().filter(|n| n.ends_with(".csv")).map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    if names.is_empty() {
        s.push_str(&not_produced("tables/*.csv", "every analysis stage"));
    }
    for name in names {
        let rows = parse_csv(&read_opt(&out.join("tables"), &name).unwrap_or_default());
        // A large table's Parquet twin (StageCtx::write_table_with_parquet), for polars or pandas.
        let parquet = name.strip_suffix(".csv").map(|stem| format!("{stem}.parquet"));
        let link = match parquet.filter(|p| out.join("tables").join(p).is_file()) {
            Some(p) => format!(" · <a href=\"tables/{0}\">{0}</a>", escape(&p)),
            None => String::new(),
        };
        s.push_str(&format!(
            "<details><summary><code>tables/{}</code> ({} rows){link}</summary>\n{}</details>\n",
            escape(&name),
            rows.len().saturating_sub(1),
            csv_table(&rows, status_column(&rows))
        ));
    }
    s
}

/// figures.md: every chapter-4 figure with its reproducibility status and files.
fn figures_md(entries: &[CatalogueEntry], figures: &FigureFiles) -> String {
    let mut s = String::from(
        "# Figures of chapter 4\n\nStatus of every figure of the chapter in this out dir \
         (catalogue: `data/figures.toml`).\n\n| figure | thesis caption | status | stage | files |\n|---|---|---|---|---|\n",
    );
    let cell = |t: &str| t.replace('|', "\\|");
    for e in entries {
        let (status, files) = if !e.reproducible {
            (format!("not reproducible ({})", e.reason.as_deref().unwrap_or("")), String::new())
        } else {
            let stems = figures.matching(e.files.as_deref().unwrap_or_default());
            if stems.is_empty() {
                ("not produced".to_string(), String::new())
            } else {
                let list: Vec<String> = stems.iter().map(|s| format!("`{s}`")).collect();
                ("reproduced".to_string(), list.join(", "))
            }
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            e.number,
            cell(&e.caption),
            status,
            e.stages.join(", "),
            files
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_lists_every_figure_of_the_chapter() {
        let entries = catalogue().unwrap();
        let numbers: Vec<&str> = entries.iter().map(|e| e.number.as_str()).collect();
        let expected: Vec<String> = (1..=29).map(|n| format!("4.{n}")).collect();
        assert_eq!(numbers, expected);
        // The brief's list of photos and schematics: 4.1–4.7, 4.9, 4.13.
        let not: Vec<&str> = entries.iter().filter(|e| !e.reproducible).map(|e| e.number.as_str()).collect();
        assert_eq!(not, ["4.1", "4.2", "4.3", "4.4", "4.5", "4.6", "4.7", "4.9", "4.13"]);
    }

    #[test]
    fn prefixes_do_not_capture_neighbours() {
        let f = FigureFiles {
            dir: std::path::PathBuf::new(),
            stems: ["fig-4-10-thesis", "fig-4-17a", "fig-4-17b", "fig-4-1", "fig-4-170"].map(String::from).to_vec(),
        };
        assert_eq!(f.matching("fig-4-17"), ["fig-4-17a", "fig-4-17b"]);
        assert_eq!(f.matching("fig-4-1"), ["fig-4-1"]);
        assert_eq!(f.matching("fig-4-10"), ["fig-4-10-thesis"]);
    }

    #[test]
    fn audit_status_column_is_found_by_name_or_content() {
        let named = parse_csv("id,published,recomputed,status\na,1,1,ok\n");
        assert_eq!(status_column(&named), Some(3));
        let by_content = parse_csv("id,published,outcome\na,1,rounding\nb,2,inconsistent\n");
        assert_eq!(status_column(&by_content), Some(2));
        assert_eq!(status_column(&parse_csv("id,v\na,1\n")), None);
    }
}
