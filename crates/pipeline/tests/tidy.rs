//! The architecture's invariants as a test (ARCHITECTURE.md, "Invariants"):
//! dependency directions read from `cargo metadata`, rig-model's absence of
//! IO, the `//!` opening line of every source file, and stage keys that cover
//! every crate and module a stage uses.

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ANALYSIS: [&str; 11] = [
    "rig-types",
    "rig-ingest",
    "rig-calibrate",
    "rig-model",
    "rig-estimate",
    "rig-spectra",
    "rig-sweep",
    "rig-diagnose",
    "rig-figures",
    "rig-lavi",
    "rig-slider",
];

fn root() -> PathBuf {
    rig_pipeline::testing::workspace_root()
}

/// Package name -> [(dependency name, kinds: "normal" | "dev" | "build")], from the resolved graph.
struct Graph {
    edges: BTreeMap<String, Vec<(String, BTreeSet<String>)>>,
    members: BTreeSet<String>,
    /// Member name -> its folder relative to the workspace root.
    dirs: BTreeMap<String, String>,
}

fn metadata() -> Graph {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args(["metadata", "--format-version", "1"])
        .current_dir(root())
        .output()
        .expect("cargo metadata runs");
    assert!(out.status.success(), "cargo metadata: {}", String::from_utf8_lossy(&out.stderr));
    let meta: Value = serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON");
    let name_of: BTreeMap<String, String> = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["id"].as_str().unwrap().to_string(), p["name"].as_str().unwrap().to_string()))
        .collect();
    let members =
        meta["workspace_members"].as_array().unwrap().iter().map(|id| name_of[id.as_str().unwrap()].clone()).collect();
    let root_dir = root().canonicalize().unwrap();
    let dirs = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| members_contains(&meta, p["id"].as_str().unwrap()))
        .map(|p| {
            let manifest = PathBuf::from(p["manifest_path"].as_str().unwrap());
            let dir = manifest.parent().unwrap().canonicalize().unwrap();
            let rel = dir.strip_prefix(&root_dir).unwrap().to_string_lossy().replace('\\', "/");
            (p["name"].as_str().unwrap().to_string(), rel)
        })
        .collect();
    let mut edges = BTreeMap::new();
    for node in meta["resolve"]["nodes"].as_array().unwrap() {
        let name = name_of[node["id"].as_str().unwrap()].clone();
        let deps = node["deps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| {
                let kinds = d["dep_kinds"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|k| k["kind"].as_str().unwrap_or("normal").to_string())
                    .collect();
                (name_of[d["pkg"].as_str().unwrap()].clone(), kinds)
            })
            .collect::<Vec<_>>();
        edges.entry(name).or_insert_with(Vec::new).extend(deps);
    }
    Graph { edges, members, dirs }
}

fn members_contains(meta: &Value, id: &str) -> bool {
    meta["workspace_members"].as_array().unwrap().iter().any(|m| m.as_str() == Some(id))
}

impl Graph {
    /// Every package built for `pkg` or its tests: its own dependencies of any
    /// kind, then theirs of normal and build kind (dev-dependencies of a
    /// dependency are never built), transitively.
    fn reach(&self, pkg: &str) -> BTreeMap<String, String> {
        let mut seen: BTreeMap<String, String> = BTreeMap::new();
        let mut todo: Vec<(String, String)> = Vec::new();
        for (dep, _) in self.edges.get(pkg).into_iter().flatten() {
            todo.push((dep.clone(), format!("{pkg} -> {dep}")));
        }
        while let Some((p, path)) = todo.pop() {
            if seen.contains_key(&p) {
                continue;
            }
            for (dep, kinds) in self.edges.get(&p).into_iter().flatten() {
                if kinds.iter().any(|k| k != "dev") {
                    todo.push((dep.clone(), format!("{path} -> {dep}")));
                }
            }
            seen.insert(p, path);
        }
        seen
    }

    /// `pkg` and every package it needs to build (normal and build dependencies), transitively.
    fn normal_closure(&self, pkg: &str) -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut todo = vec![pkg.to_string()];
        while let Some(p) = todo.pop() {
            if !seen.insert(p.clone()) {
                continue;
            }
            for (dep, kinds) in self.edges.get(&p).into_iter().flatten() {
                if kinds.iter().any(|k| k != "dev") {
                    todo.push(dep.clone());
                }
            }
        }
        seen
    }

    fn direct(&self, pkg: &str) -> BTreeSet<String> {
        self.edges.get(pkg).into_iter().flatten().map(|(d, _)| d.clone()).collect()
    }
}

#[test]
fn dependencies_point_the_right_way() {
    let g = metadata();
    let mut problems = Vec::new();
    for pkg in ANALYSIS {
        assert!(g.members.contains(pkg), "{pkg} is not a workspace member");
        if let Some(path) = g.reach(pkg).get("rig-virtual-rig") {
            problems.push(format!("analysis crate {pkg} depends on rig-virtual-rig: {path}"));
        }
    }
    for pkg in &g.members {
        if pkg != "rig-figures" && g.direct(pkg).contains("plotters") {
            problems.push(format!("{pkg} depends on plotters; only rig-figures may draw"));
        }
    }
    let allowed: BTreeSet<String> = ["rig-pipeline", "clap", "anyhow"].map(String::from).into();
    let extra: Vec<String> = g.direct("xtask").difference(&allowed).cloned().collect();
    if !extra.is_empty() {
        problems.push(format!("xtask depends on {extra:?}; it may depend only on rig-pipeline, clap, anyhow"));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every `.rs` file under `dir`, sorted, skipping build output and hidden folders.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else { return out };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if p.is_dir() {
            if name != "target" && !name.starts_with('.') {
                out.extend(rust_files(&p));
            }
        } else if name.ends_with(".rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

#[test]
fn model_does_no_io() {
    let forbidden =
        ["std::fs", "std::io", "std::env", "std::net", "File::", "println!", "eprintln!", "print!", "eprint!", "dbg!"];
    let files = rust_files(&root().join("crates/model/src"));
    assert!(!files.is_empty(), "no sources found under crates/model/src");
    let mut problems = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, line) in text.lines().enumerate() {
            // Comments may name what the crate does not do.
            let code = line.split("//").next().unwrap_or("");
            for word in forbidden.iter().filter(|w| code.contains(*w)) {
                problems.push(format!("{}:{}: rig-model does no IO, found `{word}`", f.display(), i + 1));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_source_file_opens_with_a_module_doc_line() {
    let mut files = rust_files(&root().join("crates"));
    files.extend(rust_files(&root().join("xtask")));
    assert!(files.len() > 20, "only {} files found", files.len());
    let missing: Vec<String> = files
        .iter()
        .filter(|f| !std::fs::read_to_string(f).unwrap().starts_with("//!"))
        .map(|f| format!("{}: first line must be a `//!` line saying what the file is for", f.display()))
        .collect();
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// A stage's key must cover what its body uses: every workspace crate it names
/// (checked against `cargo metadata`, with that crate's dependencies), every
/// pipeline module it reaches, and nothing it names may be left unplaced.
#[test]
fn stage_keys_cover_what_stages_use() {
    let g = metadata();
    let root = root();
    let config = rig_pipeline::PipelineConfig::load(&root.join("pipeline.toml"), rig_pipeline::stages::lookup)
        .expect("pipeline.toml loads");
    let index = rig_pipeline::code::CodeIndex::load(&root).expect("the crate graph reads");
    let mut problems = Vec::new();
    for name in rig_pipeline::stages::names() {
        let Some(source) = rig_pipeline::stages::source(name) else {
            problems.push(format!("stage {name}: no source file registered in stages/mod.rs"));
            continue;
        };
        if !root.join(source).is_file() {
            problems.push(format!("stage {name}: source {source} does not exist"));
            continue;
        }
        let declared = config.stage(name).map(|d| d.code.clone()).unwrap_or_default();
        let code = index.stage_code(Some(source), &declared).expect("stage code computes");
        for u in &code.unresolved {
            problems.push(format!("stage {name}: {u} names nothing the key can cover (use a module path)"));
        }
        let covered = |path: &str| code.paths.iter().any(|p| p == path || path.starts_with(&format!("{p}/")));
        // The stage file and its folder, read independently of the scanner.
        let mut files = vec![root.join(source)];
        files.extend(rust_files(&root.join(source.trim_end_matches(".rs"))));
        for f in files {
            let text = std::fs::read_to_string(&f).unwrap();
            for member in &g.members {
                let lib = member.replace('-', "_");
                if !text.contains(&format!("{lib}::")) {
                    continue;
                }
                for needed in g.normal_closure(member).intersection(&g.members) {
                    let src = format!("{}/src", g.dirs[needed]);
                    if !covered(&src) {
                        problems.push(format!(
                            "stage {name}: {} uses {member}, which builds on {needed}, but {src} is not in its key",
                            f.display()
                        ));
                    }
                }
            }
            for word in text.split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')) {
                if let Some(rest) = word.strip_prefix("crate::") {
                    let module = rest.split("::").next().unwrap_or("");
                    let file = format!("crates/pipeline/src/{module}.rs");
                    if root.join(&file).is_file() && !covered(&file) {
                        problems.push(format!(
                            "stage {name}: {} uses crate::{module}, but {file} is not in its key",
                            f.display()
                        ));
                    }
                }
            }
        }
        if !covered("Cargo.lock") {
            problems.push(format!("stage {name}: Cargo.lock (external crate versions) is not in its key"));
        }
    }
    // The two holes the hand-written lists had (issue 11).
    let report = index.stage_code(rig_pipeline::stages::source("report"), &[]).unwrap();
    assert!(report.paths.contains("crates/report/src"), "report uses rig_report: {:?}", report.paths);
    assert!(report.paths.contains("data/figures.toml"), "report embeds data/figures.toml: {:?}", report.paths);
    let sweeps = index.stage_code(rig_pipeline::stages::source("sweeps"), &[]).unwrap();
    assert!(sweeps.paths.contains("crates/calibrate/src"), "sweeps uses rig_calibrate: {:?}", sweeps.paths);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Stages whose params are not a typed struct yet (owned by others; they add
/// `Some(typed::<Params>)` to their line in stages/mod.rs and leave this list).
const PARAMS_NOT_YET_TYPED: [&str; 0] = [];

/// Every stage's params are a `deny_unknown_fields` struct checked before any
/// stage runs, and the repository's pipeline.toml passes every check.
#[test]
fn every_stage_has_typed_params_and_pipeline_toml_passes() {
    let untyped = rig_pipeline::stages::untyped();
    let mut expected: Vec<&str> = PARAMS_NOT_YET_TYPED.to_vec();
    expected.sort();
    let mut got = untyped.clone();
    got.sort();
    assert_eq!(
        got, expected,
        "stages without a params type in stages/mod.rs (update PARAMS_NOT_YET_TYPED when one is converted)"
    );
    let config =
        rig_pipeline::PipelineConfig::load(&root().join("pipeline.toml"), rig_pipeline::stages::lookup).unwrap();
    for decl in &config.stages {
        if let Err(e) = rig_pipeline::stages::check_params(&decl.name, &decl.params) {
            panic!("pipeline.toml: stage {}: {e}", decl.name);
        }
    }
}

/// Every stage file is a thin adapter (≤ 150 lines, issue 11), and no stage imports another stage (shared helpers live in the crates).
#[test]
fn stage_files_are_thin() {
    let dir = root().join("crates/pipeline/src/stages");
    let mut problems = Vec::new();
    let stages: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".rs") && n != "mod.rs")
        .collect();
    for name in &stages {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        let lines = text.lines().count();
        if lines > 150 {
            problems.push(format!(
                "stages/{name} has {lines} lines; a stage reads, calls one analysis function, writes (≤ 150)"
            ));
        }
        for other in &stages {
            let module = other.trim_end_matches(".rs");
            if other != name && text.contains(&format!("super::{module}::")) {
                problems.push(format!("stages/{name} imports stage {module}: move the shared code into a crate"));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Files (outside `rig_types::units`) that still define their own rad/s → rpm
/// factor; owned by others, to switch to `rig_types::units::RAD_S_TO_RPM`.
const RPM_NOT_YET: [&str; 1] = ["crates/model/src/friction.rs"];

/// `const RAD_S_TO_RPM` with any visibility (`pub`, `pub(crate)`, none).
fn defines_rpm_factor(line: &str) -> bool {
    let mut l = line.trim_start();
    if let Some(rest) = l.strip_prefix("pub") {
        l = match rest.strip_prefix('(') {
            Some(r) => r.split_once(')').map_or("", |(_, after)| after),
            None => rest,
        };
    }
    l.trim_start().starts_with("const RAD_S_TO_RPM")
}

#[test]
fn the_rpm_factor_is_found_with_any_visibility() {
    for l in ["const RAD_S_TO_RPM: f64 = 1.0;", "pub const RAD_S_TO_RPM", "  pub(crate) const RAD_S_TO_RPM: f64"] {
        assert!(defines_rpm_factor(l), "{l}");
    }
    assert!(!defines_rpm_factor("let rpm = w * RAD_S_TO_RPM;") && !defines_rpm_factor("use units::RAD_S_TO_RPM;"));
}

/// One unit conversion, one home: `rig_types::units`.
#[test]
fn unit_conversions_have_one_home() {
    let mut files = rust_files(&root().join("crates"));
    files.retain(|f| !f.ends_with("crates/types/src/units.rs"));
    let problems: Vec<String> = files
        .iter()
        .filter(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            text.lines().any(defines_rpm_factor)
        })
        .filter(|f| !RPM_NOT_YET.iter().any(|n| f.ends_with(n)))
        .map(|f| format!("{}: defines RAD_S_TO_RPM; use rig_types::units::RAD_S_TO_RPM", f.display()))
        .collect();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// One rendering convention: the module that turns a crate's results into
/// `Table`s, `FigureSpec`s and markdown is `render` (`render.rs` or
/// `render/`), in every crate; `report` is only the crate of the HTML page
/// (`rig-report`, whose files are `lib.rs`, `markdown.rs`, `diff.rs`) and
/// the pipeline's stage that calls it (`stages/report.rs`).
#[test]
fn rendering_has_one_name() {
    let allowed = ["crates/pipeline/src/stages/report.rs"];
    let root = root();
    let problems: Vec<String> = rust_files(&root.join("crates"))
        .iter()
        .filter_map(|f| {
            let rel = f.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
            let stem = f.file_stem()?.to_string_lossy().into_owned();
            let named = ["output", "tables", "figures", "report"].contains(&stem.as_str());
            (named && rel.contains("/src/") && !allowed.contains(&rel.as_str())).then(|| {
                format!("{rel}: results are rendered in a module named `render` (ARCHITECTURE.md, Invariants)")
            })
        })
        .collect();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
