//! Content hashes (blake3, hex): files, directories hashed recursively in
//! sorted path order, and stage parameters as canonical TOML text.

use crate::error::PipelineError;
use std::path::{Path, PathBuf};

/// Hex blake3 of bytes.
pub fn hash_bytes(bytes: &[u8]) -> String {
    blake3::hash(bytes).to_hex().to_string()
}

/// Hex blake3 of a file's content.
pub fn hash_file(path: &Path) -> Result<String, PipelineError> {
    let mut hasher = blake3::Hasher::new();
    let mut file = std::fs::File::open(path).map_err(|source| io(path, source))?;
    std::io::copy(&mut file, &mut hasher).map_err(|source| io(path, source))?;
    Ok(hasher.finalize().to_hex().to_string())
}

/// A file's hash, or for a directory the hash of every file under it: the
/// relative path (with `/`) and content hash of each, in sorted path order, so
/// a rename or a moved file changes it but the folder's location does not.
pub fn hash_path(path: &Path) -> Result<String, PipelineError> {
    let meta = std::fs::metadata(path).map_err(|source| io(path, source))?;
    if !meta.is_dir() {
        return hash_file(path);
    }
    let mut hasher = blake3::Hasher::new();
    hasher.update(b"rig-lab dir v1\0");
    for rel in list_files(path)? {
        let h = hash_file(&path.join(&rel))?;
        hasher.update(rel.as_bytes());
        hasher.update(b"\0");
        hasher.update(h.as_bytes());
        hasher.update(b"\n");
    }
    Ok(hasher.finalize().to_hex().to_string())
}

/// Every file under `dir` as a `/`-separated relative path, sorted. Hidden
/// entries (`.cache`, temporary files, editor swap files) are left out.
pub fn list_files(dir: &Path) -> Result<Vec<String>, PipelineError> {
    let mut out = Vec::new();
    walk(dir, "", &mut out)?;
    out.sort();
    Ok(out)
}

fn walk(dir: &Path, prefix: &str, out: &mut Vec<String>) -> Result<(), PipelineError> {
    let entries = std::fs::read_dir(dir).map_err(|source| io(dir, source))?;
    for entry in entries {
        let entry = entry.map_err(|source| io(dir, source))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let rel = if prefix.is_empty() { name.clone() } else { format!("{prefix}/{name}") };
        let path = entry.path();
        let meta = std::fs::metadata(&path).map_err(|source| io(&path, source))?;
        if meta.is_dir() {
            walk(&path, &rel, out)?;
        } else {
            out.push(rel);
        }
    }
    Ok(())
}

/// Parameters as canonical text: keys sorted at every level, one spelling per
/// value, so formatting or key order in pipeline.toml does not change a key.
pub fn canonical_params(params: &toml::Table) -> std::collections::BTreeMap<String, String> {
    params.iter().map(|(k, v)| (k.clone(), canonical_value(v))).collect()
}

fn canonical_value(v: &toml::Value) -> String {
    match v {
        toml::Value::Array(items) => {
            format!("[{}]", items.iter().map(canonical_value).collect::<Vec<_>>().join(", "))
        }
        toml::Value::Table(t) => {
            let mut keys: Vec<&String> = t.keys().collect();
            keys.sort();
            let body: Vec<String> = keys.iter().map(|k| format!("{k} = {}", canonical_value(&t[k.as_str()]))).collect();
            format!("{{{}}}", body.join(", "))
        }
        // Scalars: toml's own spelling (strings quoted, floats with a point).
        other => other.to_string(),
    }
}

fn io(path: &Path, source: std::io::Error) -> PipelineError {
    PipelineError::Io { path: PathBuf::from(path), source }
}
