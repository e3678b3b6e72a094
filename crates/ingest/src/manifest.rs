//! campaign.toml to a checked manifest: format, [rig], and each run's id,
//! kind, file and metadata, every value checked against the format's rules
//! before any CSV is opened.

use crate::IngestError;
use crate::columns::{ColSpec, ColType, TIME_COLUMN};
use rig_types::{RigInfo, RunKind};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};
use toml::Spanned;

/// The only format string this reader accepts.
pub const FORMAT: &str = "rig-campaign/1";

/// A TOML table whose keys keep their source position.
type SpannedTable = BTreeMap<String, Spanned<toml::Value>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCampaign {
    format: Option<Spanned<String>>,
    name: Option<Spanned<String>>,
    description: Option<String>,
    rig: Option<Spanned<SpannedTable>>,
    runs: Option<Vec<Spanned<SpannedTable>>>,
}

/// A run as declared in campaign.toml, checked, CSV not yet read.
#[derive(Debug)]
pub(crate) struct RunEntry {
    pub id: String,
    pub kind: RunKind,
    /// As written in campaign.toml (relative to the folder).
    pub file: PathBuf,
    /// The file, resolved inside the campaign folder.
    pub resolved: PathBuf,
}

/// campaign.toml, checked.
#[derive(Debug)]
pub(crate) struct Manifest {
    pub name: String,
    pub description: String,
    pub rig: RigInfo,
    pub runs: Vec<RunEntry>,
}

/// The run kinds of the format: name, metadata keys, CSV columns.
pub(crate) struct KindSpec {
    pub name: &'static str,
    pub metadata: &'static [&'static str],
    pub columns: &'static [ColSpec],
}

const fn float(name: &'static str) -> ColSpec {
    ColSpec { name, ty: ColType::Float }
}
const fn count(name: &'static str) -> ColSpec {
    ColSpec { name, ty: ColType::Count }
}

/// The table "Run kinds" of recording-format.md.
pub(crate) const KINDS: &[KindSpec] = &[
    KindSpec {
        name: "force_calibration",
        metadata: &["load_n"],
        columns: &[float(TIME_COLUMN), float("brake_force_mv")],
    },
    KindSpec { name: "static_twist", metadata: &["torque_nm"], columns: &[float(TIME_COLUMN), count("rotor_ticks")] },
    KindSpec {
        name: "voltage_step",
        metadata: &["voltage_v"],
        columns: &[float(TIME_COLUMN), float("motor_voltage_v"), count("motor_ticks"), count("rotor_ticks")],
    },
    KindSpec {
        name: "operating_point",
        metadata: &["motor_rpm_setpoint", "normal_force_n", "ramp_s"],
        columns: &[
            float(TIME_COLUMN),
            float("motor_voltage_v"),
            count("motor_ticks"),
            count("rotor_ticks"),
            float("brake_force_mv"),
        ],
    },
];

/// The kind spec of a checked run kind.
pub(crate) fn kind_spec(kind: &RunKind) -> &'static KindSpec {
    KINDS.iter().find(|k| k.name == kind.name()).expect("every RunKind is in KINDS")
}

/// Reads and checks `<dir>/campaign.toml` and resolves every run's file.
pub(crate) fn read_manifest(dir: &Path) -> Result<Manifest, IngestError> {
    let path = dir.join("campaign.toml");
    let text = std::fs::read_to_string(&path).map_err(|source| IngestError::Io {
        file: path.clone(),
        rule: "cannot read campaign.toml".into(),
        source,
    })?;
    let at = |span: std::ops::Range<usize>| Some(line_of(&text, span.start));
    let err = |line: Option<usize>, rule: String| IngestError::rule(&path, line, rule);

    let raw: RawCampaign = toml::from_str(&text).map_err(|e| {
        err(e.span().map(|s| line_of(&text, s.start)), format!("invalid campaign.toml: {}", e.message().trim()))
    })?;

    let format = raw.format.ok_or_else(|| err(None, format!("format = \"{FORMAT}\" is missing")))?;
    if format.get_ref() != FORMAT {
        return Err(err(
            at(format.span()),
            format!("format must be exactly \"{FORMAT}\", found {:?}", format.get_ref()),
        ));
    }
    let name = raw.name.ok_or_else(|| err(None, "name is missing".into()))?;
    if name.get_ref().trim().is_empty() {
        return Err(err(at(name.span()), "name must not be empty".into()));
    }
    let rig_table = raw.rig.ok_or_else(|| {
        err(
            None,
            "[rig] is missing (encoder_ticks_per_rev, brake_disc_radius_m, supply_voltage_v, sample_rate_hz)".into(),
        )
    })?;
    let rig = read_rig(&rig_table, &|span, rule| err(at(span), rule))
        .map_err(|e| e.unwrap_or_else(|rule| err(at(rig_table.span()), rule)))?;

    let raw_runs = raw.runs.unwrap_or_default();
    if raw_runs.is_empty() {
        return Err(err(None, "the campaign has no [[runs]]".into()));
    }
    let canonical_dir = dir.canonicalize().map_err(|source| IngestError::Io {
        file: dir.to_path_buf(),
        rule: "cannot resolve the campaign folder".into(),
        source,
    })?;
    let mut runs: Vec<RunEntry> = Vec::with_capacity(raw_runs.len());
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for (i, table) in raw_runs.iter().enumerate() {
        let table_line = line_of(&text, table.span().start);
        let entry = read_run(i + 1, table.get_ref(), &rig, dir, &canonical_dir, &|span, rule| err(at(span), rule))
            .map_err(|e| e.unwrap_or_else(|rule| err(Some(table_line), rule)))?;
        if let Some(first) = seen.insert(entry.id.clone(), table_line) {
            return Err(err(
                Some(table_line),
                format!("run id {:?} is used twice (first at line {first}); run ids must be unique", entry.id),
            ));
        }
        runs.push(entry);
    }
    refuse_undescribed(dir, &runs)?;
    Ok(Manifest { name: name.into_inner(), description: raw.description.unwrap_or_default(), rig, runs })
}

/// An error located at a key's span (`Ok`) or only at the enclosing table (`Err` of the inner result).
type Located = Result<IngestError, String>;
type MakeErr<'a> = &'a dyn Fn(std::ops::Range<usize>, String) -> IngestError;

fn read_rig(table: &Spanned<SpannedTable>, err: MakeErr<'_>) -> Result<RigInfo, Located> {
    const KEYS: [&str; 4] = ["encoder_ticks_per_rev", "brake_disc_radius_m", "supply_voltage_v", "sample_rate_hz"];
    let t = table.get_ref();
    refuse_unknown(t, &KEYS, "[rig]", err)?;
    let ticks = t.get("encoder_ticks_per_rev").ok_or_else(|| Err("[rig] encoder_ticks_per_rev is missing".into()))?;
    let encoder_ticks_per_rev = match ticks.get_ref() {
        toml::Value::Integer(n) if *n > 0 && *n <= i64::from(u32::MAX) => *n as u32,
        v => {
            return Err(Ok(err(
                ticks.span(),
                format!("[rig] encoder_ticks_per_rev must be a positive integer, found {v}"),
            )));
        }
    };
    let positive = |key: &str| -> Result<f64, Located> {
        let x = number(t, key, "[rig]", err)?;
        if x > 0.0 { Ok(x) } else { Err(Ok(err(t[key].span(), format!("[rig] {key} must be > 0, found {x}")))) }
    };
    Ok(RigInfo {
        encoder_ticks_per_rev,
        brake_disc_radius_m: positive("brake_disc_radius_m")?,
        supply_voltage_v: positive("supply_voltage_v")?,
        sample_rate_hz: positive("sample_rate_hz")?,
    })
}

fn read_run(
    number_in_file: usize,
    t: &SpannedTable,
    rig: &RigInfo,
    dir: &Path,
    canonical_dir: &Path,
    err: MakeErr<'_>,
) -> Result<RunEntry, Located> {
    let string = |key: &str, ctx: &str| -> Result<(String, std::ops::Range<usize>), Located> {
        let v = t.get(key).ok_or_else(|| Err(format!("{ctx}: {key} is missing")))?;
        match v.get_ref() {
            toml::Value::String(s) => Ok((s.clone(), v.span())),
            other => Err(Ok(err(v.span(), format!("{ctx}: {key} must be a string, found {other}")))),
        }
    };
    let (id, id_span) = string("id", &format!("[[runs]] #{number_in_file}"))?;
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-') {
        return Err(Ok(err(id_span, format!("run id {id:?} must match [a-z0-9-]+"))));
    }
    let ctx = format!("run {id:?}");
    let (kind_name, kind_span) = string("kind", &ctx)?;
    let Some(spec) = KINDS.iter().find(|k| k.name == kind_name) else {
        let known = KINDS.iter().map(|k| k.name).collect::<Vec<_>>().join(", ");
        return Err(Ok(err(kind_span, format!("run {id:?}: unknown run kind {kind_name:?} (known: {known})"))));
    };
    let mut allowed = vec!["id", "kind", "file"];
    allowed.extend_from_slice(spec.metadata);
    refuse_unknown(t, &allowed, &format!("run {id:?} (kind {kind_name})"), err)?;
    let meta = |key: &str| number(t, key, &ctx, err);
    let check = |key: &str, x: f64, ok: bool, rule: &str| -> Result<f64, Located> {
        if ok { Ok(x) } else { Err(Ok(err(t[key].span(), format!("run {id:?}: {key} {rule}, found {x}")))) }
    };
    let kind = match spec.name {
        "force_calibration" => {
            let load_n = meta("load_n")?;
            RunKind::ForceCalibration { load_n: check("load_n", load_n, load_n >= 0.0, "must be >= 0 N")? }
        }
        "static_twist" => {
            let torque_nm = meta("torque_nm")?;
            RunKind::StaticTwist { torque_nm: check("torque_nm", torque_nm, torque_nm > 0.0, "must be > 0 N m")? }
        }
        "voltage_step" => {
            let v = meta("voltage_v")?;
            let supply = rig.supply_voltage_v;
            let rule = format!("must be non-zero and within +/- supply_voltage_v = {supply} V");
            RunKind::VoltageStep { voltage_v: check("voltage_v", v, v != 0.0 && v.abs() <= supply, &rule)? }
        }
        "operating_point" => {
            let rpm = meta("motor_rpm_setpoint")?;
            let normal = meta("normal_force_n")?;
            let ramp = meta("ramp_s")?;
            RunKind::OperatingPoint {
                motor_rpm_setpoint: check("motor_rpm_setpoint", rpm, rpm > 0.0, "must be > 0 rpm")?,
                normal_force_n: check("normal_force_n", normal, normal >= 0.0, "must be >= 0 N")?,
                ramp_s: check("ramp_s", ramp, ramp >= 0.0, "must be >= 0 s")?,
            }
        }
        other => unreachable!("kind {other} is in KINDS but not matched"),
    };
    let (file, file_span) = string("file", &ctx)?;
    let resolved =
        resolve_file(&file, dir, canonical_dir).map_err(|rule| Ok(err(file_span, format!("run {id:?}: {rule}"))))?;
    Ok(RunEntry { id, kind, file: PathBuf::from(file), resolved })
}

/// `file` is relative, has no `..`, exists, is a regular file, and still lies
/// inside the campaign folder once symlinks are resolved.
fn resolve_file(file: &str, dir: &Path, canonical_dir: &Path) -> Result<PathBuf, String> {
    let rel = Path::new(file);
    if file.is_empty() {
        return Err("file must not be empty".into());
    }
    if rel.has_root() || rel.is_absolute() || file.starts_with('\\') {
        return Err(format!("file {file:?} must be relative to the campaign folder, not absolute"));
    }
    if rel.components().any(|c| matches!(c, Component::ParentDir | Component::Prefix(_))) {
        return Err(format!("file {file:?} must stay inside the campaign folder (no `..`)"));
    }
    let joined = dir.join(rel);
    let canonical =
        joined.canonicalize().map_err(|e| format!("file {file:?} does not exist or cannot be opened ({e})"))?;
    if !canonical.starts_with(canonical_dir) {
        return Err(format!("file {file:?} resolves (through a symlink) outside the campaign folder"));
    }
    if !canonical.is_file() {
        return Err(format!("file {file:?} is not a regular file"));
    }
    Ok(joined)
}

/// No file the format does not describe where the reader would skip it
/// silently: every entry of `runs/` (at any depth) is a listed run's file or
/// a folder holding one, and every `.csv` file beside campaign.toml is a
/// listed run's file. Other files beside campaign.toml (a README, a
/// licence) are not recordings and are left alone: the spec's layout names
/// campaign.toml and `runs/`, and lets a run's `file` be anywhere inside the
/// folder. Entries are reported in name order, the first one refused.
fn refuse_undescribed(dir: &Path, runs: &[RunEntry]) -> Result<(), IngestError> {
    let plain = |p: &Path| p.components().filter(|c| !matches!(c, Component::CurDir)).collect::<PathBuf>();
    let listed: Vec<PathBuf> = runs.iter().map(|r| plain(&r.file)).collect();
    let rule = |rel: &Path, what: &str| {
        IngestError::rule(
            dir.join(rel),
            None,
            format!(
                "{what} the format does not describe: a campaign's recordings are the CSV files its \
                 campaign.toml lists ([[runs]] file), runs/ holds nothing else, and no run lists this one"
            ),
        )
    };
    let listing = |rel: &Path| -> Result<Vec<(PathBuf, bool)>, IngestError> {
        let abs = dir.join(rel);
        let io = |source| IngestError::Io { file: abs.clone(), rule: "cannot list the folder".into(), source };
        let mut out = Vec::new();
        for e in std::fs::read_dir(&abs).map_err(io)? {
            let e = e.map_err(io)?;
            out.push((rel.join(e.file_name()), e.file_type().map_err(io)?.is_dir()));
        }
        out.sort();
        Ok(out)
    };
    for (rel, is_dir) in listing(Path::new(""))? {
        let csv = rel.extension().is_some_and(|x| x.eq_ignore_ascii_case("csv"));
        if csv && !is_dir && !listed.contains(&rel) {
            return Err(rule(&rel, "a CSV file"));
        }
    }
    let mut stack = vec![PathBuf::from("runs")];
    if !dir.join("runs").is_dir() {
        return Ok(()); // every run's file lies elsewhere in the folder
    }
    while let Some(folder) = stack.pop() {
        for (rel, is_dir) in listing(&folder)? {
            if listed.contains(&rel) {
                continue;
            }
            if is_dir && listed.iter().any(|l| l.starts_with(&rel)) {
                stack.push(rel);
                continue;
            }
            return Err(rule(&rel, if is_dir { "a folder" } else { "a file" }));
        }
    }
    Ok(())
}

/// A finite number (TOML float or integer) under `key`.
fn number(t: &SpannedTable, key: &str, ctx: &str, err: MakeErr<'_>) -> Result<f64, Located> {
    let v = t.get(key).ok_or_else(|| Err(format!("{ctx}: {key} is missing")))?;
    let x = match v.get_ref() {
        toml::Value::Float(x) => *x,
        toml::Value::Integer(n) => *n as f64,
        other => return Err(Ok(err(v.span(), format!("{ctx}: {key} must be a number, found {other}")))),
    };
    if !x.is_finite() {
        return Err(Ok(err(v.span(), format!("{ctx}: {key} must be finite, found {x}"))));
    }
    Ok(x)
}

/// Typo protection: a key the format does not define is an error, not ignored.
fn refuse_unknown(t: &SpannedTable, allowed: &[&str], ctx: &str, err: MakeErr<'_>) -> Result<(), Located> {
    match t.iter().find(|(k, _)| !allowed.contains(&k.as_str())) {
        Some((k, v)) => Err(Ok(err(v.span(), format!("{ctx}: unknown key {k:?} (allowed: {})", allowed.join(", "))))),
        None => Ok(()),
    }
}

/// 1-based line of a byte offset.
fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].bytes().filter(|&b| b == b'\n').count() + 1
}
