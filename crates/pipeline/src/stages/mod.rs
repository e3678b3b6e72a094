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
