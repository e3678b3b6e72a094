//! The ENS Lyon paper-on-paper spring–slider (Colas et al., Phys. Rev. E 2019):
//! what a Coulomb law gets wrong, why, and what a friction law with memory
//! gains at stiffnesses it was not calibrated on.
//!
//! [`run_study`] is the front door: read a folder in the layout
//! `runs/k<k>-v<V>.csv` (`rig_ingest::slider`), measure every run with the
//! one feature function ([`features`]), fit the Coulomb baseline and the
//! candidate models — a friction law on a set-up ([`fit`]) — on the
//! calibration stiffnesses by simulating them ([`sim`]) through the same
//! feature function, predict the held-out runs, choose the extensions by
//! forward selection on their held-out gain ([`select`], [`study`]), and
//! render `slider.md`, tables, figures and `slider-diagnosis.json`
//! ([`render`]).
//!
//! # Effect ids of this rig (`slider-diagnosis.json`)
//!
//! | id | picture | law ([`sim::Law`]) | parameters |
//! |---|---|---|---|
//! | `coulomb` | the baseline: one static and one kinetic coefficient | stick below μs, slip at μk | `mu_static`, `mu_drop` (μs − μk) |
//! | `static_ageing` | the static threshold grows with the time stuck (contacts age), the kinetic friction grows with speed | μs(t) = μs0 + β ln(1 + t/τ); μk(v) = μk0 + α ln(1 + v/v1), v1 = 100 µm/s | `mu_static0`, `ageing_beta`, `ageing_time_s`, `mu_drop`, `alpha` |
//! | `rate_state_ageing` | friction with a memory of the contact's age θ (Dieterich–Ruina) | μ = μ0 + a ln(v/v*) + b ln(v*θ/Dc), dθ/dt = 1 − vθ/Dc, v* = 100 µm/s | `mu0`, `a`, `b_minus_a`, `dc_m` |
//! | `rate_state_slip` | the same friction with Ruina's slip law: the state evolves only while sliding, symmetric after a jump in speed ([`slip`]) | μ = μ0 + a ln(v/v*) + b ln(v*θ/Dc), dθ/dt = −(vθ/Dc) ln(vθ/Dc), v* = 100 µm/s | `mu0`, `a`, `b_minus_a`, `dc_m` |
//! | `heslot_creep` | rate and state with the speed and the age cut off at small values (Heslot et al. 1994): a static threshold that ages, a steady friction weakening below B V0/A and strengthening above ([`heslot`]) | μ = μ0 + A ln(1 + v/V0) + B ln(1 + θ/θ0), dθ/dt = 1 − vθ/D0, θ0 = D0/V0 | `mu0`, `a`, `b_minus_a`, `d0_m`, `v0_m_s` |
//! | `track_threshold` | Coulomb whose threshold varies along the paper: a stiff spring follows it (creep), a soft one stick-slips over it ([`track`]) | μs(x) = μs0 + σ z(x/ℓ), μk = μs − Δμ, z smooth random of unit deviation | `mu_static0`, `mu_drop`, `track_sd`, `track_length_m` |
//! | `effective_mass` | the mass that oscillates is not the slider's weighed mass (a spring's own mass adds m_s/3), or — the same equation, the channel reading the spring's extension through the stated k — the spring is 1/r times stiffer than stated | m_eff = r m in m_eff ẍ = k (V t − x) − m g μ | `mass_ratio` |
//! | `series_compliance` | a compliance in series with the spring (force sensor, loading stage) | 1/k_eff = 1/k + 1/k_s | `series_stiffness_n_m` |
//! | `none` / `unexplained` | as in ../shared/spec/diagnosis.md | — | — |
//!
//! A model is a friction law on a set-up (`stated_setup`: the README's m and
//! k), its id `law+set-up` (`coulomb+effective_mass`); a finding names the
//! element its step added.

pub mod features;
pub mod fit;
pub mod heslot;
pub mod level;
pub mod render;
pub mod sim;
pub mod slip;
pub mod study;
pub mod track;

pub use features::{FeatureOptions, Features, Regime, RunConstants, Spread, features};
pub use render::{StudyOutput, render};
pub use study::{Study, StudyParams, run_study};

/// Everything that can go wrong; each names what a person must fix.
#[derive(Debug, thiserror::Error)]
pub enum SliderError {
    /// The folder or one of its runs was refused (file, line, rule).
    #[error(transparent)]
    Ingest(#[from] rig_ingest::IngestError),
    /// No run at any stiffness of `calibration_stiffnesses_n_m`.
    #[error("{}: calibration_stiffnesses_n_m = {listed:?}: no run of the folder has one of these stiffnesses", folder.display())]
    NoCalibration { listed: Vec<f64>, folder: std::path::PathBuf },
    /// The folds could not start a selection (`rig_types::select::SelectError`).
    #[error("slider: forward selection: {0}")]
    Selection(String),
}
