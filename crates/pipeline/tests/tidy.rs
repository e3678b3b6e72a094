//! The architecture's invariants as a test (ARCHITECTURE.md, "Invariants"):
//! dependency directions read from `cargo metadata`, rig-model's absence of
//! IO, and the `//!` opening line of every source file.

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ANALYSIS: [&str; 10] = [
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
];

fn root() -> PathBuf {
    rig_pipeline::testing::workspace_root()
}

/// Package name -> [(dependency name, kinds: "normal" | "dev" | "build")], from the resolved graph.
struct Graph {
    edges: BTreeMap<String, Vec<(String, BTreeSet<String>)>>,
    members: BTreeSet<String>,
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
    Graph { edges, members }
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
