//! Tests of the source fingerprint (`fingerprint.rs`, which the build script
//! and xtask compile without them).

use crate::fingerprint::*;
use std::path::Path;

fn write(root: &Path, rel: &str, text: &str) {
    let p = root.join(rel);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(p, text).unwrap();
}

/// An edit to a covered file (a source, a manifest, the lock file, a file
/// pulled in by include_str!) changes the fingerprint; a test file does not.
#[test]
fn an_edit_to_what_is_compiled_changes_the_fingerprint_and_a_test_edit_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    write(root, "Cargo.toml", "[workspace]\n");
    write(root, "Cargo.lock", "# lock\n");
    write(root, "xtask/Cargo.toml", "[package]\n");
    write(root, "xtask/src/main.rs", "fn main() {}\n");
    write(root, "crates/a/Cargo.toml", "[package]\n");
    write(root, "crates/a/src/lib.rs", "static T: &str = include_str!(\"../../../data/t.toml\");\n");
    write(root, "crates/a/src/inner/m.rs", "pub fn f() {}\n");
    write(root, "crates/a/tests/t.rs", "#[test] fn t() {}\n");
    write(root, "data/t.toml", "x = 1\n");
    let (files, srcs) = source_files(root).unwrap();
    assert_eq!(
        files,
        [
            "Cargo.lock",
            "Cargo.toml",
            "crates/a/Cargo.toml",
            "crates/a/src/inner/m.rs",
            "crates/a/src/lib.rs",
            "data/t.toml"
        ]
    );
    assert_eq!(srcs, ["crates/a/src"]);
    let base = fingerprint(root).unwrap();
    assert_eq!(fingerprint(root).unwrap(), base, "deterministic");
    write(root, "crates/a/tests/t.rs", "#[test] fn t2() {}\n");
    assert_eq!(fingerprint(root).unwrap(), base, "a test file is not compiled into the binary");
    write(root, "xtask/src/main.rs", "fn main() { run() }\n");
    assert_eq!(fingerprint(root).unwrap(), base, "xtask is not compiled into the binary");
    for (rel, text) in [
        ("crates/a/src/inner/m.rs", "pub fn g() {}\n"),
        ("data/t.toml", "x = 2\n"),
        ("Cargo.lock", "# lock 2\n"),
        ("crates/a/src/new.rs", "\n"),
    ] {
        let before = fingerprint(root).unwrap();
        write(root, rel, text);
        assert_ne!(fingerprint(root).unwrap(), before, "{rel}");
    }
}

/// The binary under test was built from the sources on disk, so the
/// build script and the runtime cover the same files the same way.
#[test]
fn this_build_matches_the_workspace_sources() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    crate::check_built_from(&root).expect("built from the sources on disk");
}
