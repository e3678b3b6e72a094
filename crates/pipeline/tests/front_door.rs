//! The front door of a run (issue 24): a campaign that lacks what an enabled
//! stage needs is refused before anything is written, naming the file, the
//! rule and the stage; every refusal says each clause once.

use rig_pipeline::{PipelineError, Runner};
use std::path::{Path, PathBuf};

/// A copy of the shipped campaign in `dir/campaign`, without the runs whose
/// campaign.toml block satisfies `drop` (their CSV files are not copied).
fn campaign_without(dir: &Path, drop: impl Fn(&str) -> bool) -> PathBuf {
    let src = rig_pipeline::testing::workspace_root().join("data/emulated-rig-2026");
    let camp = dir.join("campaign");
    std::fs::create_dir_all(camp.join("runs")).unwrap();
    let text = std::fs::read_to_string(src.join("campaign.toml")).unwrap();
    let mut blocks = text.split("[[runs]]");
    let mut kept = blocks.next().unwrap().to_string();
    for block in blocks {
        if drop(block) {
            continue;
        }
        kept.push_str("[[runs]]");
        kept.push_str(block);
        let file = block.lines().find_map(|l| l.strip_prefix("file = ")).unwrap().trim_matches('"');
        std::fs::copy(src.join(file), camp.join(file)).unwrap();
    }
    std::fs::write(camp.join("campaign.toml"), kept).unwrap();
    camp
}

fn of_kind(kind: &str) -> impl Fn(&str) -> bool + '_ {
    move |block: &str| block.contains(&format!("kind = \"{kind}\""))
}

fn runner(camp: &Path, out: &Path) -> Runner {
    let root = rig_pipeline::testing::workspace_root();
    Runner::new(&root.join("pipeline.toml")).unwrap().campaign(camp).out(out)
}

/// The refusal as xtask prints it, after checking nothing was written.
fn refusal(r: Runner, out: &Path) -> String {
    let err = r.run().unwrap_err();
    assert!(matches!(err, PipelineError::CampaignUnfit { .. }), "{err}");
    assert!(!out.exists(), "nothing under --out, not even the folder: {err}");
    let msg = rig_pipeline::describe(&err.into());
    assert_eq!(msg.lines().count(), 1, "{msg}");
    assert_no_clause_repeats(&msg);
    msg
}

/// Splits a message at `: ` and `; ` and asserts no clause occurs twice.
fn assert_no_clause_repeats(msg: &str) {
    let mut seen = std::collections::BTreeSet::new();
    for clause in msg.split(": ").flat_map(|c| c.split("; ")) {
        assert!(seen.insert(clause), "clause {clause:?} repeats in {msg}");
    }
}

/// The refusal of the shipped campaign without the runs of `kind`, and the
/// head every such refusal starts with (the file, then what it has).
fn refused_without(kind: &str) -> (String, String) {
    let dir = tempfile::tempdir().unwrap();
    let camp = campaign_without(dir.path(), of_kind(kind));
    let out = dir.path().join("out");
    let msg = refusal(runner(&camp, &out), &out);
    (msg, format!("campaign refused: {}: no {kind} run: ", camp.join("campaign.toml").display()))
}

/// One test per run kind: the stages needing it are named, with the rule.
#[test]
fn a_campaign_without_force_calibrations_is_refused_before_any_stage() {
    let (msg, head) = refused_without("force_calibration");
    assert!(msg.starts_with(&head), "{msg}");
    assert!(msg.contains("stage campaign-calibration needs at least 3 (the force-sensor line of Table 4.6"), "{msg}");
    assert!(!msg.contains("stage estimation"), "{msg}");
}

#[test]
fn a_campaign_without_static_twists_is_refused_before_any_stage() {
    let (msg, head) = refused_without("static_twist");
    assert_eq!(msg, format!("{head}stage campaign-calibration needs at least 2 (the static stiffness of Table 4.3)"));
}

#[test]
fn a_campaign_without_voltage_steps_is_refused_before_any_stage() {
    let (msg, head) = refused_without("voltage_step");
    let stages = "stage campaign-calibration needs at least 1 (the free decay of Table 4.2 and the inertia of Eq. 4-4), \
                  stage estimation needs at least 1 (the least-squares fit of Tables 4.4-4.5)";
    assert_eq!(msg, format!("{head}{stages}"));
}

/// Also with `--only` a stage whose upstream needs the runs: estimation
/// needs operating points, calibration alone does not.
#[test]
fn a_campaign_without_operating_points_is_refused_before_any_stage() {
    let dir = tempfile::tempdir().unwrap();
    let camp = campaign_without(dir.path(), of_kind("operating_point"));
    let out = dir.path().join("out");
    let msg = refusal(runner(&camp, &out), &out);
    assert!(msg.contains("campaign.toml: no operating_point run: stage estimation needs at least 1 (the PI gains and the Coulomb friction), stage diagnosis needs at least 3 (cross-validation over runs)"), "{msg}");
    let msg = refusal(runner(&camp, &out).only(&["simulation"]), &out);
    assert!(msg.contains("stage estimation needs") && !msg.contains("diagnosis"), "{msg}");
    // Only what the selected stages need: calibration runs without operating points.
    let r = runner(&camp, &out).only(&["campaign-calibration"]).dry_run(true).run().unwrap();
    assert_eq!(r.ran(), ["campaign-calibration"], "{}", r.summary(true));
    assert!(!out.exists(), "a dry run writes nothing");
}

/// Metadata counts too: three force calibrations with one load make no line.
#[test]
fn force_calibrations_with_a_single_load_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let camp = campaign_without(dir.path(), |_| false);
    let toml = camp.join("campaign.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    let mut one_load = String::new();
    for line in text.lines() {
        one_load.push_str(if line.starts_with("load_n = ") { "load_n = 2.0" } else { line });
        one_load.push('\n');
    }
    std::fs::write(&toml, one_load).unwrap();
    let out = dir.path().join("out");
    let msg = refusal(runner(&camp, &out), &out);
    assert!(msg.contains("5 force_calibration runs with 1 different load_n values: stage campaign-calibration needs at least 2 different load_n values"), "{msg}");
}

/// The reader's own refusal is said once (it was `…: format must be … :
/// …: format must be …`), and so is an I/O error's cause.
#[test]
fn every_refusal_says_each_clause_once() {
    let dir = tempfile::tempdir().unwrap();
    let camp = campaign_without(dir.path(), |_| false);
    let toml = camp.join("campaign.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    std::fs::write(&toml, text.replacen("rig-campaign/1", "rig-campaign/2", 1)).unwrap();
    let out = dir.path().join("out");
    let err = runner(&camp, &out).run().unwrap_err();
    assert!(matches!(err, PipelineError::Campaign(_)), "{err}");
    let msg = rig_pipeline::describe(&err.into());
    assert!(msg.starts_with("campaign refused: "), "{msg}");
    assert_eq!(msg.matches("format must be exactly").count(), 1, "{msg}");
    assert_no_clause_repeats(&msg);
    assert!(!out.exists());

    let missing = dir.path().join("nowhere");
    let io = PipelineError::Io { path: missing.clone(), source: std::io::Error::other("no such file") };
    let e = anyhow::Error::from(io).context("reading the manifest");
    assert_eq!(rig_pipeline::describe(&e), format!("reading the manifest: {}: no such file", missing.display()));
}

/// The calibration's declared needs are the crate's own limits: one run
/// fewer than a declared minimum, and `rig_calibrate` itself refuses the
/// campaign; at the minimum the pre-flight lets it through and so does the crate.
#[test]
fn the_calibration_needs_are_what_rig_calibrate_refuses() {
    let root = rig_pipeline::testing::workspace_root();
    let shipped = rig_ingest::read_campaign(&root.join("data/emulated-rig-2026")).unwrap();
    let needs = rig_pipeline::stages::needs("campaign-calibration");
    assert_eq!(needs.len(), 3, "{needs:?}");
    for need in needs {
        for keep in [need.min_runs, need.min_runs - 1] {
            let mut c = shipped.clone();
            let mut seen = 0;
            c.runs.retain(|r| {
                seen += usize::from(r.kind.name() == need.kind);
                r.kind.name() != need.kind || seen <= keep
            });
            let unmet = rig_pipeline::needs::unmet(rig_pipeline::stages::needs, ["campaign-calibration"], &c);
            let calibrated = rig_calibrate::calibrate_campaign(&c);
            if keep == need.min_runs {
                assert!(unmet.is_empty(), "{keep} {}: {unmet:?}", need.kind);
                assert!(calibrated.is_ok(), "{keep} {}: {:?}", need.kind, calibrated.err());
            } else {
                assert_eq!(unmet.len(), 1, "{keep} {}: {unmet:?}", need.kind);
                assert!(calibrated.is_err(), "{keep} {}: the crate accepts what the pre-flight refuses", need.kind);
            }
        }
    }
}

/// Calls of [`counting_reader`] (one test uses it).
static READS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// `rig_ingest::read_campaign`, counted.
fn counting_reader(dir: &Path) -> Result<rig_types::Campaign, rig_ingest::IngestError> {
    READS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    rig_ingest::read_campaign(dir)
}

/// Line `n` (1-based) of `file` replaced by `text`.
fn edit_line(file: &Path, n: usize, text: &str) {
    let old = std::fs::read_to_string(file).unwrap();
    let mut lines: Vec<&str> = old.lines().collect();
    lines[n - 1] = text;
    std::fs::write(file, lines.join("\n") + "\n").unwrap();
}

/// The front door's memory (module `accepted`): a rerun on the bytes it
/// accepted does not read them again, a stage that runs reads them once,
/// and a changed, corrupted or truncated file is validated again and
/// refused with the reader's message (file, line, rule), writing nothing.
#[test]
fn an_accepted_campaign_is_not_validated_again_until_its_bytes_change() {
    use std::sync::atomic::Ordering::SeqCst;
    let dir = tempfile::tempdir().unwrap();
    let camp = campaign_without(dir.path(), |_| false);
    let out = dir.path().join("out");
    let run = || {
        runner(&camp, &out)
            .campaign_reader(counting_reader)
            .remember_accepted("test code")
            .only(&["campaign-calibration"])
            .run()
    };
    let first = run().unwrap();
    assert_eq!(first.ran(), ["campaign-calibration"], "{}", first.summary(true));
    assert_eq!(READS.load(SeqCst), 1, "read once, by the front door, and shared with the stage");
    assert!(out.join(".cache/accepted-campaign.json").is_file());
    let again = run().unwrap();
    assert!(again.ran().is_empty(), "{}", again.summary(true));
    assert_eq!(READS.load(SeqCst), 1, "the no-op rerun reads nothing");
    // An output gone: the stage runs, and reads the accepted campaign itself.
    let calibration = out.join("tables/campaign-force-calibration.csv");
    std::fs::remove_file(&calibration).unwrap();
    let rerun = run().unwrap();
    assert_eq!(rerun.ran(), ["campaign-calibration"], "{}", rerun.summary(true));
    assert_eq!(READS.load(SeqCst), 2, "the stage that runs reads the accepted bytes once");
    // A corrupted sample: validated again and refused naming file, line and rule.
    let csv = camp.join("runs/cal-1.csv");
    let good = std::fs::read_to_string(&csv).unwrap();
    edit_line(&csv, 7, "0.0100,abc");
    let before = std::fs::read_dir(&out).unwrap().count();
    let err = run().unwrap_err();
    assert!(matches!(err, PipelineError::Campaign(_)), "{err}");
    let msg = rig_pipeline::describe(&err.into());
    assert!(msg.starts_with(&format!("campaign refused: {}:7: ", csv.display())), "{msg}");
    assert!(msg.contains("brake_force_mv") || msg.contains("number"), "names the rule: {msg}");
    assert_eq!(READS.load(SeqCst), 3);
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), before, "a refusal writes nothing");
    // Truncated mid-line: refused too.
    let cut = good[..good.len() / 2].rfind(',').unwrap() + 1;
    std::fs::write(&csv, &good[..cut]).unwrap();
    let msg = rig_pipeline::describe(&run().unwrap_err().into());
    assert!(msg.starts_with(&format!("campaign refused: {}:", csv.display())), "{msg}");
    // Restored: the record is still that of these bytes (a refusal records nothing).
    std::fs::write(&csv, &good).unwrap();
    assert!(run().unwrap().ran().is_empty());
    assert_eq!(READS.load(SeqCst), 4, "the accepted bytes again: not read");
}

/// The real runner (`Runner::new`, what `cargo xtask reproduce` runs): after
/// a run, a CSV line edited by hand is refused at the next run with the
/// file, the line and the rule, as on the first run.
#[test]
fn a_csv_line_edited_after_a_run_is_refused_with_file_line_and_rule() {
    let dir = tempfile::tempdir().unwrap();
    let camp = campaign_without(dir.path(), |_| false);
    let out = dir.path().join("out");
    let r = runner(&camp, &out).only(&["campaign-calibration"]).run().unwrap();
    assert_eq!(r.ran(), ["campaign-calibration"]);
    let csv = camp.join("runs/cal-2.csv");
    edit_line(&csv, 12, "0.0200,151.75,7");
    let err = runner(&camp, &out).only(&["campaign-calibration"]).run().unwrap_err();
    let msg = rig_pipeline::describe(&err.into());
    assert!(msg.starts_with(&format!("campaign refused: {}:12: ", csv.display())), "{msg}");
}
