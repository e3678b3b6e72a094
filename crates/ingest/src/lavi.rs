//! The real stick-slip recording of the UFRJ/LAVI drill-string test rig
//! (../shared/data/ufrj-lavi-2018/run-175.csv, Real et al. 2018) as plain columns.
//!
//! Validated like a campaign run (header with exactly these columns in any
//! order, every row as many cells as the header — a trailing empty cell is
//! refused —, every cell a finite number, `time_s` strictly increasing) but
//! the recording need not start at t = 0. The reader opens the one file it is
//! given, so no other file of its folder can be skipped unseen. The top speed's dips (to about
//! -263 rpm, about 10 ms each) are finite numbers and are kept: they carry
//! angle (the twist integrated from the raw top and bit speeds stays within
//! about ±0.5 rad, README of the data), and any repair is the analysis' job,
//! audited there by what it changes in the twist (rig_lavi::data).

use crate::IngestError;
use crate::columns::{ColSpec, ColType, ColValues, TIME_COLUMN, TimeStart, read_numeric_csv};
use std::path::Path;

/// One LAVI recording; every column has `time_s.len()` entries.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaviRecording {
    /// Sample times, strictly increasing (1 kHz in run 175).
    pub time_s: Vec<f64>,
    /// Drive-side (top) speed, rpm, as recorded (dips included).
    pub top_speed_rpm: Vec<f64>,
    /// Bottom-rotor (bit) speed, rpm.
    pub bit_speed_rpm: Vec<f64>,
    /// Torque on bit (the friction torque at the bottom), N m.
    pub bit_torque_nm: Vec<f64>,
    /// Weight on bit (normal force of the bit-rock contact), N.
    pub wob_n: Vec<f64>,
}

impl LaviRecording {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when there are no samples (never for a recording from [`read_lavi`]).
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }
}

const COLUMNS: &[ColSpec] = &[
    ColSpec { name: TIME_COLUMN, ty: ColType::Float },
    ColSpec { name: "top_speed_rpm", ty: ColType::Float },
    ColSpec { name: "bit_speed_rpm", ty: ColType::Float },
    ColSpec { name: "bit_torque_nm", ty: ColType::Float },
    ColSpec { name: "wob_n", ty: ColType::Float },
];

/// Reads a LAVI CSV (`time_s, top_speed_rpm, bit_speed_rpm, bit_torque_nm, wob_n`).
pub fn read_lavi(path: &Path) -> Result<LaviRecording, IngestError> {
    let mut cols = read_numeric_csv(path, COLUMNS, TimeStart::Any)?.into_iter().map(|c| match c {
        ColValues::Float(v) => v,
        ColValues::Count(_) => unreachable!("LAVI columns are all Float"),
    });
    let mut next = || cols.next().expect("one value vector per column");
    Ok(LaviRecording {
        time_s: next(),
        top_speed_rpm: next(),
        bit_speed_rpm: next(),
        bit_torque_nm: next(),
        wob_n: next(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "time_s,top_speed_rpm,bit_speed_rpm,bit_torque_nm,wob_n\n";

    fn read(rows: &str) -> Result<LaviRecording, IngestError> {
        let d = tempfile::tempdir().unwrap();
        let path = d.path().join("run.csv");
        std::fs::write(&path, format!("{HEADER}{rows}")).unwrap();
        read_lavi(&path)
    }

    #[test]
    fn reads_a_recording_that_starts_anywhere() {
        let r = read("12.000,60.0,0.0,1.5,900\n12.001,-263.0,0.1,1.6,901\n").unwrap();
        assert_eq!(r.time_s, vec![12.0, 12.001]);
        assert_eq!(r.top_speed_rpm, vec![60.0, -263.0]);
    }

    #[test]
    fn a_trailing_empty_cell_names_file_line_and_rule() {
        let e = read("12.000,60.0,0.0,1.5,900\n12.001,61.0,0.1,1.6,901,\n").unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(e.to_string().ends_with("run.csv:3: row has 6 cells but the header has 5"), "{e}");
    }
}
