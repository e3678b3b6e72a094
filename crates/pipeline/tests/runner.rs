//! The runner on a tiny pipeline of fake stages in a temporary folder:
//! order, parallelism, skipping, --why reasons, refusal of undeclared
//! outputs, failure isolation, interrupted commits, manifest determinism.

use rig_pipeline::{Outcome, PipelineError, RunReport, Runner, StageCtx, StageFn};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Events per out dir (tests run in parallel, each with its own out dir).
static EVENTS: Mutex<BTreeMap<PathBuf, Vec<String>>> = Mutex::new(BTreeMap::new());

fn log(ctx: &StageCtx, what: &str) {
    let mut events = EVENTS.lock().unwrap();
    events.entry(ctx.out_dir.clone()).or_default().push(format!("{what} {}", ctx.name));
}

fn events(out: &Path) -> Vec<String> {
    EVENTS.lock().unwrap().remove(out).unwrap_or_default()
}

/// The one fake body, driven by its params: `read` = ["campaign:rel" | "out:rel"],
/// `write` = [rel], `sleep_ms`, `fail`, `panic`, `tag` (mixed into the content).
fn fake(ctx: &mut StageCtx) -> anyhow::Result<()> {
    log(ctx, "start");
    let list = |key: &str| -> Vec<String> {
        ctx.params
            .get(key)
            .and_then(|v| v.as_array())
            .map(|a| a.iter().filter_map(|s| s.as_str().map(String::from)).collect())
            .unwrap_or_default()
    };
    let mut content = format!("stage {}\n", ctx.name);
    if let Some(tag) = ctx.params.get("tag") {
        content.push_str(&format!("tag {tag}\n"));
    }
    for r in list("read") {
        let path = match r.split_once(':') {
            Some(("campaign", rel)) => ctx.campaign_dir.join(rel),
            Some(("out", rel)) => ctx.out_dir.join(rel),
            _ => anyhow::bail!("bad read {r}"),
        };
        content.push_str(&std::fs::read_to_string(&path)?);
    }
    if let Some(ms) = ctx.params.get("sleep_ms").and_then(|v| v.as_integer()) {
        std::thread::sleep(Duration::from_millis(ms as u64));
    }
    if ctx.params.get("panic").is_some() {
        panic!("fake stage asked to panic");
    }
    for w in list("write") {
        ctx.write_text(&w, &format!("{content}file {w}\n"))?;
    }
    log(ctx, "end");
    if ctx.params.get("fail").is_some() {
        anyhow::bail!("fake stage {} asked to fail", ctx.name);
    }
    Ok(())
}

fn registry(name: &str) -> Option<StageFn> {
    if name.starts_with("unknown") { None } else { Some(fake as StageFn) }
}

const SETTINGS: &str = r#"
[settings]
campaign = "campaign"
thesis = "thesis"
shared = "shared"
out = "out"
"#;

/// a and b read the campaign; c reads both; d is independent.
const DIAMOND: &str = r#"
[[stage]]
name = "a"
inputs = ["{campaign}/a.txt"]
code = ["code/a.rs"]
outputs = ["a/*"]
[stage.params]
read = ["campaign:a.txt"]
write = ["a/one.txt", "a/two.txt", "a/three.txt"]

[[stage]]
name = "b"
inputs = ["{campaign}/b.txt"]
code = ["code/b.rs"]
outputs = ["b.txt"]
[stage.params]
read = ["campaign:b.txt"]
write = ["b.txt"]

[[stage]]
name = "c"
inputs = ["@a/a/one.txt", "@b/b.txt"]
code = ["code/c"]
outputs = ["c/out.txt"]
[stage.params]
read = ["out:a/one.txt", "out:b.txt"]
write = ["c/out.txt"]

[[stage]]
name = "d"
inputs = ["{campaign}"]
outputs = ["d.txt"]
[stage.params]
write = ["d.txt"]
"#;

struct Fixture {
    dir: tempfile::TempDir,
}

impl Fixture {
    fn new(stages: &str) -> Self {
        let dir = tempfile::tempdir().unwrap();
        let f = Fixture { dir };
        f.write("pipeline.toml", &format!("{SETTINGS}{stages}"));
        f.write("campaign/a.txt", "alpha\n");
        f.write("campaign/b.txt", "beta\n");
        f.write("code/a.rs", "//! a\n");
        f.write("code/b.rs", "//! b\n");
        f.write("code/c/main.rs", "//! c\n");
        f.write("code/c/util/mod.rs", "//! c util\n");
        std::fs::create_dir_all(f.root().join("thesis")).unwrap();
        f
    }

    fn root(&self) -> &Path {
        self.dir.path()
    }

    fn out(&self) -> PathBuf {
        self.root().join("out")
    }

    fn write(&self, rel: &str, text: &str) {
        let p = self.root().join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }

    fn read_out(&self, rel: &str) -> String {
        std::fs::read_to_string(self.out().join(rel)).unwrap()
    }

    fn runner(&self) -> Runner {
        Runner::with_registry(&self.root().join("pipeline.toml"), registry).unwrap()
    }

    fn run(&self) -> RunReport {
        self.runner().jobs(2).run().unwrap()
    }

    fn edit_toml(&self, from: &str, to: &str) {
        let p = self.root().join("pipeline.toml");
        let t = std::fs::read_to_string(&p).unwrap();
        assert!(t.contains(from), "{from} not in pipeline.toml");
        std::fs::write(&p, t.replacen(from, to, 1)).unwrap();
    }
}

fn outcome(r: &RunReport, stage: &str) -> String {
    format!("{:?}", r.stage(stage).unwrap().outcome).split(['(', ' ']).next().unwrap().to_string()
}

fn reasons(r: &RunReport, stage: &str) -> Vec<String> {
    r.stage(stage).unwrap().reasons.clone()
}

/// Every file under `dir` (hidden ones included) with its bytes.
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(dir: &Path, base: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, base, out);
            } else {
                out.insert(p.strip_prefix(base).unwrap().display().to_string(), std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

#[test]
fn runs_in_dependency_order_and_commits_outputs() {
    let f = Fixture::new(DIAMOND);
    let r = f.run();
    assert_eq!(r.ran(), ["a", "b", "c", "d"]);
    let ev = events(&f.out());
    let pos = |e: &str| ev.iter().position(|x| x == e).unwrap_or_else(|| panic!("{e} not in {ev:?}"));
    assert!(pos("end a") < pos("start c") && pos("end b") < pos("start c"), "{ev:?}");
    assert_eq!(
        f.read_out("c/out.txt"),
        "stage c\nstage a\nalpha\nfile a/one.txt\nstage b\nbeta\nfile b.txt\nfile c/out.txt\n"
    );
    assert!(r.into_result().is_ok());
}

#[test]
fn independent_stages_run_in_parallel_only_with_two_jobs() {
    let stages = DIAMOND.replace("write = [\"b.txt\"]", "write = [\"b.txt\"]\nsleep_ms = 400").replace(
        "write = [\"a/one.txt\", \"a/two.txt\", \"a/three.txt\"]",
        "write = [\"a/one.txt\", \"a/two.txt\", \"a/three.txt\"]\nsleep_ms = 400",
    );
    let overlap = |jobs: usize| {
        let f = Fixture::new(&stages);
        let t0 = Instant::now();
        f.runner().jobs(jobs).only(&["a", "b"]).run().unwrap();
        let ev = events(&f.out());
        let (sa, eb) = (ev.iter().position(|e| e == "start a"), ev.iter().position(|e| e == "end b"));
        let (sb, ea) = (ev.iter().position(|e| e == "start b"), ev.iter().position(|e| e == "end a"));
        // Overlap: each started before the other ended.
        (sa < eb && sb < ea, t0.elapsed())
    };
    // The overlap of the event logs is the proof; wall time only bounds the
    // sequential case from below (an upper bound would flake on a busy machine).
    let (par, _) = overlap(2);
    let (seq, t1) = overlap(1);
    assert!(par, "with 2 jobs a and b should overlap");
    assert!(!seq, "with 1 job a and b must not overlap");
    assert!(t1 >= Duration::from_millis(800), "1 job took {t1:?}");
}

#[test]
fn second_run_skips_everything_quickly() {
    let f = Fixture::new(DIAMOND);
    f.run();
    let t0 = Instant::now();
    let r = f.run();
    let took = t0.elapsed();
    assert!(r.ran().is_empty(), "{}", r.summary(true));
    for s in ["a", "b", "c", "d"] {
        assert_eq!(outcome(&r, s), "UpToDate");
    }
    assert!(took < Duration::from_secs(1), "{took:?}");
}

#[test]
fn changed_input_reruns_only_downstream() {
    let f = Fixture::new(DIAMOND);
    f.run();
    f.write("campaign/b.txt", "beta two\n");
    let r = f.run();
    // d hashes the whole campaign folder, so it re-runs too; a does not read b.txt.
    assert_eq!(r.ran(), ["b", "c", "d"]);
    assert_eq!(reasons(&r, "b"), ["input {campaign}/b.txt changed"]);
    assert_eq!(reasons(&r, "c"), ["input @b/b.txt changed"]);
    assert_eq!(reasons(&r, "d"), ["input {campaign} changed"]);
    assert!(f.read_out("c/out.txt").contains("beta two"));
}

#[test]
fn unchanged_upstream_output_stops_the_cascade() {
    let f = Fixture::new(DIAMOND);
    f.run();
    // b's code changes but b writes the same bytes: c stays up to date.
    f.write("code/b.rs", "//! b, reformatted\n");
    let r = f.run();
    assert_eq!(r.ran(), ["b"], "{}", r.summary(true));
    assert_eq!(reasons(&r, "b"), ["code code/b.rs changed"]);
    assert_eq!(outcome(&r, "c"), "UpToDate");
    // A file deep in a code folder counts as the folder's code.
    f.write("code/c/util/mod.rs", "//! c util, changed\n");
    let r = f.run();
    assert_eq!(r.ran(), ["c"]);
    assert_eq!(reasons(&r, "c"), ["code code/c changed"]);
    assert!(f.run().ran().is_empty());
}

#[test]
fn why_names_params_code_and_outputs() {
    let f = Fixture::new(DIAMOND);
    f.run();
    f.edit_toml("write = [\"d.txt\"]", "write = [\"d.txt\"]\ntag = 7");
    f.write("code/a.rs", "//! a, changed\n");
    std::fs::remove_file(f.out().join("b.txt")).unwrap();
    std::fs::write(f.out().join("c/out.txt"), "tampered").unwrap();
    let dry = f.runner().dry_run(true).run().unwrap();
    assert_eq!(reasons(&dry, "a"), ["code code/a.rs changed"]);
    assert_eq!(reasons(&dry, "b"), ["output b.txt is missing"]);
    assert_eq!(outcome(&dry, "c"), "WouldRun");
    assert_eq!(
        reasons(&dry, "c"),
        ["upstream a would run; its outputs may change", "upstream b would run; its outputs may change"]
    );
    assert_eq!(reasons(&dry, "d"), ["param tag is new"]);
    assert!(dry.manifest.is_none());
    // The dry run changed nothing: still tampered, still missing.
    assert_eq!(f.read_out("c/out.txt"), "tampered");
    assert!(!f.out().join("b.txt").exists());
    let r = f.run();
    assert_eq!(r.ran(), ["a", "b", "c", "d"]);
    f.edit_toml("tag = 7", "tag = 8");
    let r = f.run();
    assert_eq!(r.ran(), ["d"]);
    assert_eq!(reasons(&r, "d"), ["param tag changed (7 -> 8)"]);
    assert!(r.summary(true).contains("param tag changed (7 -> 8)"));
}

#[test]
fn undeclared_output_is_refused_and_nothing_is_written() {
    let f = Fixture::new(&DIAMOND.replace("write = [\"d.txt\"]", "write = [\"d.txt\", \"sneaky.txt\"]"));
    let r = f.run();
    let Outcome::Failed(e) = &r.stage("d").unwrap().outcome else { panic!("{}", r.summary(true)) };
    let err = e.downcast_ref::<PipelineError>().expect("a PipelineError");
    assert!(matches!(err, PipelineError::UndeclaredOutput { stage, rel } if stage == "d" && rel == "sneaky.txt"));
    assert!(e.to_string().contains("not declared"), "{e}");
    assert!(!f.out().join("sneaky.txt").exists());
    assert!(!f.out().join("d.txt").exists());
    assert!(r.into_result().is_err());
}

#[test]
fn failing_stage_writes_nothing_and_blocks_only_its_downstream() {
    let f = Fixture::new(&DIAMOND.replace("write = [\"b.txt\"]", "write = [\"b.txt\"]\nfail = true"));
    let r = f.run();
    assert_eq!(outcome(&r, "b"), "Failed");
    assert!(matches!(&r.stage("c").unwrap().outcome, Outcome::Blocked { by } if by == "b"));
    assert_eq!(outcome(&r, "a"), "Ran");
    assert_eq!(outcome(&r, "d"), "Ran");
    assert!(!f.out().join("b.txt").exists());
    assert!(!f.out().join("c").exists());
    let err = r.into_result().unwrap_err().to_string();
    assert!(err.contains("stage b") && err.contains("asked to fail"), "{err}");
    // The manifest lists what succeeded only.
    let manifest = std::fs::read_to_string(f.out().join("manifest.json")).unwrap();
    assert!(manifest.contains("\"d.txt\"") && !manifest.contains("\"b.txt\""), "{manifest}");
}

#[test]
fn a_panicking_stage_is_a_failure_not_a_crash() {
    let f = Fixture::new(&DIAMOND.replace("write = [\"d.txt\"]", "write = [\"d.txt\"]\npanic = true"));
    let r = f.run();
    let Outcome::Failed(e) = &r.stage("d").unwrap().outcome else { panic!() };
    assert!(e.to_string().contains("panicked"), "{e}");
    assert_eq!(outcome(&r, "c"), "Ran");
}

#[test]
fn interrupted_commit_leaves_whole_files_and_the_next_run_resumes() {
    let f = Fixture::new(DIAMOND);
    f.run();
    let old: Vec<String> = ["one", "two", "three"].iter().map(|n| f.read_out(&format!("a/{n}.txt"))).collect();
    f.write("campaign/a.txt", "alpha two\n");
    // Killed after the first of three renames: one new file, two old ones, temporaries left.
    let r = f.runner().inject_commit_fault("a", 1).run().unwrap();
    assert_eq!(outcome(&r, "a"), "Failed");
    assert_eq!(outcome(&r, "c"), "Blocked");
    let after: Vec<String> = ["one", "two", "three"].iter().map(|n| f.read_out(&format!("a/{n}.txt"))).collect();
    let fresh = after.iter().filter(|t| t.contains("alpha two")).count();
    assert_eq!(fresh, 1, "{after:?}");
    for (a, o) in after.iter().zip(&old) {
        assert!(a == o || a.ends_with(".txt\n") && a.contains("alpha two\n"), "torn file: {a:?}");
    }
    let temps = tree(&f.out()).into_keys().filter(|k| k.ends_with(".rigtmp")).count();
    assert_eq!(temps, 2, "the simulated kill leaves two temporaries");
    // The cache record is still the old one, so the next run re-runs a and cleans up.
    let r = f.run();
    assert_eq!(r.ran(), ["a", "c"]);
    assert!(f.read_out("a/three.txt").contains("alpha two"));
    assert!(tree(&f.out()).keys().all(|k| !k.ends_with(".rigtmp")));
    assert!(f.run().ran().is_empty());
}

#[test]
fn stale_family_members_are_removed() {
    let f = Fixture::new(DIAMOND);
    f.write("out/b-not-mine.txt", "kept\n");
    f.run();
    f.edit_toml("write = [\"a/one.txt\", \"a/two.txt\", \"a/three.txt\"]", "write = [\"a/one.txt\"]");
    let r = f.run();
    assert_eq!(r.ran(), ["a"]);
    assert!(f.out().join("a/one.txt").exists());
    assert!(!f.out().join("a/two.txt").exists() && !f.out().join("a/three.txt").exists());
    assert_eq!(f.read_out("b-not-mine.txt"), "kept\n");
}

#[test]
fn manifest_is_deterministic_and_complete() {
    let f1 = Fixture::new(DIAMOND);
    let f2 = Fixture::new(DIAMOND);
    f1.runner().jobs(1).run().unwrap();
    f2.runner().jobs(2).run().unwrap();
    let m1 = f1.read_out("manifest.json");
    assert_eq!(m1, f2.read_out("manifest.json"));
    // Byte-identical out dirs (caches included) for 1 and 2 jobs.
    assert_eq!(tree(&f1.out()), tree(&f2.out()));
    // Unchanged by a run that skips everything, or by --only.
    f1.run();
    assert_eq!(m1, f1.read_out("manifest.json"));
    f1.runner().only(&["b"]).run().unwrap();
    assert_eq!(m1, f1.read_out("manifest.json"));
    let m: serde_json::Value = serde_json::from_str(&m1).unwrap();
    let artifacts = m["artifacts"].as_object().unwrap();
    let names: Vec<&str> = artifacts.keys().map(String::as_str).collect();
    assert_eq!(names, ["a/one.txt", "a/three.txt", "a/two.txt", "b.txt", "c/out.txt", "d.txt"]);
    let b = &artifacts["b.txt"];
    assert_eq!(b["stage"], "b");
    assert_eq!(b["blake3"], blake3::hash(f1.read_out("b.txt").as_bytes()).to_hex().to_string());
    assert_eq!(b["size"], f1.read_out("b.txt").len());
    assert_eq!(m["stages"]["c"]["inputs"].as_object().unwrap().len(), 2);
    assert!(m["stages"]["a"]["params"]["write"].as_str().unwrap().starts_with("[\"a/one.txt\""));
    assert!(!m1.contains(&f1.root().display().to_string()), "no absolute paths");
}

#[test]
fn only_runs_the_stage_and_its_upstream() {
    let f = Fixture::new(DIAMOND);
    let r = f.runner().only(&["c"]).run().unwrap();
    assert_eq!(r.ran(), ["a", "b", "c"]);
    assert!(r.stage("d").is_none());
    assert!(matches!(f.runner().only(&["zzz"]).run(), Err(PipelineError::UnknownStage(s)) if s == "zzz"));
}

#[test]
fn campaign_and_out_can_be_redirected() {
    let f = Fixture::new(DIAMOND);
    f.write("other/a.txt", "other alpha\n");
    f.write("other/b.txt", "other beta\n");
    let out = f.root().join("elsewhere");
    let r = f.runner().campaign(&f.root().join("other")).out(&out).run().unwrap();
    assert_eq!(r.ran().len(), 4);
    assert!(std::fs::read_to_string(out.join("c/out.txt")).unwrap().contains("other beta"));
    assert!(!f.out().exists());
}

#[test]
fn optional_stage_with_missing_input_is_skipped_and_empty_stage_too() {
    let extra = r#"
[[stage]]
name = "opt"
inputs = ["{shared}/data/x"]
outputs = ["opt.txt"]
optional = true
[stage.params]
write = ["opt.txt"]

[[stage]]
name = "needs"
inputs = ["{shared}/data/x"]
outputs = ["needs.txt"]
[stage.params]
write = ["needs.txt"]

[[stage]]
name = "empty"
inputs = []
outputs = ["empty.txt"]
after = ["opt"]
[stage.params]
"#;
    let f = Fixture::new(&format!("{DIAMOND}{extra}"));
    let r = f.run();
    assert_eq!(outcome(&r, "opt"), "SkippedOptional");
    assert!(reasons(&r, "opt")[0].contains("{shared}/data/x"));
    let Outcome::Failed(e) = &r.stage("needs").unwrap().outcome else { panic!() };
    assert!(e.to_string().contains("mark the stage optional"), "{e}");
    assert_eq!(outcome(&r, "empty"), "SkippedEmpty");
    f.write("shared/data/x", "x\n");
    let r = f.run();
    assert_eq!(outcome(&r, "opt"), "Ran");
    assert_eq!(outcome(&r, "needs"), "Ran");
}

fn config_error(stages: &str) -> String {
    let f = Fixture::new(stages);
    match Runner::with_registry(&f.root().join("pipeline.toml"), registry) {
        Ok(_) => panic!("accepted:\n{stages}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn config_errors_name_the_file_and_the_stage() {
    let e = config_error("[[stage]]\nname = \"unknown-x\"\noutputs = [\"x\"]\n");
    assert!(e.contains("pipeline.toml: stage unknown-x: unknown stage name"), "{e}");
    let cycle = "[[stage]]\nname = \"p\"\ninputs = [\"@q/q.txt\"]\noutputs = [\"p.txt\"]\n\
                 [[stage]]\nname = \"q\"\nafter = [\"p\"]\noutputs = [\"q.txt\"]\n";
    let e = config_error(cycle);
    assert!(e.contains("pipeline.toml: stage p: dependency cycle among stages p, q"), "{e}");
    let e =
        config_error(&format!("{DIAMOND}[[stage]]\nname = \"e\"\ninputs = [\"@a/b.txt\"]\noutputs = [\"e.txt\"]\n"));
    assert!(e.contains("pipeline.toml: stage e: input @a/b.txt: stage a declares no such output"), "{e}");
    let e = config_error("[[stage]]\nname = \"p\"\ninputs = [\"{campain}\"]\noutputs = [\"p.txt\"]\n");
    assert!(e.contains("stage p") && e.contains("unknown placeholder {campain}"), "{e}");
    let e = config_error("[[stage]]\nname = \"p\"\noutputs = [\"p.txt\"]\ncolour = 1\n");
    assert!(e.contains("pipeline.toml") && e.contains("colour"), "{e}");
}

#[test]
fn graph_prints_mermaid_and_dot() {
    let f = Fixture::new(DIAMOND);
    let runner = f.runner();
    let m = rig_pipeline::graph::mermaid(runner.config());
    assert!(m.starts_with("flowchart LR\n") && m.contains("    a --> c\n") && m.contains("    b --> c\n"), "{m}");
    let d = rig_pipeline::graph::dot(runner.config());
    assert!(d.contains("\"a\" -> \"c\";") && d.ends_with("}\n"), "{d}");
}

#[test]
fn the_repository_pipeline_toml_is_valid() {
    let toml = rig_pipeline::testing::workspace_root().join("pipeline.toml");
    let runner = Runner::new(&toml).unwrap_or_else(|e| panic!("{e}"));
    let order = rig_pipeline::graph::topological_order(runner.config()).unwrap();
    assert_eq!(order.first().map(String::as_str), Some("thesis-tables"));
    assert_eq!(order.last().map(String::as_str), Some("report"));
}

#[test]
fn reformatting_pipeline_toml_reruns_nothing() {
    let f = Fixture::new(&DIAMOND.replace("write = [\"d.txt\"]", "write = [\"d.txt\"]\nx = 1.5\ny = { b = 1, a = 2 }"));
    f.run();
    f.edit_toml("x = 1.5\ny = { b = 1, a = 2 }", "y = {a=2,b=1}   # reordered\nx = 1.50");
    f.edit_toml("name = \"c\"", "name = \"c\"\nsummary = \"a summary is documentation, not a parameter\"");
    let r = f.run();
    assert!(r.ran().is_empty(), "{}", r.summary(true));
}

/// e reads nothing declared but runs `after` d (like the report after every
/// figure stage): a change in d's outputs must re-run e.
#[test]
fn outputs_of_an_after_stage_are_part_of_the_key() {
    let stages = format!(
        "{DIAMOND}{}",
        r#"
[[stage]]
name = "e"
after = ["d"]
outputs = ["e.txt"]
[stage.params]
read = ["out:d.txt"]
write = ["e.txt"]
"#
    );
    let f = Fixture::new(&stages);
    f.run();
    assert!(f.run().ran().is_empty());
    // d hashes the campaign folder and writes its params: a new tag changes d.txt.
    f.edit_toml("write = [\"d.txt\"]", "write = [\"d.txt\"]\ntag = 2");
    let r = f.run();
    assert_eq!(r.ran(), ["d", "e"], "{}", r.summary(true));
    assert_eq!(reasons(&r, "e"), ["input @d/d.txt changed"]);
    assert!(f.read_out("e.txt").contains("tag 2"));
}

/// Stage code is computed: in a small workspace where stage `s`'s body names
/// `rig_a::` and rig-a depends on rig-b, appending a line to rig-b's source
/// makes `--dry-run` re-run `s` and say why; a crate it does not use does not.
#[test]
fn stage_code_is_computed_from_the_crates_the_body_uses() {
    let f = Fixture::new(
        r#"
[[stage]]
name = "s"
inputs = ["{campaign}/a.txt"]
outputs = ["s.txt"]
[stage.params]
write = ["s.txt"]
"#,
    );
    f.write(
        "Cargo.toml",
        "[workspace.dependencies]\nrig-a = { path = \"crates/a\" }\nrig-b = { path = \"crates/b\" }\nrig-c = { path = \"crates/c\" }\n",
    );
    f.write(
        "crates/a/Cargo.toml",
        "[dependencies]\nrig-b.workspace = true\n[dev-dependencies]\nrig-c.workspace = true\n",
    );
    f.write("crates/a/src/lib.rs", "//! a\n");
    f.write("crates/b/Cargo.toml", "[dependencies]\n");
    f.write("crates/b/src/lib.rs", "//! b\n");
    f.write("crates/b/assets/x.txt", "data\n");
    f.write("crates/b/src/data.rs", "//! b data\nstatic X: &str = include_str!(\"../assets/x.txt\");\n");
    f.write("crates/c/Cargo.toml", "[dependencies]\n");
    f.write("crates/c/src/lib.rs", "//! c\n");
    f.write("stages/s.rs", "//! s\nuse crate::helper;\nfn run() { rig_a::go(); }\n");
    f.write("src/helper.rs", "//! helper\n");
    let runner = || f.runner().stage_sources(|n| (n == "s").then_some("stages/s.rs"));
    runner().run().unwrap();
    let code = &runner().run().unwrap().stage("s").unwrap().record.clone().unwrap().code;
    let paths: Vec<&str> = code.keys().map(String::as_str).collect();
    assert!(paths.contains(&"crates/a/src") && paths.contains(&"crates/b/src"), "{paths:?}");
    assert!(paths.contains(&"crates/b/assets/x.txt") && paths.contains(&"stages/s.rs"), "{paths:?}");
    assert!(!paths.contains(&"crates/c/src"), "a dev-dependency is not code the stage runs: {paths:?}");

    f.write("crates/c/src/lib.rs", "//! c\n// unused by s\n");
    assert_eq!(outcome(&runner().dry_run(true).run().unwrap(), "s"), "UpToDate");
    f.write("crates/b/src/lib.rs", "//! b\n// one more line\n");
    let r = runner().dry_run(true).run().unwrap();
    assert_eq!(outcome(&r, "s"), "WouldRun");
    assert_eq!(reasons(&r, "s"), ["code crates/b/src changed"]);
    f.write("crates/b/assets/x.txt", "other data\n");
    f.write("crates/b/src/lib.rs", "//! b\n");
    assert_eq!(reasons(&runner().dry_run(true).run().unwrap(), "s"), ["code crates/b/assets/x.txt changed"]);
}

/// Params are checked for every stage before any stage runs: a stage whose
/// check refuses its params stops the whole run, naming the stage and the key.
#[test]
fn params_are_checked_for_every_stage_before_any_runs() {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct DParams {
        write: Vec<String>,
    }
    fn check(name: &str, params: &toml::Table) -> Result<(), String> {
        if name == "d" { rig_pipeline::parse_params::<DParams>(params).map(|_| ()) } else { Ok(()) }
    }
    let f = Fixture::new(DIAMOND);
    f.edit_toml("write = [\"d.txt\"]", "write = [\"d.txt\"]\nwirte = 1");
    let err = f.runner().params_check(check).run().unwrap_err().to_string();
    assert!(err.contains("stage d") && err.contains("unknown field `wirte`"), "{err}");
    assert!(!f.out().exists(), "nothing ran, not even the out dir was made");
    f.edit_toml("wirte = 1", "");
    assert_eq!(f.runner().params_check(check).run().unwrap().ran(), ["a", "b", "c", "d"]);
}

/// The repository's pipeline.toml with a misspelt key is refused up front,
/// naming the stage and the key; a mistyped value names its key.
#[test]
fn the_repository_refuses_an_unknown_or_mistyped_param() {
    let root = rig_pipeline::testing::workspace_root();
    let text = std::fs::read_to_string(root.join("pipeline.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pipeline.toml");
    let bad = text.replacen("limit_cycle_s = 20.0", "limit_cycle_s = 20.0\nlimit_cycle = 20.0", 1);
    assert_ne!(bad, text);
    std::fs::write(&path, &bad).unwrap();
    let err = Runner::new(&path).unwrap().dry_run(true).run().unwrap_err().to_string();
    assert!(err.contains("stage simulation") && err.contains("unknown field `limit_cycle`"), "{err}");
    let bad = text.replacen("first_transient_s = 40.0", "first_transient_s = \"40 s\"", 1);
    std::fs::write(&path, &bad).unwrap();
    let err = Runner::new(&path).unwrap().dry_run(true).run().unwrap_err().to_string();
    assert!(err.contains("stage sweeps: [stage.params] first_transient_s: invalid type"), "{err}");
}

/// A bad campaign is refused once, before any stage runs, with the reader's
/// one message (file, line, rule) and no repetition; stages never start.
#[test]
fn a_bad_campaign_is_refused_before_any_stage_runs() {
    let root = rig_pipeline::testing::workspace_root();
    let dir = tempfile::tempdir().unwrap();
    let camp = dir.path().join("campaign");
    std::fs::create_dir_all(camp.join("runs")).unwrap();
    let src = root.join("data/emulated-rig-2026");
    std::fs::copy(src.join("campaign.toml"), camp.join("campaign.toml")).unwrap();
    for e in std::fs::read_dir(src.join("runs")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), camp.join("runs").join(e.file_name())).unwrap();
    }
    let cal = camp.join("runs/cal-1.csv");
    let text = std::fs::read_to_string(&cal).unwrap();
    std::fs::write(&cal, text.replacen("0.0020,150.10", "0.0020,1e308", 1)).unwrap();
    let out = dir.path().join("out");
    let started = std::time::Instant::now();
    let err = Runner::new(&root.join("pipeline.toml")).unwrap().campaign(&camp).out(&out).run().unwrap_err();
    let took = started.elapsed();
    let msg = err.to_string();
    assert!(msg.starts_with("campaign refused: "), "{msg}");
    assert!(msg.contains("runs/cal-1.csv:3: brake_force_mv = 1e308 mV is physically impossible"), "{msg}");
    assert_eq!(msg.lines().count(), 1, "{msg}");
    assert!(!out.exists(), "no stage ran, not even the out dir was made");
    // Under a second on an idle machine (polars is optimised in dev builds); generous here for loaded CI.
    assert!(took < Duration::from_secs(20), "refusal took {took:?}");
}

/// A stage's error is named once: `stage c: reading …`, not `stage c: stage c: …`.
#[test]
fn stage_errors_name_the_stage_once() {
    fn reads_missing(ctx: &mut StageCtx) -> anyhow::Result<()> {
        let _: serde_json::Value = ctx.read_json("nothing.json")?;
        Ok(())
    }
    fn reg(_: &str) -> Option<StageFn> {
        Some(reads_missing as StageFn)
    }
    let f = Fixture::new("[[stage]]\nname = \"c\"\noutputs = [\"c.txt\"]\n");
    let r = Runner::with_registry(&f.root().join("pipeline.toml"), reg).unwrap().run().unwrap();
    let msg = r.into_result().unwrap_err().to_string();
    assert!(msg.starts_with("stage c: reading "), "{msg}");
    assert_eq!(msg.matches("stage c").count(), 1, "{msg}");
}

/// A `[shared.<name>]` table is declared once and reaches every stage
/// listing it in `shared` as `params.<name>`, so it is in their keys (a
/// changed tolerance re-runs exactly those stages, and `--why` names it); a
/// stage declaring its own, or asking for a table that is not there, is refused.
#[test]
fn shared_tables_reach_the_stages_that_list_them() {
    let shared = "[shared.integrator]\nrtol = 1e-8\natol = 1e-10\n";
    let stages = DIAMOND.replace("name = \"d\"\n", "name = \"d\"\nshared = [\"integrator\"]\n");
    let f = Fixture::new(&format!("{shared}{stages}"));
    f.run();
    f.edit_toml("rtol = 1e-8", "rtol = 1e-6");
    let r = f.run();
    assert_eq!(r.ran(), ["d"]);
    let why = reasons(&r, "d");
    assert!(why.len() == 1 && why[0].starts_with("param integrator changed ({atol = "), "{why:?}");

    let e = config_error(&stages);
    assert!(e.contains("stage d") && e.contains("no [shared.integrator] table"), "{e}");
    let own = stages.replace("write = [\"d.txt\"]", "write = [\"d.txt\"]\nintegrator = { rtol = 1.0 }");
    let e = config_error(&format!("{shared}{own}"));
    assert!(e.contains("stage d") && e.contains("declared once in [shared.integrator]"), "{e}");
}

/// An on-demand stage reading b's output (like the confusion battery).
const SLOW: &str = r#"
[[stage]]
name = "slow"
inputs = ["@b/b.txt"]
outputs = ["slow.txt"]
on_demand = true
[stage.params]
read = ["out:b.txt"]
write = ["slow.txt"]
"#;

/// An `on_demand` stage (like the confusion battery) does not run in a default
/// run: it is assessed (up to date, or skipped as stale with the reasons), a
/// stage `after` it reads its last outputs, and `--only NAME` or `--all` runs it.
#[test]
fn an_on_demand_stage_runs_only_when_asked_for() {
    let stages = format!(
        "{DIAMOND}{SLOW}{}",
        r#"
[[stage]]
name = "page"
after = ["slow"]
outputs = ["page.txt"]
[stage.params]
write = ["page.txt"]
"#
    );
    let f = Fixture::new(&stages);
    assert!(rig_pipeline::graph::mermaid(f.runner().config()).contains("slow[\"slow (on demand)\"]"));
    let r = f.run();
    assert_eq!(outcome(&r, "slow"), "SkippedOnDemand");
    assert_eq!(reasons(&r, "slow"), ["no record of an earlier run in this out dir"]);
    assert!(r.summary(false).contains("cargo xtask reproduce --only slow"), "{}", r.summary(false));
    assert_eq!(r.ran(), ["a", "b", "c", "d", "page"]);
    assert!(!f.out().join("slow.txt").exists());
    // Named: it runs, and the page after it re-runs on its new outputs.
    let r = f.runner().only(&["slow", "page"]).run().unwrap();
    assert_eq!(r.ran(), ["slow", "page"], "{}", r.summary(true));
    assert!(f.read_out("slow.txt").contains("beta"));
    let r = f.run();
    assert_eq!(outcome(&r, "slow"), "UpToDate");
    assert!(r.ran().is_empty(), "{}", r.summary(true));
    // Its input changes: a default run reports it stale and why, keeps its last
    // outputs (and the page's key, so the page does not re-run), and the
    // manifest still lists them; `--all` runs it.
    f.write("campaign/b.txt", "gamma\n");
    let r = f.run();
    assert_eq!(outcome(&r, "slow"), "SkippedOnDemand");
    assert_eq!(reasons(&r, "slow"), ["input @b/b.txt changed"]);
    assert_eq!(r.ran(), ["b", "c", "d"]); // d hashes the whole campaign folder
    assert!(f.read_out("slow.txt").contains("beta"));
    assert!(f.read_out("manifest.json").contains("\"slow.txt\""));
    let r = f.runner().all(true).run().unwrap();
    assert_eq!(r.ran(), ["slow", "page"], "{}", r.summary(true));
    assert!(f.read_out("slow.txt").contains("gamma"));
    // No default stage may read its outputs as an input.
    let e = config_error(&format!(
        "{stages}[[stage]]\nname = \"reader\"\ninputs = [\"@slow/slow.txt\"]\noutputs = [\"r.txt\"]\n"
    ));
    assert!(e.contains("stage reader: input @slow/slow.txt: stage slow is on_demand"), "{e}");
}

/// A fresh clone has the committed out dir (outputs and manifest) but no
/// `.cache/`: a default run re-runs the default stages and keeps the on-demand
/// stage's entries (its record is read from the manifest, its outputs are
/// intact and its key unchanged, so it is up to date), leaving the manifest
/// byte-identical. When its inputs change it is kept, marked stale; an
/// optional stage whose input is missing keeps its last outputs, marked.
#[test]
fn a_fresh_clone_keeps_the_manifest_of_stages_it_does_not_rerun() {
    let stages = format!(
        "{DIAMOND}{SLOW}{}",
        r#"
[[stage]]
name = "extra"
inputs = ["{shared}/x.txt"]
outputs = ["extra.txt"]
optional = true
[stage.params]
write = ["extra.txt"]

[[stage]]
name = "page"
after = ["slow", "extra"]
outputs = ["page.txt"]
[stage.params]
write = ["page.txt"]
"#
    );
    let f = Fixture::new(&stages);
    f.write("shared/x.txt", "x\n");
    f.runner().all(true).run().unwrap();
    let committed = tree(&f.out());
    let manifest = f.read_out("manifest.json");
    assert!(manifest.contains("\"on_demand\": true") && !manifest.contains("\"kept\""), "{manifest}");
    // The clone: no cache, and ../shared absent.
    std::fs::remove_dir_all(f.out().join(".cache")).unwrap();
    std::fs::remove_dir_all(f.root().join("shared")).unwrap();
    let r = f.run();
    assert_eq!(outcome(&r, "slow"), "UpToDate", "{}", r.summary(true));
    assert_eq!(outcome(&r, "extra"), "SkippedOptional");
    assert_eq!(r.ran(), ["a", "b", "c", "d", "page"]);
    let m = f.read_out("manifest.json");
    let v: serde_json::Value = serde_json::from_str(&m).unwrap();
    assert_eq!(v["artifacts"]["slow.txt"]["stage"], "slow");
    assert_eq!(v["artifacts"]["extra.txt"]["stage"], "extra");
    assert!(v["stages"]["extra"]["kept"].as_str().unwrap().starts_with("optional, skipped"), "{m}");
    let committed_page = serde_json::from_str::<serde_json::Value>(&manifest).unwrap()["stages"]["page"].clone();
    assert_eq!(v["stages"]["page"], committed_page, "the page's key covers the kept outputs it reads");
    // With the input back (the usual clone, beside ../shared) the out dir is
    // the committed one, byte for byte, apart from the rebuilt cache.
    f.write("shared/x.txt", "x\n");
    f.run();
    let mut now = tree(&f.out());
    now.retain(|k, _| !k.starts_with(".cache"));
    let mut want = committed.clone();
    want.retain(|k, _| !k.starts_with(".cache"));
    assert_eq!(now, want);
    // Its input changes: kept with its last outputs, marked stale with the reason.
    std::fs::remove_dir_all(f.out().join(".cache")).unwrap();
    f.write("campaign/b.txt", "gamma\n");
    let r = f.run();
    assert_eq!(outcome(&r, "slow"), "SkippedOnDemand");
    let v: serde_json::Value = serde_json::from_str(&f.read_out("manifest.json")).unwrap();
    assert_eq!(v["artifacts"]["slow.txt"]["stage"], "slow");
    let kept = v["stages"]["slow"]["kept"].as_str().unwrap();
    assert!(kept.starts_with("stale, not rerun (input @b/b.txt changed)") && kept.contains("--only slow"), "{kept}");
}

/// The schedule starts the ready stage with the longest remaining path
/// (`cpu_s`: its own CPU seconds plus the longest path after it) first: with
/// one worker, `d` (5 s alone) before `a` and `b` (whose path through `c` is
/// 0.2 + 3 s), then `a` before `b` (a tie: declaration order); without
/// `cpu_s` the declaration order. The outputs do not depend on it.
#[test]
fn the_longest_remaining_path_starts_first() {
    let starts = |stages: &str| {
        let f = Fixture::new(stages);
        f.runner().jobs(1).run().unwrap();
        let ev: Vec<String> = events(&f.out()).into_iter().filter(|e| e.starts_with("start")).collect();
        (ev, tree(&f.out()).into_iter().filter(|(k, _)| !k.starts_with(".cache")).collect::<BTreeMap<_, _>>())
    };
    let (plain, plain_out) = starts(DIAMOND);
    assert_eq!(plain, ["start a", "start b", "start c", "start d"]);
    let timed = DIAMOND
        .replacen("name = \"a\"\n", "name = \"a\"\ncpu_s = 0.2\n", 1)
        .replacen("name = \"b\"\n", "name = \"b\"\ncpu_s = 0.2\n", 1)
        .replacen("name = \"c\"\n", "name = \"c\"\ncpu_s = 3.0\n", 1)
        .replacen("name = \"d\"\n", "name = \"d\"\ncpu_s = 5.0\n", 1);
    let (first, first_out) = starts(&timed);
    assert_eq!(first, ["start d", "start a", "start b", "start c"]);
    let manifest = |t: &BTreeMap<String, Vec<u8>>| t.iter().filter(|(k, _)| *k != "manifest.json").count();
    assert_eq!(manifest(&plain_out), manifest(&first_out));
    for (k, v) in &plain_out {
        if k != "manifest.json" {
            assert_eq!(first_out.get(k), Some(v), "{k}");
        }
    }
    let bad = DIAMOND.replacen("name = \"d\"\n", "name = \"d\"\ncpu_s = -1.0\n", 1);
    let f = Fixture::new(&bad);
    let e = Runner::with_registry(&f.root().join("pipeline.toml"), registry).err().expect("refused").to_string();
    assert!(e.contains("stage d") && e.contains("cpu_s = -1"), "{e}");
}
