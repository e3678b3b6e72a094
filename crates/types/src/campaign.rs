//! A measuring campaign in the `rig-campaign/1` format (../shared/spec/recording-format.md),
//! already validated by `rig-ingest`.

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// What the experimenter knows before measuring (`[rig]` of campaign.toml).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigInfo {
    pub encoder_ticks_per_rev: u32,
    pub brake_disc_radius_m: f64,
    pub supply_voltage_v: f64,
    pub sample_rate_hz: f64,
}

/// The kind of a run with its kind-specific metadata.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RunKind {
    ForceCalibration { load_n: f64 },
    StaticTwist { torque_nm: f64 },
    VoltageStep { voltage_v: f64 },
    OperatingPoint { motor_rpm_setpoint: f64, normal_force_n: f64, ramp_s: f64 },
}

impl RunKind {
    /// The kind's name as written in campaign.toml.
    pub fn name(&self) -> &'static str {
        match self {
            RunKind::ForceCalibration { .. } => "force_calibration",
            RunKind::StaticTwist { .. } => "static_twist",
            RunKind::VoltageStep { .. } => "voltage_step",
            RunKind::OperatingPoint { .. } => "operating_point",
        }
    }
}

/// The columns of one run's CSV. A column the kind does not have is `None`;
/// `rig-ingest` guarantees the present ones have `time_s.len()` entries.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunData {
    pub time_s: Vec<f64>,
    pub motor_voltage_v: Option<Vec<f64>>,
    /// Cumulative motor-side encoder counts, zero at t = 0.
    pub motor_ticks: Option<Vec<i64>>,
    /// Cumulative rotor-1 encoder counts, zero at t = 0.
    pub rotor_ticks: Option<Vec<i64>>,
    /// Raw force-sensor voltage (tangential force on the pads), mV.
    pub brake_force_mv: Option<Vec<f64>>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Run {
    pub id: String,
    pub kind: RunKind,
    /// Path relative to the campaign folder, as written in campaign.toml.
    pub file: PathBuf,
    pub data: RunData,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Campaign {
    pub name: String,
    pub description: String,
    pub rig: RigInfo,
    pub runs: Vec<Run>,
}

impl Campaign {
    /// Runs of one kind, in campaign.toml order.
    pub fn runs_of<'a>(&'a self, kind_name: &'a str) -> impl Iterator<Item = &'a Run> + 'a {
        self.runs.iter().filter(move |r| r.kind.name() == kind_name)
    }

    /// The sample rate of the runs of one kind as their time columns
    /// measure it, Hz ([`crate::sensor::clock_rate_hz`]: `sample_rate_hz`
    /// itself unless the columns disagree with it beyond
    /// [`crate::sensor::CLOCK_TOLERANCE`]). What a derivative over samples,
    /// or a window counted in samples for the whole campaign, divides by.
    pub fn clock_rate_hz(&self, kind_name: &str) -> f64 {
        let records: Vec<&[f64]> = self.runs_of(kind_name).map(|r| r.data.time_s.as_slice()).collect();
        crate::sensor::clock_rate_hz(&records, self.rig.sample_rate_hz)
    }
}
