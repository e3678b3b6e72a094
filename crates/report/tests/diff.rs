//! `xtask diff` against a throw-away git repository with two commits: moves
//! beyond printed precision are reported with old → new, reformatting is not,
//! added/removed rows and files are counted, a bad revision is an error.
//!
//! Note on CI: a snapshot that changed without review fails the test suite
//! by insta's own behaviour — with `CI=true` (set by CI runners) a mismatch
//! fails and no `.snap.new` is written. Checked by hand on 2026-11-21 with
//! `CI=true cargo test -p rig-figures` after editing a pinned hash in
//! crates/figures/tests/snapshots/: the test failed and left no `.snap.new`.

use std::path::Path;
use std::process::Command;

fn git(root: &Path, args: &[&str]) {
    let out = Command::new("git").arg("-C").arg(root).args(args).output().expect("git runs");
    assert!(out.status.success(), "git {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn write(root: &Path, rel: &str, text: &str) {
    let p = root.join(rel);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(p, text).unwrap();
}

/// A repository whose first commit holds a small out dir.
fn repo() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    git(root, &["init", "-q"]);
    git(root, &["config", "user.email", "test@example.invalid"]);
    git(root, &["config", "user.name", "diff test"]);
    git(root, &["config", "commit.gpgsign", "false"]);
    write(
        root,
        "reports/tables/stiffness.csv",
        "trial,torque_nm,k_nm_rad\n1,0.142,0.255\n2,0.139,0.260\n3,0.277,0.251\n",
    );
    write(
        root,
        "reports/figures/fig-4-10.csv",
        "series,x,y\nmeasured,0.556,0.142\nmeasured,1.104,0.277\nfit,0.000,0.000\n",
    );
    write(
        root,
        "reports/audit.csv",
        "id,published,recomputed,status\nK_sA,0.268,0.2679,ok\nJ_1E,0.0287,0.0293,inconsistent\n",
    );
    write(root, "reports/tables/gone.csv", "a\n1\n");
    write(root, "reports/index.html", "<p>not compared</p>\n");
    git(root, &["add", "."]);
    git(root, &["commit", "-q", "-m", "baseline"]);
    dir
}

#[test]
fn reports_moves_rows_and_files() {
    let dir = repo();
    let root = dir.path();
    // trial 1: k moves 0.255 → 0.262 (beyond 0.0005); trial 2: printed with one
    // more digit, within precision; trial 3 removed; trial 4 added.
    write(
        root,
        "reports/tables/stiffness.csv",
        "trial,torque_nm,k_nm_rad\n1,0.142,0.262\n2,0.139,0.2604\n4,0.305,0.259\n",
    );
    // Figure series: unchanged text.
    // Audit: a status changes (text), a recomputed value moves.
    write(
        root,
        "reports/audit.csv",
        "id,published,recomputed,status\nK_sA,0.268,0.2679,ok\nJ_1E,0.0287,0.0290,rounding\n",
    );
    std::fs::remove_file(root.join("reports/tables/gone.csv")).unwrap();
    write(root, "reports/tables/new.csv", "a\n1\n");

    let text = rig_report::diff::run(root, "HEAD", "reports").unwrap();
    let expected_lines = [
        "reports/audit.csv: 1 rows changed (1 numeric cells moved, 1 text cells changed), 0 rows added, 0 rows removed",
        "    id=J_1E / recomputed: 0.0293 → 0.0290 (-1.02 %)",
        "    id=J_1E / status: \"inconsistent\" → \"rounding\"",
        "reports/tables/gone.csv: removed",
        "reports/tables/new.csv: added",
        "reports/tables/stiffness.csv: 1 rows changed (1 numeric cells moved, 0 text cells changed), 1 rows added, 1 rows removed",
        "    trial=1 / k_nm_rad: 0.255 → 0.262 (+2.75 %)",
        "    rows added: trial=4",
        "    rows removed: trial=3",
        "summary: 5 files compared: 1 unchanged, 2 changed, 1 added, 1 removed; 2 numeric cells moved beyond printed precision",
    ];
    for line in expected_lines {
        assert!(text.lines().any(|l| l == line), "missing line {line:?} in:\n{text}");
    }
    assert!(!text.contains("fig-4-10"), "an unchanged file is only counted:\n{text}");
    assert!(!text.contains("index.html"), "HTML is not compared:\n{text}");
}

#[test]
fn compares_with_an_older_revision_and_rejects_a_bad_one() {
    let dir = repo();
    let root = dir.path();
    write(
        root,
        "reports/figures/fig-4-10.csv",
        "series,x,y\nmeasured,0.556,0.150\nmeasured,1.104,0.277\nfit,0.000,0.000\n",
    );
    git(root, &["commit", "-q", "-am", "second"]);
    // The working tree equals HEAD: nothing moved against HEAD, one cell against HEAD~1.
    let same = rig_report::diff::run(root, "HEAD", "reports").unwrap();
    assert!(same.contains("4 files compared: 4 unchanged, 0 changed"), "{same}");
    let older = rig_report::diff::run(root, "HEAD~1", "reports/").unwrap();
    assert!(older.contains("    measured #1 / y: 0.142 → 0.150 (+5.63 %)"), "{older}");

    let err = rig_report::diff::run(root, "no-such-rev", "reports").unwrap_err();
    assert!(format!("{err:#}").contains("\"no-such-rev\" is not a commit"), "{err:#}");
}
