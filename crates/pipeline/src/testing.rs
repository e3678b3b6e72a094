//! Test helpers for stage authors: run stages (and their upstream) against the
//! repo's campaign, thesis tables and ../shared, and snapshot a stage's outputs.
//!
//! A stage's snapshot test is one line in `crates/pipeline/tests/snap_<module>.rs`:
//! `#[test] fn snap() { rig_pipeline::testing::snapshot_stage("estimation"); }`.

use crate::runner::{Outcome, RunReport, Runner};
use anyhow::Context;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

/// The workspace root (the folder holding pipeline.toml).
pub fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    here.canonicalize().unwrap_or(here)
}

/// Runs the named stages and everything they depend on, against the repo's
/// default campaign, thesis tables and shared folder, into `out_dir`.
/// Errors when any of them fails (with the stage's error chain).
pub fn run_stages(out_dir: &Path, names: &[&str]) -> anyhow::Result<()> {
    run_report(out_dir, names).map(|_| ())
}

fn run_report(out_dir: &Path, names: &[&str]) -> anyhow::Result<RunReport> {
    let toml = workspace_root().join("pipeline.toml");
    let report = Runner::new(&toml)
        .with_context(|| format!("loading {}", toml.display()))?
        .out(out_dir)
        .only(names)
        .jobs(2)
        .run()?;
    report.into_result()
}

/// One out dir shared by every snapshot test process: nextest runs each test
/// in its own process, and the runner's content-hash cache lets a later
/// process skip the upstream stages an earlier one already ran (a stage
/// re-runs whenever its inputs, params or code change, so this is never
/// stale). A file lock serialises the processes that use it.
fn shared_out_dir() -> PathBuf {
    workspace_root().join("target").join("rig-snapshot-out")
}

/// Holds an exclusive lock on `<out dir>.lock` for the life of the guard.
struct DirLock(#[allow(dead_code)] std::fs::File);

fn lock_shared_out_dir(dir: &Path) -> DirLock {
    if let Some(parent) = dir.parent() {
        std::fs::create_dir_all(parent).unwrap_or_else(|e| panic!("{}: {e}", parent.display()));
    }
    let lock_path = dir.with_extension("lock");
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lock_path)
        .unwrap_or_else(|e| panic!("{}: {e}", lock_path.display()));
    file.lock().unwrap_or_else(|e| panic!("locking {}: {e}", lock_path.display()));
    DirLock(file)
}

/// Serialises tests of one process too (the file lock is per open file).
fn process_mutex() -> &'static Mutex<()> {
    static M: OnceLock<Mutex<()>> = OnceLock::new();
    M.get_or_init(|| Mutex::new(()))
}

/// The shared out dir after running `names` (and their upstream), locked
/// against other test processes while the returned guard lives.
pub fn shared_outputs(names: &[&str]) -> SharedOut {
    let guard = process_mutex().lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let dir = shared_out_dir();
    let lock = lock_shared_out_dir(&dir);
    if let Err(e) = run_report(&dir, names) {
        panic!("running stages {names:?}: {}", crate::describe(&e));
    }
    SharedOut { dir, _lock: lock, _guard: guard }
}

/// See [`shared_outputs`].
pub struct SharedOut {
    pub dir: PathBuf,
    _lock: DirLock,
    _guard: std::sync::MutexGuard<'static, ()>,
}

/// Runs stage `name` (and its upstream) into this process's out dir and
/// insta-snapshots every output of that stage into `crates/pipeline/tests/snapshots/`:
/// CSV, MD, JSON and TXT as text; each figure's SVG text and PNG pixels as
/// hashes in one small YAML snapshot ([`png_pixels_blake3`]: a PNG encoder
/// update that changes no pixel changes no snapshot) (its `.csv` series and `.txt` caption are text
/// snapshots like any other); any other file as hash and size.
/// Snapshot names are `<stage>__<output path with / as __>`.
///
/// Panics (failing the test) when a stage fails or the stage writes nothing.
/// An optional stage whose input is missing (no ../shared) is skipped with a note on stderr.
pub fn snapshot_stage(name: &str) {
    let _guard = process_mutex().lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let dir = shared_out_dir();
    let _lock = lock_shared_out_dir(&dir);
    let report = match run_report(&dir, &[name]) {
        Ok(r) => r,
        Err(e) => panic!("running stage {name}: {}", crate::describe(&e)),
    };
    let stage = report.stage(name).unwrap_or_else(|| panic!("stage {name} is not in pipeline.toml"));
    if matches!(stage.outcome, Outcome::SkippedOptional) {
        eprintln!("snapshot_stage({name}): skipped: {}", stage.reasons.join("; "));
        return;
    }
    let outputs = stage.outputs();
    assert!(!outputs.is_empty(), "stage {name} wrote no outputs ({:?})", stage.outcome);
    let snapshots = snapshot_texts(&dir, &outputs);
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path(workspace_root().join("crates/pipeline/tests/snapshots"));
    settings.set_prepend_module_to_snapshot(false);
    settings.set_omit_expression(true);
    settings.bind(|| {
        for (rel, text) in snapshots {
            let snap_name = format!("{name}__{}", rel.replace('/', "__"));
            insta::assert_snapshot!(snap_name, text);
        }
    });
}

/// Output path (figures: `figures/<id>.render`) -> the text to snapshot.
fn snapshot_texts(dir: &Path, outputs: &BTreeMap<String, crate::FileHash>) -> BTreeMap<String, String> {
    let mut texts = BTreeMap::new();
    let mut renders: BTreeMap<String, BTreeMap<&'static str, String>> = BTreeMap::new();
    for (rel, hash) in outputs {
        let ext = rel.rsplit_once('.').map(|(_, e)| e).unwrap_or("");
        let stem = rel.rsplit_once('.').map(|(s, _)| s).unwrap_or(rel);
        match ext {
            "csv" | "md" | "json" | "txt" => {
                let path = dir.join(rel);
                let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                texts.insert(rel.clone(), text);
            }
            "svg" if rel.starts_with("figures/") => {
                renders.entry(format!("{stem}.render")).or_default().insert("svg_blake3", hash.blake3.clone());
            }
            // The decoded pixels, not the file: only a visible change fails.
            "png" if rel.starts_with("figures/") => {
                let path = dir.join(rel);
                let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                let pixels = png_pixels_blake3(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                renders.entry(format!("{stem}.render")).or_default().insert("pixels_blake3", pixels);
            }
            _ => {
                texts.insert(rel.clone(), format!("blake3: {}\nsize: {}\n", hash.blake3, hash.size));
            }
        }
    }
    for (rel, fields) in renders {
        let text: String = fields.iter().map(|(k, v)| format!("{k}: {v}\n")).collect();
        texts.insert(rel, text);
    }
    texts
}

/// blake3 of a PNG's decoded RGB8 pixels, prefixed by its width and height:
/// the same for every encoding of the same picture (compression level,
/// filter, encoder version), different for any changed pixel.
pub fn png_pixels_blake3(png: &[u8]) -> Result<String, String> {
    let ((w, h), rgb) = rig_figures::decode_png(png)?;
    let mut hasher = blake3::Hasher::new();
    hasher.update(&w.to_le_bytes());
    hasher.update(&h.to_le_bytes());
    hasher.update(&rgb);
    Ok(hasher.finalize().to_hex().to_string())
}

/// Developer aid for stage authors: runs only stage `name` against an out dir
/// that already holds its upstream outputs (`out`), without re-running or
/// re-checking upstream stages, and writes what it staged to `out/dev-<name>/`.
pub fn dev_run_only(name: &str, out: &Path) -> anyhow::Result<()> {
    let root = workspace_root();
    // The stage's params as the runner hands them over, `[shared.*]` tables included.
    let config = crate::PipelineConfig::load(&root.join("pipeline.toml"), crate::stages::lookup)?;
    let params = config.stage(name).map(|d| d.params.clone()).unwrap_or_default();
    let body = crate::stages::lookup(name).with_context(|| format!("no stage {name}"))?;
    let shared = root.join("../shared");
    let mut ctx = crate::StageCtx::new(
        name,
        &root.join("data/emulated-rig-2026"),
        &root.join("data/thesis"),
        shared.exists().then_some(shared.as_path()),
        out,
        params,
    );
    body(&mut ctx)?;
    for (rel, bytes) in ctx.into_staged() {
        let path = out.join(format!("dev-{name}")).join(rel);
        std::fs::create_dir_all(path.parent().expect("a file path has a parent"))?;
        std::fs::write(path, bytes)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::png_pixels_blake3;
    use rig_figures::{PngSettings, SIZE_PX, encode_png, render_rgb};
    use rig_types::{SeriesStyle, figure, series};

    #[test]
    fn pixel_hash_ignores_the_encoding_and_sees_one_pixel() {
        let spec = figure(
            "t",
            "pixel hash",
            "",
            ("x", 1),
            ("y", 1),
            vec![series("s", vec![0.0, 1.0, 2.0], vec![0.0, 2.0, 1.0], SeriesStyle::Line)],
        );
        let rgb = render_rgb(&spec).unwrap();
        let fast = PngSettings { compression: png::Compression::Fast, filter: png::FilterType::NoFilter };
        let best = PngSettings { compression: png::Compression::Best, filter: png::FilterType::Paeth };
        let (a, b) = (encode_png(SIZE_PX, &rgb, fast).unwrap(), encode_png(SIZE_PX, &rgb, best).unwrap());
        assert_ne!(a, b, "the two encodings must differ for this test to mean anything");
        assert_eq!(png_pixels_blake3(&a).unwrap(), png_pixels_blake3(&b).unwrap());
        let mut moved = rgb.clone();
        let i = 3 * (SIZE_PX.0 as usize * 300 + 450);
        moved[i] ^= 0x01;
        let c = encode_png(SIZE_PX, &moved, fast).unwrap();
        assert_ne!(png_pixels_blake3(&a).unwrap(), png_pixels_blake3(&c).unwrap());
        assert!(png_pixels_blake3(b"not a png").is_err());
    }
}
