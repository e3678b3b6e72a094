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

/// The body of the stage called `name` in pipeline.toml.
pub fn lookup(name: &str) -> Option<StageFn> {
    Some(match name {
        "thesis-tables" => thesis::run,
        "campaign-calibration" => campaign_cal::run,
        "estimation" => estimation::run,
        "simulation" => simulation::run,
        "sweeps" => sweeps::run,
        "spectra" => spectra::run,
        "harmonic" => harmonic::run,
        "diagnosis" => diagnosis::run,
        "lavi" => lavi::run,
        "confusion" => confusion::run,
        "report" => report::run,
        _ => return None,
    })
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
