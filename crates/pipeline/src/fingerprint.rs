//! The fingerprint of the workspace sources a binary is built from.
//!
//! A stage's cache key covers its code as it is on disk (module `code`), so a
//! binary built from older sources (`target/debug/rig-lab` run directly after
//! an edit, without the rebuild `cargo xtask` does) would store its old
//! results under the new code's keys, and every later run would trust them.
//! The build script of this crate hashes the sources into the binary
//! (`RIG_SOURCE_FINGERPRINT`) and `rig-lab reproduce` refuses to run when
//! the sources on disk hash differently ([`crate::check_built_from`]).
//!
//! Covered: the root `Cargo.toml` and `Cargo.lock`; for every folder under
//! `crates/`, its `Cargo.toml` and every file under `src/`; and every file
//! those sources pull in with `include_str!` or `include_bytes!`. Not
//! `xtask/`: the binary is not built from it (`cargo xtask` only builds and
//! runs `rig-lab`). The hash is 64-bit FNV-1a's step over each file's path,
//! length and bytes in path order, taken 8 bytes (a little-endian word) at a
//! time and the tail byte by byte (this crate runs unoptimised in the dev
//! profile: a step per word is 8× fewer steps than per byte): it detects an
//! edit, it is not a security measure.
//!
//! This file is also compiled into the build script and into `xtask` (whose
//! build stamp hashes these files and a few more: `xtask/src/main.rs`) with
//! `#[path]`, so it uses the standard library only and its tests live in
//! `fingerprint_tests.rs`.

use std::path::{Component, Path};

/// `include_str!("p")` and `include_bytes!("p")` arguments.
pub fn includes(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for mac in ["include_str!(\"", "include_bytes!(\""] {
        let mut rest = text;
        while let Some(i) = rest.find(mac) {
            rest = &rest[i + mac.len()..];
            if let Some(end) = rest.find('"') {
                out.push(rest[..end].to_string());
            }
        }
    }
    out
}

/// `inc` (relative to the folder of `file`) as a normalised path relative to the root.
pub fn join_rel(file: &str, inc: &str) -> String {
    let mut parts: Vec<String> = Vec::new();
    let base = Path::new(file).parent().unwrap_or(Path::new("")).join(inc);
    for c in base.components() {
        match c {
            Component::ParentDir => {
                parts.pop();
            }
            Component::Normal(s) => parts.push(s.to_string_lossy().into_owned()),
            _ => {}
        }
    }
    parts.join("/")
}

/// Files under `root/rel` (a folder), as `/`-separated paths relative to the root.
fn walk(root: &Path, rel: &str, out: &mut Vec<String>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(root.join(rel))?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let child = format!("{rel}/{}", e.file_name().to_string_lossy());
        if e.file_type()?.is_dir() {
            walk(root, &child, out)?;
        } else {
            out.push(child);
        }
    }
    Ok(())
}

/// The covered files (see the module docs) and the `src` folders they come
/// from, relative to `root`, sorted.
pub fn source_files(root: &Path) -> std::io::Result<(Vec<String>, Vec<String>)> {
    let mut members = Vec::new();
    let mut crates: Vec<_> = std::fs::read_dir(root.join("crates"))?.collect::<Result<_, _>>()?;
    crates.sort_by_key(|e| e.file_name());
    for e in crates {
        if e.path().join("Cargo.toml").is_file() {
            members.push(format!("crates/{}", e.file_name().to_string_lossy()));
        }
    }
    let mut files = vec!["Cargo.toml".to_string(), "Cargo.lock".to_string()];
    let mut src_dirs = Vec::new();
    for m in &members {
        files.push(format!("{m}/Cargo.toml"));
        let src = format!("{m}/src");
        if root.join(&src).is_dir() {
            walk(root, &src, &mut files)?;
            src_dirs.push(src);
        }
    }
    let mut pulled = Vec::new();
    for f in files.iter().filter(|f| f.ends_with(".rs")) {
        let text = std::fs::read_to_string(root.join(f))?;
        pulled.extend(includes(&text).iter().map(|inc| join_rel(f, inc)).filter(|p| root.join(p).is_file()));
    }
    files.extend(pulled);
    files.sort();
    files.dedup();
    Ok((files, src_dirs))
}

/// The fingerprint of the sources under `root` (16 hex digits).
pub fn fingerprint(root: &Path) -> std::io::Result<String> {
    hash_files(root, &source_files(root)?.0)
}

/// The same hash over `files` (relative to `root`) in the order given; a
/// file that does not exist is hashed as its path and the length `u64::MAX`
/// (no file has that length), so creating or deleting one changes the hash.
pub fn hash_files(root: &Path, files: &[String]) -> std::io::Result<String> {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        let words = bytes.chunks_exact(8);
        let tail = words.remainder();
        for w in words {
            h = (h ^ u64::from_le_bytes(w.try_into().expect("8 bytes"))).wrapping_mul(PRIME);
        }
        for &b in tail {
            h = (h ^ u64::from(b)).wrapping_mul(PRIME);
        }
    };
    for f in files {
        match std::fs::read(root.join(f)) {
            Ok(bytes) => {
                feed(f.as_bytes());
                feed(&(bytes.len() as u64).to_le_bytes());
                feed(&bytes);
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                feed(f.as_bytes());
                feed(&u64::MAX.to_le_bytes());
            }
            Err(e) => return Err(e),
        }
    }
    Ok(format!("{h:016x}"))
}
