//! The stage registry: pipeline.toml names -> stage bodies. One module per
//! stage family; each body is a thin call into an analysis crate.

mod campaign_cal;
mod confusion;
mod diagnosis;
mod estimation;
mod harmonic;
mod lavi;
mod report;
mod simulation;
mod spectra;
mod sweeps;
mod thesis;

use crate::StageFn;

/// Every stage: its pipeline.toml name, its body, and the file holding the
/// body (relative to the workspace root; the runner computes the stage's code
/// from it, see `code.rs`). One line per stage.
const STAGES: &[(&str, StageFn, &str)] = &[
    ("thesis-tables", thesis::run, "crates/pipeline/src/stages/thesis.rs"),
    ("campaign-calibration", campaign_cal::run, "crates/pipeline/src/stages/campaign_cal.rs"),
    ("estimation", estimation::run, "crates/pipeline/src/stages/estimation.rs"),
    ("simulation", simulation::run, "crates/pipeline/src/stages/simulation.rs"),
    ("sweeps", sweeps::run, "crates/pipeline/src/stages/sweeps.rs"),
    ("spectra", spectra::run, "crates/pipeline/src/stages/spectra.rs"),
    ("harmonic", harmonic::run, "crates/pipeline/src/stages/harmonic.rs"),
    ("diagnosis", diagnosis::run, "crates/pipeline/src/stages/diagnosis.rs"),
    ("lavi", lavi::run, "crates/pipeline/src/stages/lavi.rs"),
    ("confusion", confusion::run, "crates/pipeline/src/stages/confusion.rs"),
    ("report", report::run, "crates/pipeline/src/stages/report.rs"),
];

/// The body of the stage called `name` in pipeline.toml.
pub fn lookup(name: &str) -> Option<StageFn> {
    STAGES.iter().find(|s| s.0 == name).map(|s| s.1)
}

/// The file holding the body of the stage called `name`, relative to the workspace root.
pub fn source(name: &str) -> Option<&'static str> {
    STAGES.iter().find(|s| s.0 == name).map(|s| s.2)
}

/// The names of every registered stage, in registry order.
pub fn names() -> Vec<&'static str> {
    STAGES.iter().map(|s| s.0).collect()
}

/// The thesis model as published (Table 4.5, the chapter's printed ξ — its C —,
/// Table 4.7, r; see `rig_model::thesis_model_params`) with `drive`: the chapter
/// publishes no PI gains, so stages pass the rig's identified drive.
pub(crate) fn thesis_model(data: &rig_calibrate::ThesisData, drive: rig_types::DriveParams) -> rig_types::RigParams {
    rig_model::thesis_model_params(&rig_model::ThesisModelInputs {
        motor: data.motor_estimated.clone(),
        rotor_inertia_kgm2: data.rotor_inertia_kgm2,
        shaft_stiffness_nm_rad: data.shaft_stiffness_nm_rad,
        damping_ratio: data.damping_ratio,
        friction: data.friction.clone(),
        brake_disc_radius_m: data.brake_disc_radius_m,
        drive,
    })
}
