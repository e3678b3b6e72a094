//! Embeds the fingerprint of the workspace sources (module `fingerprint`) as
//! `RIG_SOURCE_FINGERPRINT`, so that `cargo xtask reproduce` can refuse to
//! run a binary built from other sources than are on disk.

#[allow(dead_code)]
#[path = "src/fingerprint.rs"]
mod fingerprint;

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (files, src_dirs) = fingerprint::source_files(&root).expect("read the workspace sources");
    // A folder is scanned recursively (a file added to a src folder reruns this script).
    for p in files.iter().chain(&src_dirs) {
        println!("cargo:rerun-if-changed={}", root.join(p).display());
    }
    let fp = fingerprint::fingerprint(&root).expect("hash the workspace sources");
    println!("cargo:rustc-env=RIG_SOURCE_FINGERPRINT={fp}");
}
