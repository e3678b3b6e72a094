//! `cargo xtask ARGS`: builds the workspace's binaries when what they are
//! built from changed, then runs `rig-lab ARGS` (the pipeline's command line,
//! `crates/pipeline/src/bin/rig-lab`: `reproduce`, `graph`, `diff`,
//! `merge-shards`, their flags and outputs). Standard library only, so that
//! cargo's freshness check of this crate (`cargo run -p xtask`, the
//! `.cargo/config.toml` alias) walks one crate, not the pipeline's whole
//! dependency graph.
//!
//! The build is one `cargo build --workspace --bins --quiet`: a `--workspace`
//! build, so dependencies' features resolve as for the tests and the
//! binary's libraries are the ones `cargo nextest run --workspace` builds.
//! It is started only when the build stamp `rig-lab.stamp` beside the binary
//! differs from what the sources on disk give: cargo's freshness walk of the
//! workspace costs about as much as the one this crate used to need
//! (docs/performance.md, "The no-op floor"), the stamp a few milliseconds.
//! The stamp holds the hash of what the binary is built from and the
//! binary's size and modification time after the build:
//!
//! - the pipeline's source fingerprint (`crates/pipeline/src/fingerprint.rs`,
//!   compiled in here with `#[path]`: the root and member manifests,
//!   `Cargo.lock`, every file under each member's `src/` and what those
//!   include), and besides it each member's `build.rs`, `.cargo/config.toml`,
//!   the rust-toolchain files and the cargo home's `config.toml`;
//! - the environment variables that change a build (`RUSTFLAGS`, `RUSTC*`,
//!   `CARGO_BUILD_*`, `CARGO_PROFILE_*`, …) and the cargo binary (path,
//!   size, modification time: a toolchain update);
//!
//! so any of them changing, or the binary replaced by another build (`cargo
//! build -p rig-pipeline`), runs cargo again, which decides what to rebuild.
//! The stamp's inputs are hashed before cargo starts: an edit during the build
//! leaves a stamp that no longer matches, and the next run builds again.
//! What the stamp cannot see (a system library, a registry crate edited in
//! place) cargo would; `rig-lab reproduce` itself refuses to run from
//! sources other than it was built from (`rig_pipeline::check_built_from`).

#[allow(dead_code)]
#[path = "../../crates/pipeline/src/fingerprint.rs"]
mod fingerprint;

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The binary this task builds and runs (`crates/pipeline/src/bin/rig-lab`).
const BINARY: &str = "rig-lab";

/// Environment variables that change what cargo builds, by prefix.
const BUILD_ENV_PREFIXES: [&str; 9] = [
    "RUSTC",
    "RUSTFLAGS",
    "RUSTDOCFLAGS",
    "RUSTUP_TOOLCHAIN",
    "CARGO_BUILD_",
    "CARGO_PROFILE_",
    "CARGO_ENCODED_",
    "CARGO_TARGET_",
    "CARGO_INCREMENTAL",
];

/// Environment variables `cargo run` sets for the package it runs (xtask),
/// by prefix: not handed to the build.
const PACKAGE_ENV_PREFIXES: [&str; 6] = [
    "CARGO_PKG_",
    "CARGO_MANIFEST_",
    "CARGO_CRATE_NAME",
    "CARGO_BIN_NAME",
    "CARGO_PRIMARY_PACKAGE",
    "CARGO_RUSTC_CURRENT_DIR",
];

/// The workspace root (this crate is `xtask/`).
fn workspace_root() -> PathBuf {
    let manifest_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest_dir.parent().unwrap_or(manifest_dir).to_path_buf()
}

/// The stamp's first part: what the binary is built from, as it is now
/// (`env`: this process's environment).
fn inputs_now(root: &Path, env: impl Iterator<Item = (OsString, OsString)>) -> std::io::Result<String> {
    let (mut files, _) = fingerprint::source_files(root)?;
    let sources = fingerprint::hash_files(root, &files)?;
    files.clear();
    for e in std::fs::read_dir(root.join("crates"))? {
        let dir = e?.file_name().to_string_lossy().into_owned();
        files.push(format!("crates/{dir}/build.rs"));
    }
    files.sort();
    files.extend([".cargo/config.toml", ".cargo/config", "rust-toolchain.toml", "rust-toolchain"].map(String::from));
    let build = fingerprint::hash_files(root, &files)?;
    let mut text = format!("sources {sources}\nbuild files {build}\n");
    let cargo_home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")));
    if let Some(home) = cargo_home {
        let names = ["config.toml", "config"].map(String::from);
        text += &format!("cargo home {}\n", fingerprint::hash_files(&home, &names)?);
    }
    let mut env: Vec<(String, String)> = env
        .filter_map(|(k, v)| Some((k.into_string().ok()?, v.to_string_lossy().into_owned())))
        .filter(|(k, _)| BUILD_ENV_PREFIXES.iter().any(|p| k.starts_with(p)))
        .collect();
    env.sort();
    for (k, v) in env {
        text += &format!("env {k}={v:?}\n");
    }
    text += &format!("cargo {}\n", file_identity(&cargo()));
    Ok(text)
}

/// Path, size and modification time of a file (`absent` when it is not there).
fn file_identity(path: &Path) -> String {
    let found = if path.components().count() > 1 { Some(path.to_path_buf()) } else { which(path) };
    match found.as_deref().map(std::fs::metadata) {
        Some(Ok(m)) => {
            let modified = m.modified().ok().and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok());
            format!("{} {} {}", path.display(), m.len(), modified.map_or(0, |d| d.as_nanos()))
        }
        _ => format!("{} absent", path.display()),
    }
}

/// `name` on `PATH`.
fn which(name: &Path) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?).map(|d| d.join(name)).find(|p| p.is_file())
}

/// The cargo that runs this task (`CARGO`, set by `cargo run`), else `cargo` on `PATH`.
fn cargo() -> PathBuf {
    std::env::var_os("CARGO").map_or_else(|| PathBuf::from("cargo"), PathBuf::from)
}

/// Writes `text` to `path` through a temporary file and a rename.
fn write_atomic(path: &Path, text: &str) -> std::io::Result<()> {
    let tmp = path.with_extension(format!("stamp.tmp{}", std::process::id()));
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, path)
}

/// Builds the workspace's binaries unless the stamp says nothing changed.
fn build_if_stale(root: &Path, binary: &Path) -> Result<(), String> {
    let stamp = binary.with_extension("stamp");
    let inputs = inputs_now(root, std::env::vars_os())
        .map_err(|e| format!("reading the sources under {}: {e}", root.display()))?;
    let expected = format!("{inputs}binary {}\n", file_identity(binary));
    if binary.is_file() && std::fs::read_to_string(&stamp).is_ok_and(|s| s == expected) {
        return Ok(());
    }
    let cargo = cargo();
    let mut build = Command::new(&cargo);
    build.args(["build", "--workspace", "--bins", "--quiet"]).current_dir(root);
    // What `cargo run` set for this package only: the build is the workspace's, as from a shell.
    for (k, _) in std::env::vars_os() {
        let k = k.to_string_lossy();
        if PACKAGE_ENV_PREFIXES.iter().any(|p| k.starts_with(p)) {
            build.env_remove(&*k);
        }
    }
    let status = match build.status() {
        Ok(status) => status,
        // A machine that runs the built binaries without a toolchain (a cluster's
        // compute node): the binary stands, and `reproduce` checks what it was built from.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound && binary.is_file() => {
            eprintln!("xtask: {} not found, running {} as built", cargo.display(), binary.display());
            return Ok(());
        }
        Err(e) => return Err(format!("{} build --workspace --bins: {e}", cargo.display())),
    };
    if !status.success() {
        return Err(format!("`cargo build --workspace --bins` failed ({status})"));
    }
    let built = format!("{inputs}binary {}\n", file_identity(binary));
    // A stamp that cannot be written only costs the next run a freshness check.
    if let Err(e) = write_atomic(&stamp, &built) {
        eprintln!("xtask: could not write {}: {e}", stamp.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    let root = workspace_root();
    // `rig-lab` is built into the folder this binary was built into (same target dir and profile).
    let exe = std::env::current_exe().unwrap_or_default();
    let binary = exe.with_file_name(format!("{BINARY}{}", std::env::consts::EXE_SUFFIX));
    if let Err(e) = build_if_stale(&root, &binary) {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    run(&binary, &args)
}

/// Runs `binary ARGS` in place of this process (its exit code is ours).
#[cfg(unix)]
fn run(binary: &Path, args: &[OsString]) -> ExitCode {
    use std::os::unix::process::CommandExt;
    // This process's own name as argv[0]: usage lines say `xtask` as before.
    let name = std::env::args_os().next().unwrap_or_else(|| BINARY.into());
    let e = Command::new(binary).arg0(name).args(args).exec();
    eprintln!("error: running {}: {e}", binary.display());
    ExitCode::FAILURE
}

/// Runs `binary ARGS` and returns its exit code.
#[cfg(not(unix))]
fn run(binary: &Path, args: &[OsString]) -> ExitCode {
    match Command::new(binary).args(args).status() {
        Ok(s) => ExitCode::from(s.code().map_or(1, |c| c.clamp(0, 255) as u8)),
        Err(e) => {
            eprintln!("error: running {}: {e}", binary.display());
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder under the system's temporary dir (this crate has no dependencies).
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("xtask-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn write(root: &Path, rel: &str, text: &str) {
        let p = root.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }

    fn env(pairs: &[(&str, &str)]) -> impl Iterator<Item = (OsString, OsString)> {
        pairs.iter().map(|(k, v)| (OsString::from(k), OsString::from(v))).collect::<Vec<_>>().into_iter()
    }

    /// What the binary is built from moves the stamp's inputs: a source, a
    /// build script appearing, the cargo configuration, a build variable; a
    /// test file and a run-time variable do not.
    #[test]
    fn the_stamp_moves_with_what_the_binary_is_built_from_and_only_with_it() {
        let root = scratch("stamp");
        write(&root, "Cargo.toml", "[workspace]\n");
        write(&root, "Cargo.lock", "# lock\n");
        write(&root, "crates/a/Cargo.toml", "[package]\n");
        write(&root, "crates/a/src/lib.rs", "pub fn f() {}\n");
        let quiet = [("PATH", "/bin"), ("RUST_BACKTRACE", "1")];
        let base = inputs_now(&root, env(&quiet)).unwrap();
        assert_eq!(inputs_now(&root, env(&quiet)).unwrap(), base, "deterministic");
        write(&root, "crates/a/tests/t.rs", "#[test] fn t() {}\n");
        assert_eq!(inputs_now(&root, env(&[("RUST_LOG", "debug")])).unwrap(), base, "a test file, a run-time variable");
        let loud = [("RUSTFLAGS", "-C target-cpu=native")];
        assert_ne!(inputs_now(&root, env(&loud)).unwrap(), base, "RUSTFLAGS");
        assert_ne!(inputs_now(&root, env(&[("CARGO_PROFILE_DEV_OPT_LEVEL", "1")])).unwrap(), base, "a profile");
        for (rel, text) in [
            ("crates/a/src/lib.rs", "pub fn g() {}\n"),
            ("crates/a/build.rs", "fn main() {}\n"),
            (".cargo/config.toml", "[build]\n"),
            ("rust-toolchain.toml", "[toolchain]\n"),
            ("Cargo.lock", "# lock 2\n"),
        ] {
            let before = inputs_now(&root, env(&quiet)).unwrap();
            write(&root, rel, text);
            assert_ne!(inputs_now(&root, env(&quiet)).unwrap(), before, "{rel}");
        }
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// The binary's identity is part of the stamp: another build of it (a
    /// different size or time) does not match, and a missing one says so.
    #[test]
    fn a_rebuilt_or_missing_binary_does_not_match_its_stamp() {
        let root = scratch("binary");
        let bin = root.join("rig-lab");
        assert!(file_identity(&bin).ends_with(" absent"));
        std::fs::write(&bin, b"one").unwrap();
        let first = file_identity(&bin);
        std::fs::write(&bin, b"other").unwrap();
        assert_ne!(file_identity(&bin), first);
        std::fs::remove_dir_all(&root).unwrap();
    }
}
