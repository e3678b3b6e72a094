//! What a stage needs of a campaign (run kinds, counts, metadata), declared
//! with its registration in `stages/mod.rs` and checked by the runner once,
//! before any stage runs or anything is written under the out dir.

use rig_types::{Campaign, RunKind};
use std::collections::BTreeSet;

/// One thing a stage needs of the campaign the reader accepted: at least
/// `min_runs` runs of `kind`, among them at least `min_distinct` different
/// values of the kind's metadata (a line fit needs two different loads).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunNeed {
    /// The run kind as written in campaign.toml (`force_calibration`, ...).
    pub kind: &'static str,
    pub min_runs: usize,
    /// Different metadata values (`load_n`, `torque_nm`, `voltage_v`, the
    /// set-point and normal force of an operating point) among those runs.
    pub min_distinct: usize,
    /// What the stage does with them, for the refusal.
    pub purpose: &'static str,
}

impl RunNeed {
    /// At least `min_runs` runs of `kind`, no condition on their metadata.
    pub const fn runs(kind: &'static str, min_runs: usize, purpose: &'static str) -> Self {
        RunNeed { kind, min_runs, min_distinct: 0, purpose }
    }

    /// ... and among them at least `min_distinct` different metadata values.
    pub const fn distinct(self, min_distinct: usize) -> Self {
        RunNeed { min_distinct, ..self }
    }

    /// `None` when `campaign` meets the need, else what the stage needs
    /// ("at least 3 (purpose)"); [`unmet`] says what the campaign has.
    fn shortfall(&self, campaign: &Campaign) -> Option<String> {
        let runs: Vec<&RunKind> = campaign.runs_of(self.kind).map(|r| &r.kind).collect();
        if runs.len() < self.min_runs {
            return Some(format!("at least {} ({})", self.min_runs, self.purpose));
        }
        let distinct: BTreeSet<String> = runs.iter().map(|k| metadata(k)).collect();
        (distinct.len() < self.min_distinct).then(|| {
            format!("at least {} different {} values ({})", self.min_distinct, metadata_name(self.kind), self.purpose)
        })
    }
}

/// A run's metadata as one comparable value (the bits of its numbers).
fn metadata(kind: &RunKind) -> String {
    match kind {
        RunKind::ForceCalibration { load_n } => format!("{:x}", load_n.to_bits()),
        RunKind::StaticTwist { torque_nm } => format!("{:x}", torque_nm.to_bits()),
        RunKind::VoltageStep { voltage_v } => format!("{:x}", voltage_v.to_bits()),
        RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, .. } => {
            format!("{:x} {:x}", motor_rpm_setpoint.to_bits(), normal_force_n.to_bits())
        }
    }
}

fn metadata_name(kind: &str) -> &'static str {
    match kind {
        "force_calibration" => "load_n",
        "static_twist" => "torque_nm",
        "voltage_step" => "voltage_v",
        _ => "(motor_rpm_setpoint, normal_force_n)",
    }
}

/// What each stage needs: a pipeline.toml name -> its needs (injectable for tests).
pub type Needs = fn(&str) -> &'static [RunNeed];

/// Every unmet need of the `stages` on `campaign`, one clause per run kind
/// (what the campaign has, then each stage that needs more and what for), in
/// the order the stages are given: empty when the campaign serves them all.
pub fn unmet<'a>(needs: Needs, stages: impl IntoIterator<Item = &'a str>, campaign: &Campaign) -> Vec<String> {
    let mut by_kind: Vec<(&'static str, Vec<String>)> = Vec::new();
    for stage in stages {
        for need in needs(stage) {
            let Some(short) = need.shortfall(campaign) else { continue };
            let what = format!("stage {stage} needs {short}");
            match by_kind.iter_mut().find(|(k, _)| *k == need.kind) {
                Some((_, list)) => list.push(what),
                None => by_kind.push((need.kind, vec![what])),
            }
        }
    }
    by_kind
        .into_iter()
        .map(|(kind, list)| {
            let runs: Vec<&RunKind> = campaign.runs_of(kind).map(|r| &r.kind).collect();
            let distinct: BTreeSet<String> = runs.iter().map(|k| metadata(k)).collect();
            let has = match runs.len() {
                0 => format!("no {kind} run"),
                1 => format!("1 {kind} run"),
                n => format!("{n} {kind} runs with {} different {} values", distinct.len(), metadata_name(kind)),
            };
            format!("{has}: {}", list.join(", "))
        })
        .collect()
}
