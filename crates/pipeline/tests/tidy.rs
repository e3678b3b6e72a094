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
    // xtask builds and runs the `rig-lab` binary; with no dependency its
    // freshness check (part of every `cargo xtask` call) walks one crate.
    let extra = g.direct("xtask");
    if !extra.is_empty() {
        problems.push(format!("xtask depends on {extra:?}; it uses the standard library only"));
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

/// Code lines (comments dropped, spaces and `std::f64::consts::` removed) of
/// every `.rs` file under crates/ and xtask/, with the file and line number.
fn code_lines() -> Vec<(PathBuf, usize, String)> {
    let mut files = rust_files(&root().join("crates"));
    files.extend(rust_files(&root().join("xtask")));
    let mut out = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            let squeezed: String =
                code.replace("std::f64::consts::", "").chars().filter(|c| !c.is_whitespace()).collect();
            if !squeezed.is_empty() {
                out.push((f.clone(), i + 1, squeezed));
            }
        }
    }
    out
}

/// Lines of code containing any of `patterns`, outside the files whose path
/// ends with one of `homes`, as "file:line: what".
fn written_outside(patterns: &[&str], homes: &[&str], what: &str) -> Vec<String> {
    code_lines()
        .into_iter()
        .filter(|(f, _, _)| !homes.iter().any(|h| f.ends_with(h)))
        .filter_map(|(f, i, code)| {
            let hit = patterns.iter().find(|p| code.contains(*p))?;
            Some(format!("{}:{i}: `{hit}`: {what}", f.display()))
        })
        .collect()
}

/// One unit conversion, one home: `rig_types::units` (the factor in any
/// spelling: a constant, 2π/60, π/30, 60/(2π), 30/π, τ/60).
#[test]
fn unit_conversions_have_one_home() {
    let patterns = [
        "constRAD_S_TO_RPM",
        "constRPM_TO_RAD_S",
        "PI/60.0",
        "PI/30.0",
        "30.0/PI",
        "60.0/(2.0*PI)",
        "60.0/PI/2.0",
        "TAU/60.0",
        "60.0/TAU",
        "PI)/60.0",
    ];
    let problems = written_outside(
        &patterns,
        &["crates/types/src/units.rs", "crates/pipeline/tests/tidy.rs"],
        "an rpm factor; use rig_types::units",
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// One clock: an analysis reads the records' sample rate through
/// `Campaign::clock_rate_hz` (the time columns' measured step, the declared
/// `sample_rate_hz` within `rig_types::sensor::CLOCK_TOLERANCE`), never the
/// declaration itself: a derivative divided by a declared rate 2 % off the
/// recorder's clock is 2 % off (docs/findings.md, twenty-first session,
/// h/clock). The reader checks the declaration, the virtual rig writes it,
/// and tests build campaigns with it.
#[test]
fn the_declared_sample_rate_is_read_in_one_place() {
    let problems: Vec<String> = written_outside(
        &["rig.sample_rate_hz"],
        &["crates/types/src/campaign.rs", "crates/pipeline/tests/tidy.rs"],
        "the declared sample rate read directly; use Campaign::clock_rate_hz",
    )
    .into_iter()
    .filter(|p| !["crates/ingest/", "crates/virtual-rig/", "/tests/"].iter().any(|d| p.contains(d)))
    .collect();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// One Stribeck law: μk + (μs − μk)·exp(−(Ω/vs)²) is
/// `rig_model::friction::stribeck_mu` / `stribeck_decay`. The virtual rig
/// keeps its own physics (the generator's truth is written independently of
/// the analysis), so it is not held to this.
#[test]
fn the_stribeck_law_has_one_home() {
    let patterns = [".powi(2)).exp()", ").powf("];
    let mut problems = written_outside(
        &patterns[..1],
        &["crates/model/src/friction.rs", "crates/pipeline/tests/tidy.rs"],
        "a Stribeck exponential; use rig_model::friction::stribeck_mu",
    );
    // exp(−(Ω/vs)^δ) with a fitted exponent.
    problems.extend(
        code_lines()
            .into_iter()
            .filter(|(f, _, code)| code.contains(patterns[1]) && code.contains(")).exp()") && !f.ends_with("tidy.rs"))
            .map(|(f, i, _)| format!("{}:{i}: a Stribeck exponential; use rig_model::friction", f.display())),
    );
    // Library code only: a test may shape synthetic data with a Gaussian; the
    // virtual rig keeps its own physics.
    problems.retain(|p| p.contains("/src/") && !p.contains("crates/virtual-rig/"));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// One linear least-squares solver: `rig_types::linear` (faer's Cholesky
/// behind `spd_solve`, `spd_inverse`, `Normal`, `ArrowNormal`, `ols`,
/// `ols_eiv`, `iv`; `rig_estimate::linear` re-exports it). Nothing else
/// factorises a matrix or writes its own normal-equation solver.
#[test]
fn linear_least_squares_has_one_home() {
    let patterns = [
        ".llt(",
        ".ldlt(",
        "partial_piv_lu(",
        "full_piv_lu(",
        ".qr(",
        "col_piv_qr(",
        ".svd(",
        "fncholesky",
        "fncho_solve",
        "fnsolve_with_inverse",
        "fngauss_jordan",
        "fnsolve_linear",
        "fnsolve3",
    ];
    let homes = ["crates/types/src/linear.rs", "crates/pipeline/tests/tidy.rs"];
    let problems = written_outside(&patterns, &homes, "a linear solver; use rig_estimate::linear");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Where code outside the engine writes a forward-selection loop of its
/// own, as "file:line: marker". The markers, on code lines with comments
/// and spaces dropped: selection steps numbered in a loop (`for step in 1..`,
/// the trace's numbering), and models ranked by their step comparison's
/// gain (`.gain.total_cmp(`, [`rig_types::select::Comparison`]'s field: the
/// pick of a step's best). The engine (`crates/types/src/select/`) is
/// their one home; everyone else implements `Study`/`Candidate` and calls
/// `forward_select` / `forward_select_from`.
fn own_selection_loops(lines: &[(PathBuf, usize, String)]) -> Vec<String> {
    let markers = ["forstepin1..", ".gain.total_cmp("];
    let homes = ["crates/types/src/select/mod.rs", "crates/types/src/select/views.rs", "crates/pipeline/tests/tidy.rs"];
    lines
        .iter()
        .filter(|(f, _, _)| !homes.iter().any(|h| f.ends_with(h)))
        .filter_map(|(f, i, code)| {
            let hit = markers.iter().find(|m| code.contains(*m))?;
            Some(format!(
                "{}:{i}: `{hit}`: a forward-selection loop of its own; put the candidates on rig_types::select",
                f.display()
            ))
        })
        .collect()
}

/// One forward-selection engine: `rig_types::select` (the diagnosis'
/// vocabulary, the LAVI and the slider studies run on it). No crate writes
/// its own step loop or ranks candidates by their gain itself.
#[test]
fn forward_selection_has_one_engine() {
    let lines = code_lines();
    let mut problems = own_selection_loops(&lines);
    problems.extend(selections_off_the_engine(&lines));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every selection of the workspace, by the file that runs it, and what it
/// selects: each must call the engine (`forward_select`,
/// `forward_select_from` or `select_on_views`, on code lines). The markers of
/// [`own_selection_loops`] see a step loop or a ranking by gain; this sees a
/// selection that left the engine in any other spelling (the structural
/// candidates ranked themselves by a (tier, gain) key and a filter of their own
/// before they moved onto `select_on_views`).
const SELECTIONS: [(&str, &str); 5] = [
    ("crates/diagnose/src/select.rs", "the thesis rig's vocabulary effects"),
    ("crates/diagnose/src/structure/selection.rs", "the thesis rig's structural candidates (three views)"),
    ("crates/diagnose/src/extension/mod.rs", "the `unexplained` answer's extension (library signals, free run)"),
    ("crates/lavi/src/select.rs", "the LAVI study's candidates"),
    ("crates/slider/src/study/mod.rs", "the slider's friction laws"),
];

/// The files of [`SELECTIONS`] with no call to the engine on a code line,
/// as "file: what".
fn selections_off_the_engine(lines: &[(PathBuf, usize, String)]) -> Vec<String> {
    let calls = ["forward_select(", "forward_select_from(", "select_on_views("];
    SELECTIONS
        .iter()
        .filter(|(file, _)| {
            !lines.iter().any(|(f, _, code)| f.ends_with(file) && calls.iter().any(|c| code.contains(c)))
        })
        .map(|(file, what)| format!("{file}: {what} selected without the engine (rig_types::select)"))
        .collect()
}

/// The rule sees a planted copy of the loop the diagnosis ran before it
/// moved onto the engine (it is not vacuous), and passes the engine's callers.
#[test]
fn a_planted_selection_loop_is_seen() {
    let planted = "
        for step in 1..=registry.len() {
            let best = tried
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.1.gain.total_cmp(&b.1.1.gain).then(b.0.cmp(&a.0)))
                .map(|(i, _)| i);
        }";
    let squeeze = |text: &str, file: &str| -> Vec<(PathBuf, usize, String)> {
        text.lines()
            .enumerate()
            .map(|(i, l)| (PathBuf::from(file), i + 1, l.chars().filter(|c| !c.is_whitespace()).collect()))
            .collect()
    };
    let seen = own_selection_loops(&squeeze(planted, "crates/diagnose/src/select.rs"));
    assert_eq!(seen.len(), 2, "{seen:?}");
    assert!(seen[0].starts_with("crates/diagnose/src/select.rs:2: `forstepin1..`"), "{seen:?}");
    let caller = "let sel = engine::forward_select_from(&study, &candidates, &baselines, &folds, &rule, &search)?;";
    assert!(own_selection_loops(&squeeze(caller, "crates/diagnose/src/select.rs")).is_empty());
    assert!(own_selection_loops(&squeeze(planted, "crates/types/src/select/mod.rs")).is_empty());
    // The extension's loop had an exception until it moved onto the engine: none now.
    let seen = own_selection_loops(&squeeze(planted, "crates/diagnose/src/extension/mod.rs"));
    assert_eq!(seen.len(), 2, "{seen:?}");
    // The structure's selection off the engine (its former pick) is seen; on it, not.
    let off = "let winner = (1..REGISTRY.len()).filter_map(|k| scored[k].as_ref().map(|x| (k, x)));";
    let seen = selections_off_the_engine(&squeeze(off, "crates/diagnose/src/structure/selection.rs"));
    assert!(seen.iter().any(|p| p.starts_with("crates/diagnose/src/structure/selection.rs: ")), "{seen:?}");
    let on = "let sel = select_on_views(&study, &cand_refs, &baselines, &folds, &rule, &search);";
    let seen = selections_off_the_engine(&squeeze(on, "crates/diagnose/src/structure/selection.rs"));
    assert!(!seen.iter().any(|p| p.starts_with("crates/diagnose/src/structure/selection.rs")), "{seen:?}");
}

/// pipeline.toml keys that two stages declare with the same value on purpose:
/// each is that stage's own physics, not a setting the stages must agree on.
const SAME_VALUE_ON_PURPOSE: [(&str, &str); 4] = [
    (
        "tolerance_bins",
        "spectra (measured signals) and harmonic (noise-free simulations) set their line tolerance for \
         their own noise; both 0.1 bin today, free to differ",
    ),
    (
        "sample_rate_hz",
        "the rate each study samples its own simulations at (sweeps: the classifier's spectral test up \
         to 10 Hz; harmonic: lines below 5 Hz); neither reads the other's",
    ),
    (
        "shard",
        "each sharded stage's own slice of its own job array (sweeps: the maps' chains; confusion: \
         the battery's campaigns); \"1/1\" is each one's unsharded default",
    ),
    (
        "adequacy_threshold",
        "the LAVI and slider studies each measure their misfit in units of their own feature targets \
         (1 = every feature at its bound); the same number, two scales",
    ),
];

/// Every non-table value of `t` and of the tables nested in it: its dotted
/// path (after `at`, ending in a dot, or `at` itself at the top), its key and
/// its value, in key order.
fn leaves<'a>(t: &'a toml::Table, at: &str) -> Vec<(String, &'a str, &'a toml::Value)> {
    let mut out = Vec::new();
    for (key, value) in t {
        match value.as_table() {
            Some(inner) => out.extend(leaves(inner, &format!("{at}{key}."))),
            None => out.push((at.to_string(), key.as_str(), value)),
        }
    }
    out
}

/// What breaks "no setting two stages must agree on is declared twice" in
/// a pipeline.toml text: a key of a `[shared.<name>]` table in a stage's
/// params (the spectral-band keys excepted: each study sets its band for its
/// own signals, rig_spectra's `LineAnalysisOptions`), or a key with the same
/// value in two stages' params that is not in `SAME_VALUE_ON_PURPOSE`.
fn declared_twice(text: &str) -> Vec<String> {
    let doc: toml::Table = toml::from_str(text).unwrap();
    let shared = doc.get("shared").and_then(|v| v.as_table()).cloned().unwrap_or_default();
    let stages = doc.get("stage").and_then(|v| v.as_array()).cloned().unwrap_or_default();
    let per_study = ["min_freq_hz", "max_freq_hz", "tolerance_bins"];
    let mut problems = Vec::new();
    let mut seen: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for st in &stages {
        let name = st.get("name").and_then(|v| v.as_str()).unwrap_or("?").to_string();
        let Some(params) = st.get("params").and_then(|v| v.as_table()) else { continue };
        // Nested tables too (`[stage.params.channels]`): a key's leaf name is
        // what a second declaration would repeat.
        for (_, key, value) in leaves(params, "") {
            for (table, keys) in &shared {
                let in_shared = keys.as_table().is_some_and(|t| t.contains_key(key));
                if in_shared && !per_study.contains(&key) {
                    problems.push(format!(
                        "stage {name}: `{key}` is declared in [shared.{table}]; list \"{table}\" in `shared`"
                    ));
                }
            }
            seen.entry(key.to_string()).or_default().push((name.clone(), value.to_string()));
        }
    }
    for (key, decls) in &seen {
        for (i, (a, va)) in decls.iter().enumerate() {
            for (b, vb) in &decls[i + 1..] {
                if a != b && va == vb && !SAME_VALUE_ON_PURPOSE.iter().any(|(k, _)| k == key) {
                    problems.push(format!(
                        "`{key} = {va}` is declared by stages {a} and {b}: one [shared.<name>] table, or list it \
                         in SAME_VALUE_ON_PURPOSE with the reason"
                    ));
                }
            }
        }
    }
    problems
}

/// No setting two stages must agree on is declared twice in pipeline.toml.
#[test]
fn pipeline_toml_declares_each_shared_setting_once() {
    let problems = declared_twice(&std::fs::read_to_string(root().join("pipeline.toml")).unwrap());
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The rule sees both kinds of duplicate (it is not vacuous).
#[test]
fn a_setting_declared_twice_is_seen() {
    let twice = "[[stage]]\nname = \"a\"\n[stage.params]\nmin_relative_gain = 0.05\n\
                 [[stage]]\nname = \"b\"\n[stage.params]\nmin_relative_gain = 0.05\n";
    assert_eq!(declared_twice(twice).len(), 1, "{:?}", declared_twice(twice));
    let nested = "[[stage]]\nname = \"a\"\n[stage.params]\nwindow_s = 0.05\n\
                  [[stage]]\nname = \"b\"\n[stage.params]\n[stage.params.checks]\nwindow_s = 0.05\n";
    assert_eq!(declared_twice(nested).len(), 1, "{:?}", declared_twice(nested));
    let beside_shared = "[shared.integrator]\nrtol = 1e-8\n[[stage]]\nname = \"a\"\n[stage.params]\nrtol = 1e-7\n";
    assert_eq!(declared_twice(beside_shared).len(), 1, "{:?}", declared_twice(beside_shared));
    let fine = "[shared.integrator]\nrtol = 1e-8\n[[stage]]\nname = \"a\"\nshared = [\"integrator\"]\n\
                [stage.params]\nsettle_s = 3.0\n[[stage]]\nname = \"b\"\n[stage.params]\nsettle_s = 8.0\n";
    assert!(declared_twice(fine).is_empty(), "{:?}", declared_twice(fine));
}

/// Keys of a stage that reads a recording whose names read as a window but
/// that count something else, with the reason.
const COUNTS_NOT_WINDOWS: [(&str, &str, &str); 1] = [(
    "slider",
    "features.segments",
    "the number of equal pieces a loading phase is cut into (their length follows the phase), not a length",
)];

/// What breaks "no window is counted in samples in pipeline.toml" in a
/// pipeline.toml text: a key of a stage that reads a recording (`{campaign}`,
/// or a data set under `{shared}/data`: the LAVI record, the slider's runs;
/// its params, nested tables and the `[shared.<name>]` tables it lists) whose
/// name says window, half-width, segment, dilation or samples but is not in
/// seconds (`*_s`), unless [`COUNTS_NOT_WINDOWS`] names it.
fn windows_in_samples(text: &str) -> Vec<String> {
    fn walk(t: &toml::Table, at: &str, out: &mut Vec<String>) {
        for (path, key, _) in leaves(t, at) {
            let windowish = ["window", "half", "segment", "samples", "dilate"].iter().any(|w| key.contains(w));
            if windowish && !key.ends_with("_s") {
                out.push(format!("{path}{key}"));
            }
        }
    }
    let doc: toml::Table = toml::from_str(text).unwrap();
    let shared = doc.get("shared").and_then(|v| v.as_table()).cloned().unwrap_or_default();
    let mut problems = Vec::new();
    for st in doc.get("stage").and_then(|v| v.as_array()).into_iter().flatten() {
        let name = st.get("name").and_then(|v| v.as_str()).unwrap_or("?");
        let reads_recording = st.get("inputs").and_then(|v| v.as_array()).is_some_and(|i| {
            i.iter().any(|x| x.as_str().is_some_and(|x| x.contains("{campaign}") || x.starts_with("{shared}/data")))
        });
        if !reads_recording {
            continue;
        }
        let mut keys = Vec::new();
        if let Some(p) = st.get("params").and_then(|v| v.as_table()) {
            walk(p, "", &mut keys);
        }
        for listed in st.get("shared").and_then(|v| v.as_array()).into_iter().flatten() {
            let table = listed.as_str().unwrap_or("?");
            if let Some(t) = shared.get(table).and_then(|v| v.as_table()) {
                walk(t, &format!("[shared.{table}] "), &mut keys);
            }
        }
        keys.retain(|k| !COUNTS_NOT_WINDOWS.iter().any(|(s, key, _)| *s == name && k == key));
        problems
            .extend(keys.into_iter().map(|k| format!("stage {name}: `{k}` reads as a window not in seconds (*_s)")));
    }
    problems
}

/// No window of a stage that reads a recording is counted in samples: a
/// campaign (or the LAVI record, the slider's runs) at another sample rate
/// keeps its windows' length (issue 26).
#[test]
fn campaign_windows_are_in_seconds() {
    let problems = windows_in_samples(&std::fs::read_to_string(root().join("pipeline.toml")).unwrap());
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The rule sees a window in samples, also in a nested or a shared table, and
/// in a stage that reads a data set under `{shared}/data` (the LAVI stage's
/// glitch windows before they were in seconds); it leaves stages that read no
/// recording alone, and the named counts (it is not vacuous).
#[test]
fn a_window_in_samples_is_seen() {
    let bad = "[shared.x]\nspeed_half_window = 10\n[[stage]]\nname = \"a\"\ninputs = [\"{campaign}\"]\n\
               shared = [\"x\"]\n[stage.params]\nwindow_samples = 25\nwindow_s = 0.05\n[stage.params.c]\nbalance_window = 50\n\
               [[stage]]\nname = \"lavi\"\ninputs = [\"{shared}/data/ufrj-lavi-2018\"]\n[stage.params]\n\
               glitch_median_window = 101\nglitch_dilate = 10\nglitch_dilate_s = 0.01\n\
               [[stage]]\nname = \"b\"\ninputs = [\"@a/data/x.json\"]\n[stage.params]\nwindow_samples = 25\n\
               [[stage]]\nname = \"slider\"\ninputs = [\"{shared}/data/s\"]\n[stage.params.features]\nsegments = 5\n";
    let seen = windows_in_samples(bad);
    assert_eq!(seen.len(), 5, "{seen:?}");
    assert!(
        seen.contains(&"stage lavi: `glitch_dilate` reads as a window not in seconds (*_s)".to_string()),
        "{seen:?}"
    );
    let segments_elsewhere = bad.replace("name = \"slider\"", "name = \"other\"");
    assert_eq!(windows_in_samples(&segments_elsewhere).len(), 6, "{:?}", windows_in_samples(&segments_elsewhere));
}

/// Where code writes an integrator tolerance of its own, as "file:line: what":
/// a `SimOptions` field `rtol` or `atol` given a number (a struct literal, on
/// any of its lines), or a `Default` for `SimOptions` (an `impl`, or a derive
/// on the struct). pipeline.toml's `[shared.integrator]` is the one home of
/// the numbers: stages are handed it, tests, benches and examples read it
/// (`SimOptions::from_pipeline_toml`), and a test that chooses another
/// tolerance says so by name (rig-model's `common::at_rtol`). The virtual
/// rig's `TRUTH_SIM_OPTIONS` is the generator's own (ARCHITECTURE.md: its
/// physics and settings are written independently of the analysis).
fn integrator_literals(lines: &[(PathBuf, usize, String)]) -> Vec<String> {
    let homes = ["crates/virtual-rig/src/lib.rs", "crates/pipeline/tests/tidy.rs"];
    let numeric = |code: &str, field: &str| {
        code.match_indices(field).any(|(i, _)| {
            let after = &code[i + field.len()..];
            let before = code[..i].chars().last();
            !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
                && after.starts_with(|c: char| c.is_ascii_digit() || c == '.' || c == '-')
        })
    };
    let mut out = Vec::new();
    for (k, (f, i, code)) in lines.iter().enumerate() {
        if homes.iter().any(|h| f.ends_with(h)) {
            continue;
        }
        let what = if numeric(code, "rtol:") || numeric(code, "atol:") {
            "an integrator tolerance written as a number"
        } else if code.contains("implDefaultfor") && code.contains("SimOptions") {
            "a Default for SimOptions"
        } else if code.contains("structSimOptions")
            && lines[k.saturating_sub(3)..k]
                .iter()
                .any(|(g, _, c)| g == f && c.starts_with("#[derive(") && c.contains("Default"))
        {
            "a derived Default for SimOptions"
        } else {
            continue;
        };
        out.push(format!("{}:{i}: {what}; read pipeline.toml's [shared.integrator]", f.display()));
    }
    out
}

/// No second integrator setting (issue 26, 6d): the tolerances are written
/// once, in pipeline.toml's `[shared.integrator]`.
#[test]
fn integrator_tolerances_have_one_home() {
    let problems = integrator_literals(&code_lines());
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The rule sees a tolerance literal (one line or spread over several), an
/// `impl Default` and a derived one, and passes the shipped setting read from
/// pipeline.toml, a tolerance chosen by name and the generator's own (it is
/// not vacuous).
#[test]
fn an_integrator_literal_is_seen() {
    let squeeze = |text: &str, file: &str| -> Vec<(PathBuf, usize, String)> {
        text.lines()
            .enumerate()
            .map(|(i, l)| (PathBuf::from(file), i + 1, l.chars().filter(|c| !c.is_whitespace()).collect()))
            .collect()
    };
    let planted = "let o = SimOptions { rtol: 1e-8, atol: 1e-10, max_step_s: 0.01 };
        let tight = SimOptions {
            rtol: 1e-13,
            atol: 1e-15,
            max_step_s: 0.01,
        };
        impl Default for SimOptions {
        #[derive(Debug, Clone, Default)]
        pub struct SimOptions {";
    let seen = integrator_literals(&squeeze(planted, "crates/model/tests/convergence.rs"));
    assert_eq!(seen.len(), 5, "{seen:?}");
    assert!(seen[0].starts_with("crates/model/tests/convergence.rs:1: an integrator tolerance"), "{seen:?}");
    assert!(seen[3].contains(":7: a Default for SimOptions") && seen[4].contains(":9: a derived Default"), "{seen:?}");
    let fine = "let o = SimOptions::from_pipeline_toml(include_str!(\"../../../pipeline.toml\"))?;
        SimOptions { rtol, atol: rtol * 1e-2, ..shipped() }
        let r = at_rtol(1e-13);
        let c = Crit { min_rtol: 0.5 };
        #[derive(Debug, Clone, PartialEq)]
        pub struct SimOptions {";
    assert!(integrator_literals(&squeeze(fine, "crates/model/tests/convergence.rs")).is_empty());
    let truth = "pub const TRUTH_SIM_OPTIONS: SimOptions = SimOptions { rtol: 1e-8, atol: 1e-10, max_step_s: 0.01 };";
    assert!(integrator_literals(&squeeze(truth, "crates/virtual-rig/src/lib.rs")).is_empty());
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

/// Files that may spell a vocabulary effect's id as a string literal outside
/// its effect file, with the reason: diagnosis.json as a reader sees it (the
/// report crate depends on no workspace crate, and its fixtures and the
/// report snapshot's are JSON and HTML text), and the virtual rig's
/// null fingerprint, a test frozen byte for byte since before the registry.
const ID_LITERALS_ALLOWED: [(&str, &str); 3] = [
    (
        "crates/report/src/summary.rs",
        "a diagnosis.json fixture; rig-report reads JSON and depends on no workspace crate",
    ),
    ("crates/pipeline/tests/snap_report.rs", "a diagnosis.json fixture and the HTML the report makes of it"),
    ("crates/virtual-rig/tests/null_fingerprint.rs", "frozen: must stay byte-identical (ARCHITECTURE.md, virtual rig)"),
];

/// An effect is one file (issue 26): every vocabulary effect of
/// `rig_diagnose::effects::REGISTRY` lives in `crates/diagnose/src/effects/<id>.rs`,
/// which spells its id once (`pub const ID`); everyone else names it through
/// that constant (so a misspelt id does not compile), never as a string
/// literal, except the files of [`ID_LITERALS_ALLOWED`].
#[test]
fn vocabulary_ids_are_spelt_in_their_effect_file() {
    let root = root();
    let mut problems = Vec::new();
    for e in rig_diagnose::effects::REGISTRY {
        let id = e.id();
        let home = format!("crates/diagnose/src/effects/{id}.rs");
        let literal = format!("\"{id}\"");
        match std::fs::read_to_string(root.join(&home)) {
            Ok(text) if text.matches(&literal).count() == 1 => {}
            Ok(_) => problems.push(format!("{home}: spells {literal} other than once")),
            Err(_) => problems.push(format!("{home}: missing (the effect `{id}` of the registry is one file)")),
        }
        problems.extend(
            code_lines()
                .into_iter()
                .filter(|(f, _, code)| code.contains(&literal) && !f.ends_with(&home))
                .filter(|(f, _, _)| !ID_LITERALS_ALLOWED.iter().any(|(a, _)| f.ends_with(a)))
                .map(|(f, i, _)| {
                    format!("{}:{i}: {literal} spelt outside {home}; name it `effects::{id}::ID`", f.display())
                }),
        );
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every other module of the diagnosis iterates the registry and never names
/// an effect: outside `effects/`, no library code of rig-diagnose (before
/// its `#[cfg(test)]` module) names an effect's module, so adding an effect
/// is its file and its registry line.
#[test]
fn the_diagnosis_names_no_effect_outside_its_file() {
    let root = root();
    let src = root.join("crates/diagnose/src");
    let mut problems = Vec::new();
    for f in rust_files(&src) {
        if f.starts_with(src.join("effects")) {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        let library = text.split("#[cfg(test)]").next().unwrap_or("");
        for e in rig_diagnose::effects::REGISTRY {
            let module = format!("{}::", e.id());
            for (i, line) in library.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                if code.contains(&module) {
                    problems.push(format!("{}:{}: names `{module}`; iterate the registry", f.display(), i + 1));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
