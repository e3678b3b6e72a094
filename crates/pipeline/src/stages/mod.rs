//! The stage registry: pipeline.toml names -> stage bodies, each a thin call into an analysis crate.

mod campaign_cal;
mod confusion;
mod diagnosis;
mod estimation;
mod harmonic;
mod lavi;
mod report;
mod simulation;
mod slider;
mod spectra;
mod sweeps;
mod thesis;

use crate::StageFn;
use crate::needs::RunNeed;

/// Checks a stage's `[stage.params]` against its params type; `Err` is a
/// reason naming the key (the runner adds file and stage).
type TypedCheck = fn(&toml::Table) -> Result<(), String>;

/// One registered stage.
struct Entry {
    /// Its name in pipeline.toml.
    name: &'static str,
    run: StageFn,
    /// The file holding the body, relative to the workspace root: the runner
    /// computes the stage's code from it (see `code.rs`).
    source: &'static str,
    /// Its `[stage.params]` type: `Some(typed::<T>)`, checked for every
    /// stage before any stage runs. `None` only for stages not converted yet
    /// (tidy.rs lists them; their bodies check their own params when they run).
    params: Option<TypedCheck>,
    /// What it needs of the campaign, checked by the runner before any stage
    /// runs (`crate::needs`); the counts are the ones its crate refuses below.
    needs: &'static [RunNeed],
}

/// `params` deserialise as `T` (a `#[serde(deny_unknown_fields)]` struct).
fn typed<T: serde::de::DeserializeOwned>(params: &toml::Table) -> Result<(), String> {
    crate::ctx::parse_params::<T>(params).map(|_| ())
}

/// Every stage, one line each, with what it needs of the campaign (`.needs`).
const STAGES: &[Entry] = &[
    entry("thesis-tables", thesis::run, "thesis.rs", Some(typed::<thesis::Params>)),
    entry("campaign-calibration", campaign_cal::run, "campaign_cal.rs", Some(typed::<campaign_cal::Params>))
        .needs(CALIBRATION_NEEDS),
    entry("estimation", estimation::run, "estimation.rs", Some(typed::<estimation::Params>)).needs(ESTIMATION_NEEDS),
    entry("simulation", simulation::run, "simulation.rs", Some(typed::<simulation::Params>)),
    entry("sweeps", sweeps::run, "sweeps.rs", Some(typed::<sweeps::Params>)),
    entry("spectra", spectra::run, "spectra.rs", Some(typed::<spectra::Params>)),
    entry("harmonic", harmonic::run, "harmonic.rs", Some(typed::<harmonic::Params>)),
    entry("diagnosis", diagnosis::run, "diagnosis.rs", Some(typed::<rig_diagnose::DiagnoseOptions>))
        .needs(DIAGNOSIS_NEEDS),
    entry("lavi", lavi::run, "lavi.rs", Some(typed::<rig_lavi::StudyParams>)),
    entry("slider", slider::run, "slider.rs", Some(typed::<rig_slider::StudyParams>)),
    entry("confusion", confusion::run, "confusion.rs", Some(typed::<confusion::ConfusionParams>)),
    entry("report", report::run, "report.rs", Some(typed::<report::Params>)),
];

/// `rig_calibrate::calibrate_campaign_with` refuses fewer than 3 force
/// calibrations and 2 static twists, and needs one voltage step's free decay.
const CALIBRATION_NEEDS: &[RunNeed] = &[
    RunNeed::runs("force_calibration", 3, "the force-sensor line of Table 4.6 with its interval").distinct(2),
    RunNeed::runs("static_twist", 2, "the static stiffness of Table 4.3"),
    RunNeed::runs("voltage_step", 1, "the free decay of Table 4.2 and the inertia of Eq. 4-4"),
];

/// `rig_estimate::estimate_rig` fits the voltage steps (Tables 4.4-4.5) and
/// takes the PI gains and Coulomb friction from the operating points.
const ESTIMATION_NEEDS: &[RunNeed] = &[
    RunNeed::runs("voltage_step", 1, "the least-squares fit of Tables 4.4-4.5"),
    RunNeed::runs("operating_point", 1, "the PI gains and the Coulomb friction"),
];

/// `rig_diagnose::select::diagnose_signals` cross-validates over at least 3 operating points.
const DIAGNOSIS_NEEDS: &[RunNeed] = &[RunNeed::runs("operating_point", 3, "cross-validation over runs")];

const fn entry(name: &'static str, run: StageFn, file: &'static str, params: Option<TypedCheck>) -> Entry {
    Entry { name, run, source: file, params, needs: &[] }
}

impl Entry {
    const fn needs(self, needs: &'static [RunNeed]) -> Entry {
        Entry { needs, ..self }
    }
}

/// This folder, relative to the workspace root (`source` adds it to each entry's file).
const STAGES_DIR: &str = "crates/pipeline/src/stages";

fn find(name: &str) -> Option<&'static Entry> {
    STAGES.iter().find(|s| s.name == name)
}

/// The body of the stage called `name` in pipeline.toml.
pub fn lookup(name: &str) -> Option<StageFn> {
    find(name).map(|s| s.run)
}

/// The file holding the body of the stage called `name`, relative to the workspace root.
pub fn source(name: &str) -> Option<&'static str> {
    static PATHS: std::sync::OnceLock<Vec<(&'static str, String)>> = std::sync::OnceLock::new();
    let paths = PATHS.get_or_init(|| STAGES.iter().map(|s| (s.name, format!("{STAGES_DIR}/{}", s.source))).collect());
    paths.iter().find(|(n, _)| *n == name).map(|(_, p)| p.as_str())
}

/// Checks `params` against the params type of the stage called `name`
/// (Ok for a stage with no registered type).
pub fn check_params(name: &str, params: &toml::Table) -> Result<(), String> {
    match find(name).and_then(|s| s.params) {
        Some(check) => check(params),
        None => Ok(()),
    }
}

/// What the stage called `name` needs of the campaign (nothing for an unknown name).
pub fn needs(name: &str) -> &'static [RunNeed] {
    find(name).map(|s| s.needs).unwrap_or(&[])
}

/// The names of every registered stage, in registry order.
pub fn names() -> Vec<&'static str> {
    STAGES.iter().map(|s| s.name).collect()
}

/// The registered stages whose params are not typed yet.
pub fn untyped() -> Vec<&'static str> {
    STAGES.iter().filter(|s| s.params.is_none()).map(|s| s.name).collect()
}

/// The thesis model as published (Table 4.5, the chapter's printed ξ — its C —,
/// Table 4.7, r; see `rig_model::thesis_model_params`) with `drive`: the chapter
/// publishes no PI gains, so stages pass the rig's identified drive.
pub(crate) fn thesis_model(
    data: &rig_types::contract::ThesisData,
    drive: rig_types::DriveParams,
) -> rig_types::RigParams {
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
