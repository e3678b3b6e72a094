//! A stage's code, computed from the source rather than listed by hand: the
//! stage's own file (and folder), the pipeline modules it reaches through
//! `crate::` and `super::`, every workspace crate it names (`rig_x::`) with
//! that crate's workspace dependencies from the `Cargo.toml` files,
//! transitively, and every file pulled in by `include_str!` / `include_bytes!`.
//!
//! The crate graph is read once per run from the workspace `Cargo.toml`
//! (`[workspace.dependencies]` path entries) and each member's
//! `[dependencies]`; no `cargo` process is started. A workspace crate is
//! covered by its `src` folder and its `Cargo.toml`. The scan over-approximates
//! (a `rig_x::` in a comment counts), never under-approximates for the forms
//! it accepts; `tests/tidy.rs` checks each stage against `cargo metadata` and
//! that nothing a stage names is left unresolved.

use crate::error::PipelineError;
use crate::fingerprint::{includes, join_rel};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One workspace crate: its folder (relative to the root) and the library
/// names of the workspace crates it depends on (normal and build dependencies).
#[derive(Debug, Clone)]
struct CrateInfo {
    dir: String,
    deps: Vec<String>,
    /// The files its sources pull in (`include_*!`), relative to the root:
    /// scanned once per index, not once per stage that names the crate.
    includes: OnceLock<Vec<String>>,
}

/// The workspace's crates by library name (`rig_sweep`), read from the `Cargo.toml` files.
#[derive(Debug, Clone, Default)]
pub struct CodeIndex {
    root: PathBuf,
    crates: BTreeMap<String, CrateInfo>,
}

/// What a stage's key covers, and what the scan could not place.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StageCode {
    /// Files and folders, relative to the root, `/`-separated, sorted.
    pub paths: BTreeSet<String>,
    /// Library names of the workspace crates covered (`rig_model`), sorted.
    pub crates: BTreeSet<String>,
    /// References the scan found but could not map to a file (`file: text`).
    pub unresolved: Vec<String>,
}

impl CodeIndex {
    /// Reads `root/Cargo.toml` and each path dependency's `Cargo.toml`. A root
    /// without a workspace `Cargo.toml` gives an empty index (declared code only).
    pub fn load(root: &Path) -> Result<Self, PipelineError> {
        let mut index = CodeIndex { root: root.to_path_buf(), crates: BTreeMap::new() };
        let manifest = root.join("Cargo.toml");
        if !manifest.is_file() {
            return Ok(index);
        }
        let ws = read_toml(&manifest)?;
        let Some(deps) = ws.get("workspace").and_then(|w| w.get("dependencies")).and_then(|d| d.as_table()) else {
            return Ok(index);
        };
        // Package name -> folder, for the workspace's path dependencies.
        let mut dirs: BTreeMap<String, String> = BTreeMap::new();
        for (name, spec) in deps {
            if let Some(path) = spec.get("path").and_then(|p| p.as_str()) {
                dirs.insert(name.clone(), path.trim_end_matches('/').to_string());
            }
        }
        for (name, dir) in &dirs {
            let member = read_toml(&root.join(dir).join("Cargo.toml"))?;
            let mut crate_deps = Vec::new();
            for section in ["dependencies", "build-dependencies"] {
                if let Some(t) = member.get(section).and_then(|d| d.as_table()) {
                    crate_deps.extend(t.keys().filter(|k| dirs.contains_key(*k)).map(|k| lib_name(k)));
                }
            }
            index
                .crates
                .insert(lib_name(name), CrateInfo { dir: dir.clone(), deps: crate_deps, includes: OnceLock::new() });
        }
        Ok(index)
    }

    /// The folder (relative to the root) of the crate with library name `lib`.
    pub fn crate_dir(&self, lib: &str) -> Option<&str> {
        self.crates.get(lib).map(|c| c.dir.as_str())
    }

    /// The code of a stage whose body is in `source` (relative to the root),
    /// plus `extra` paths (pipeline.toml's `code` and `common_code`); `.rs`
    /// files among them, and under folders among them, are scanned too.
    pub fn stage_code(&self, source: Option<&str>, extra: &[String]) -> Result<StageCode, PipelineError> {
        let mut code = StageCode::default();
        let mut queue: Vec<String> = Vec::new();
        if let Some(src) = source {
            queue.push(src.to_string());
            // A stage module's own folder (`stages/report/` for `stages/report.rs`).
            if let Some(stem) = src.strip_suffix(".rs")
                && self.root.join(stem).is_dir()
            {
                queue.push(stem.to_string());
            }
        }
        queue.extend(extra.iter().cloned());
        // The crate holding the stage body is scanned module by module; a path
        // inside any other workspace crate brings in that whole crate.
        let home = source.and_then(|s| self.crate_of(s));
        let mut scanned: BTreeSet<String> = BTreeSet::new();
        while let Some(rel) = queue.pop() {
            code.paths.insert(rel.clone());
            if let Some(lib) = self.crate_of(&rel)
                && Some(lib) != home
            {
                code.crates.insert(lib.to_string());
                continue;
            }
            let path = self.root.join(&rel);
            if !path.exists() {
                continue; // the caller reports a missing path when it hashes it
            }
            for file in rust_files(&path, &rel)? {
                if scanned.insert(file.clone()) {
                    self.scan(&file, &mut code, &mut queue)?;
                }
            }
        }
        // Workspace crates, closed over their dependencies.
        let mut todo: Vec<String> = code.crates.iter().cloned().collect();
        while let Some(lib) = todo.pop() {
            if let Some(info) = self.crates.get(&lib) {
                for d in &info.deps {
                    if code.crates.insert(d.clone()) {
                        todo.push(d.clone());
                    }
                }
            }
        }
        for lib in code.crates.clone() {
            let info = &self.crates[&lib];
            let dir = &info.dir;
            code.paths.insert(format!("{dir}/src"));
            code.paths.insert(format!("{dir}/Cargo.toml"));
            let pulled = match info.includes.get() {
                Some(pulled) => pulled,
                None => {
                    let mut pulled = Vec::new();
                    for file in rust_files(&self.root.join(dir).join("src"), &format!("{dir}/src"))? {
                        let text = read(&self.root.join(&file))?;
                        pulled.extend(includes(&text).iter().map(|inc| join_rel(&file, inc)));
                    }
                    info.includes.get_or_init(|| pulled)
                }
            };
            code.paths.extend(pulled.iter().cloned());
        }
        // A crate's own folder covers the files under it.
        let dirs: Vec<String> = code.paths.iter().filter(|p| self.root.join(p).is_dir()).cloned().collect();
        code.paths.retain(|p| !dirs.iter().any(|d| p != d && p.starts_with(&format!("{d}/"))));
        code.unresolved.sort();
        code.unresolved.dedup();
        Ok(code)
    }

    /// The library name of the workspace crate whose folder holds `rel`.
    fn crate_of(&self, rel: &str) -> Option<&str> {
        self.crates
            .iter()
            .filter(|(_, c)| rel == c.dir || rel.starts_with(&format!("{}/", c.dir)))
            .max_by_key(|(_, c)| c.dir.len())
            .map(|(lib, _)| lib.as_str())
    }

    /// Adds what `file` names: workspace crates, pipeline modules, included files.
    fn scan(&self, file: &str, code: &mut StageCode, queue: &mut Vec<String>) -> Result<(), PipelineError> {
        let text = read(&self.root.join(file))?;
        for inc in includes(&text) {
            queue.push(join_rel(file, &inc));
        }
        for (prefix, first) in path_heads(&text) {
            match prefix.as_str() {
                "crate" => match self.crate_module(file, &first) {
                    Some(m) => queue.push(m),
                    None => code.unresolved.push(format!("{file}: crate::{first}")),
                },
                "super" => queue.extend(self.super_module(file, &first)),
                lib if self.crates.contains_key(lib) => {
                    code.crates.insert(lib.to_string());
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// `crate::first` seen in `file`: the module file, or for an item
    /// re-exported at the crate root (`crate::StageCtx`), the module it comes from.
    fn crate_module(&self, file: &str, first: &str) -> Option<String> {
        let src = crate_src(file)?;
        if let Some(m) = module_file(&self.root, &src, first) {
            return Some(m);
        }
        let lib = read(&self.root.join(&src).join("lib.rs")).ok()?;
        lib.lines().filter_map(|l| l.trim().strip_prefix("pub use ")).find_map(|rest| {
            let (module, items) = rest.split_once("::")?;
            let named = items.split(|c: char| !(c.is_alphanumeric() || c == '_')).any(|w| w == first);
            if named { module_file(&self.root, &src, module) } else { None }
        })
    }

    /// `super::first` seen in `file`: the sibling module, or else the parent module's own file.
    fn super_module(&self, file: &str, first: &str) -> Option<String> {
        let path = Path::new(file);
        let here =
            if path.file_name().is_some_and(|n| n == "mod.rs") { path.parent()?.parent()? } else { path.parent()? };
        let here = here.to_string_lossy().replace('\\', "/");
        if first != "*"
            && let Some(m) = module_file(&self.root, &here, first)
        {
            return Some(m);
        }
        [format!("{here}.rs"), format!("{here}/mod.rs"), format!("{here}/lib.rs")]
            .into_iter()
            .find(|p| self.root.join(p).is_file() && p != file)
    }
}

/// `rig-sweep` -> `rig_sweep`.
fn lib_name(package: &str) -> String {
    package.replace('-', "_")
}

fn read(path: &Path) -> Result<String, PipelineError> {
    std::fs::read_to_string(path).map_err(|source| PipelineError::Io { path: path.to_path_buf(), source })
}

fn read_toml(path: &Path) -> Result<toml::Table, PipelineError> {
    read(path)?.parse::<toml::Table>().map_err(|e| PipelineError::Config {
        path: path.to_path_buf(),
        stage: None,
        reason: format!("computing stage code: {}", e.to_string().trim()),
    })
}

/// `rel` itself when it is a `.rs` file, every `.rs` file under it when it is a folder.
fn rust_files(path: &Path, rel: &str) -> Result<Vec<String>, PipelineError> {
    if path.is_dir() {
        Ok(crate::hash::list_files(path)?
            .into_iter()
            .filter(|f| f.ends_with(".rs"))
            .map(|f| format!("{rel}/{f}"))
            .collect())
    } else if rel.ends_with(".rs") {
        Ok(vec![rel.to_string()])
    } else {
        Ok(Vec::new())
    }
}

/// The `src` folder of the crate `file` belongs to (`crates/pipeline/src`).
fn crate_src(file: &str) -> Option<String> {
    let i = file.rfind("/src/").or_else(|| file.starts_with("src/").then_some(0).map(|_| usize::MAX))?;
    Some(if i == usize::MAX { "src".to_string() } else { file[..i + 4].to_string() })
}

/// `dir/name.rs` or `dir/name/mod.rs` when it exists (and `dir/name/` with it).
fn module_file(root: &Path, dir: &str, name: &str) -> Option<String> {
    let flat = format!("{dir}/{name}.rs");
    if root.join(&flat).is_file() {
        return Some(flat);
    }
    let nested = format!("{dir}/{name}");
    root.join(&nested).join("mod.rs").is_file().then_some(nested)
}

/// Every `head::first` path in `text` (with `use head::{a, b::c}` groups
/// expanded to each first segment): (head, first).
fn path_heads(text: &str) -> Vec<(String, String)> {
    let bytes = text.as_bytes();
    let is_ident = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(off) = text[i..].find("::") {
        let at = i + off;
        i = at + 2;
        let mut start = at;
        while start > 0 && is_ident(bytes[start - 1]) {
            start -= 1;
        }
        // Only the head of a path: not `a::b::c`'s `b`.
        if start == at || (start >= 2 && &text[start - 2..start] == "::") {
            continue;
        }
        let head = &text[start..at];
        let tail = &text[at + 2..];
        if let Some(group) = tail.strip_prefix('{') {
            let inner = &group[..group.find('}').unwrap_or(group.len())];
            for item in inner.split(',') {
                let first = item.trim().split("::").next().unwrap_or("").trim();
                let first = first.split_whitespace().next().unwrap_or("");
                if !first.is_empty() {
                    out.push((head.to_string(), first.to_string()));
                }
            }
        } else {
            let first: String = tail.chars().take_while(|c| c.is_alphanumeric() || *c == '_' || *c == '*').collect();
            if !first.is_empty() {
                out.push((head.to_string(), first));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_heads_reads_paths_and_groups() {
        let text = "use crate::{diff, ctx::StageCtx};\nlet x = rig_model::simulate(a::b::c);\nsuper::*;";
        let heads = path_heads(text);
        assert!(heads.contains(&("crate".into(), "diff".into())));
        assert!(heads.contains(&("crate".into(), "ctx".into())));
        assert!(heads.contains(&("rig_model".into(), "simulate".into())));
        assert!(heads.contains(&("a".into(), "b".into())));
        assert!(!heads.iter().any(|(h, _)| h == "b"));
        assert!(heads.contains(&("super".into(), "*".into())));
    }

    #[test]
    fn includes_resolve_against_the_file() {
        assert_eq!(
            join_rel("crates/pipeline/src/stages/report.rs", "../../../../data/figures.toml"),
            "data/figures.toml"
        );
        assert_eq!(includes("static F: &[u8] = include_bytes!(\"../assets/F.ttf\");"), vec!["../assets/F.ttf"]);
        assert_eq!(crate_src("crates/pipeline/src/stages/x.rs").as_deref(), Some("crates/pipeline/src"));
    }
}
