//! The real pipeline's cheap stages on the repo's campaign: byte-identical
//! out dirs (outputs, cache records, manifest) for 1 and 2 jobs, and a second
//! run that skips everything.

use rig_pipeline::{Outcome, Runner};
use std::collections::BTreeMap;
use std::path::Path;

const STAGES: [&str; 2] = ["thesis-tables", "campaign-calibration"];

fn tree(dir: &Path, base: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            tree(&p, base, out);
        } else {
            out.insert(p.strip_prefix(base).unwrap().display().to_string(), std::fs::read(&p).unwrap());
        }
    }
}

fn run(out: &Path, jobs: usize) -> rig_pipeline::RunReport {
    let toml = rig_pipeline::testing::workspace_root().join("pipeline.toml");
    Runner::new(&toml).unwrap().out(out).only(&STAGES).jobs(jobs).run().unwrap().into_result().unwrap()
}

#[test]
fn one_and_two_jobs_give_identical_out_dirs_and_a_rerun_skips() {
    let (d1, d2) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run(d1.path(), 1);
    run(d2.path(), 2);
    let (mut t1, mut t2) = (BTreeMap::new(), BTreeMap::new());
    tree(d1.path(), d1.path(), &mut t1);
    tree(d2.path(), d2.path(), &mut t2);
    assert!(t1.len() > 10, "only {} files", t1.len());
    assert_eq!(t1.keys().collect::<Vec<_>>(), t2.keys().collect::<Vec<_>>());
    for (k, v) in &t1 {
        assert!(v == &t2[k], "{k} differs between 1 and 2 jobs");
    }
    let again = run(d1.path(), 2);
    for s in STAGES {
        assert!(matches!(again.stage(s).unwrap().outcome, Outcome::UpToDate), "{}", again.summary(true));
    }
}

#[test]
fn run_stages_names_an_unknown_stage() {
    let d = tempfile::tempdir().unwrap();
    let e = rig_pipeline::testing::run_stages(d.path(), &["no-such-stage"]).unwrap_err();
    assert!(e.to_string().contains("no stage named no-such-stage"), "{e:#}");
}
