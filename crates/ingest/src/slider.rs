//! Spring–slider recordings in the layout of `../shared/data/ens-lyon-slider-2019/`
//! (Colas et al., Phys. Rev. E 2019): a folder with `runs/k<k>-v<V>.csv`.
//!
//! Rules, checked in this order, the first broken one reported with file,
//! line and rule:
//! - the folder has a `runs/` subfolder holding at least one `.csv` file and
//!   nothing else (no other file, no folder: a run the reader would skip is
//!   refused, not ignored; files beside `runs/`, a README or a licence, are
//!   left alone);
//! - every `.csv` file in `runs/` is named `k<k>-v<V>.csv`, `k` the spring
//!   stiffness in N/m and `V` the driving speed in µm/s, both positive
//!   numbers (`k168-v42.csv`); a (k, V) pair appears once;
//! - each CSV: the header names exactly `time_s` and `force_over_weight`
//!   (any order), every cell a finite number, `time_s` strictly increasing
//!   (it need not start at 0: the acquisition clock), every row as many
//!   cells as the header (no trailing empty cell), at least 2 rows (the rules
//!   of [`crate::lavi`]'s reader, the same CSV code).
//!
//! Force spikes (impulsive noise, occasionally below zero) are finite
//! numbers and are kept: denoising is the analysis' job.

use crate::IngestError;
use crate::columns::{ColSpec, ColType, ColValues, TIME_COLUMN, TimeStart, read_numeric_csv};
use std::path::Path;

/// One run of the slider: spring force over weight against time.
#[derive(Debug, Clone, PartialEq)]
pub struct SliderRun {
    /// File stem, `k<k>-v<V>`.
    pub name: String,
    /// Spring stiffness k, N/m (from the file name).
    pub stiffness_n_m: f64,
    /// Driving speed V, µm/s (from the file name).
    pub drive_speed_um_s: f64,
    /// Sample times, s, strictly increasing.
    pub time_s: Vec<f64>,
    /// Spring force divided by the slider's weight, F/(m g).
    pub force_over_weight: Vec<f64>,
}

const COLUMNS: &[ColSpec] =
    &[ColSpec { name: TIME_COLUMN, ty: ColType::Float }, ColSpec { name: "force_over_weight", ty: ColType::Float }];

/// Parses `k<k>-v<V>` into (k N/m, V µm/s); `None` when the stem does not fit.
pub fn parse_run_name(stem: &str) -> Option<(f64, f64)> {
    let rest = stem.strip_prefix('k')?;
    let (k, v) = rest.split_once("-v")?;
    let num = |s: &str| {
        let ok = !s.is_empty() && s.chars().all(|c| c.is_ascii_digit() || c == '.');
        ok.then(|| s.parse::<f64>().ok()).flatten().filter(|x| x.is_finite() && *x > 0.0)
    };
    Some((num(k)?, num(v)?))
}

/// Reads every run of a slider folder, sorted by (k, V).
pub fn read_slider_folder(dir: &Path) -> Result<Vec<SliderRun>, IngestError> {
    let runs_dir = dir.join("runs");
    let entries = std::fs::read_dir(&runs_dir).map_err(|source| IngestError::Io {
        file: runs_dir.clone(),
        rule: "a slider folder must hold a runs/ subfolder".into(),
        source,
    })?;
    let (mut files, mut others) = (Vec::new(), Vec::new());
    for e in entries {
        let e = e.map_err(|source| IngestError::Io { file: runs_dir.clone(), rule: "listing runs/".into(), source })?;
        let path = e.path();
        let is_dir = e.file_type().map_err(|source| IngestError::Io {
            file: path.clone(),
            rule: "listing runs/".into(),
            source,
        })?;
        if is_dir.is_dir() || path.extension().and_then(|x| x.to_str()) != Some("csv") {
            others.push(path);
        } else {
            files.push(path);
        }
    }
    others.sort();
    if let Some(other) = others.first() {
        return Err(IngestError::rule(
            other,
            None,
            "a file the layout does not describe: runs/ holds only the runs, k<k>-v<V>.csv (k in N/m, V in µm/s)",
        ));
    }
    files.sort();
    if files.is_empty() {
        return Err(IngestError::rule(
            &runs_dir,
            None,
            "no runs: expected files named k<k>-v<V>.csv (k in N/m, V in µm/s)",
        ));
    }
    let mut runs: Vec<SliderRun> = Vec::with_capacity(files.len());
    for path in files {
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
        let Some((k, v)) = parse_run_name(&stem) else {
            return Err(IngestError::rule(
                &path,
                None,
                "file name must be k<k>-v<V>.csv with k (N/m) and V (µm/s) positive numbers, e.g. k168-v42.csv",
            ));
        };
        if let Some(twin) = runs.iter().find(|r| r.stiffness_n_m == k && r.drive_speed_um_s == v) {
            return Err(IngestError::rule(
                &path,
                None,
                format!("(k, V) = ({k} N/m, {v} µm/s) already given by {}.csv", twin.name),
            ));
        }
        let mut cols = read_numeric_csv(&path, COLUMNS, TimeStart::Any)?.into_iter().map(|c| match c {
            ColValues::Float(v) => v,
            ColValues::Count(_) => unreachable!("slider columns are all Float"),
        });
        let time_s = cols.next().expect("time column");
        let force_over_weight = cols.next().expect("force column");
        if time_s.len() < 2 {
            return Err(IngestError::rule(&path, Some(2), "a run needs at least 2 samples"));
        }
        runs.push(SliderRun { name: stem, stiffness_n_m: k, drive_speed_um_s: v, time_s, force_over_weight });
    }
    runs.sort_by(|a, b| {
        a.stiffness_n_m.total_cmp(&b.stiffness_n_m).then(a.drive_speed_um_s.total_cmp(&b.drive_speed_um_s))
    });
    Ok(runs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir(d.path().join("runs")).unwrap();
        for (name, text) in files {
            std::fs::write(d.path().join("runs").join(name), text).unwrap();
        }
        d
    }

    /// Reads a folder that must be refused; returns (file name, line, message).
    fn refuse(files: &[(&str, &str)]) -> (String, Option<usize>, String) {
        let d = folder(files);
        let e = read_slider_folder(d.path()).unwrap_err();
        (e.file().file_name().unwrap().to_string_lossy().into_owned(), e.line(), e.to_string())
    }

    const GOOD: &str = "time_s,force_over_weight\n3.5,0.30\n3.5005,0.31\n3.501,-0.02\n";

    #[test]
    fn reads_names_and_sorts() {
        let d = folder(&[("k2254-v42.csv", GOOD), ("k168-v4300.csv", GOOD), ("k168-v42.csv", GOOD)]);
        let runs = read_slider_folder(d.path()).unwrap();
        let keys: Vec<_> = runs.iter().map(|r| (r.stiffness_n_m, r.drive_speed_um_s)).collect();
        assert_eq!(keys, vec![(168.0, 42.0), (168.0, 4300.0), (2254.0, 42.0)]);
        assert_eq!(runs[0].force_over_weight, vec![0.30, 0.31, -0.02]);
        assert_eq!(runs[0].time_s[0], 3.5);
    }

    #[test]
    fn bad_files_name_file_line_and_rule() {
        let (f, l, m) = refuse(&[("k168-v42.csv", GOOD), ("slider-3.csv", GOOD)]);
        assert_eq!((f.as_str(), l), ("slider-3.csv", None));
        assert!(m.contains("k<k>-v<V>.csv"), "{m}");

        let (f, l, m) = refuse(&[("k168-v42.csv", "time_s,force_over_weight\n1.0,0.3\n0.9,0.3\n")]);
        assert_eq!((f.as_str(), l), ("k168-v42.csv", Some(3)));
        assert!(m.contains("strictly increasing"), "{m}");

        let (f, l, m) = refuse(&[("k168-v42.csv", "time_s,force_over_weight\n1.0,0.3\n1.1,abc\n")]);
        assert_eq!((f.as_str(), l), ("k168-v42.csv", Some(3)));
        assert!(m.contains("force_over_weight"), "{m}");

        let (f, _, m) = refuse(&[("k168-v42.csv", "time_s,force\n1.0,0.3\n")]);
        assert_eq!(f, "k168-v42.csv");
        assert!(m.contains("force_over_weight"), "{m}");

        let (f, l, m) = refuse(&[("k0-v42.csv", GOOD)]);
        assert_eq!((f.as_str(), l), ("k0-v42.csv", None));
        assert!(m.contains("positive"), "{m}");

        let (f, l, m) = refuse(&[("k168-v42.csv", "time_s,force_over_weight\n1.0,0.3\n")]);
        assert_eq!((f.as_str(), l), ("k168-v42.csv", Some(2)));
        assert!(m.contains("at least 2"), "{m}");
    }

    #[test]
    fn a_file_the_layout_does_not_describe_is_refused() {
        let (f, l, m) = refuse(&[("k168-v42.csv", GOOD), ("notes.txt", "a note")]);
        assert_eq!((f.as_str(), l), ("notes.txt", None));
        assert!(m.contains("runs/ holds only the runs"), "{m}");

        let d = folder(&[("k168-v42.csv", GOOD)]);
        std::fs::create_dir(d.path().join("runs/old")).unwrap();
        let e = read_slider_folder(d.path()).unwrap_err();
        assert_eq!((e.file().file_name().unwrap().to_str(), e.line()), (Some("old"), None));

        // Beside runs/, a README is documentation, not a run: left alone.
        let d = folder(&[("k168-v42.csv", GOOD)]);
        std::fs::write(d.path().join("README.md"), "# a slider").unwrap();
        assert_eq!(read_slider_folder(d.path()).unwrap().len(), 1);
    }

    #[test]
    fn a_trailing_empty_cell_is_refused() {
        let (f, l, m) = refuse(&[("k168-v42.csv", "time_s,force_over_weight\n1.0,0.3\n1.1,0.3,\n")]);
        assert_eq!((f.as_str(), l), ("k168-v42.csv", Some(3)));
        assert!(m.contains("row has 3 cells but the header has 2"), "{m}");
    }

    #[test]
    fn folder_without_runs_is_refused() {
        let d = tempfile::tempdir().unwrap();
        let e = read_slider_folder(d.path()).unwrap_err();
        assert!(e.to_string().contains("runs/"), "{e}");
        let d = folder(&[]);
        let e = read_slider_folder(d.path()).unwrap_err();
        assert!(e.to_string().contains("no runs"), "{e}");
    }
}
