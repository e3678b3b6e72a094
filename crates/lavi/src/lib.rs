//! The UFRJ LAVI 2018 stick-slip recording (run 175, Real et al. 2018): what
//! the 1-DOF simulation gets wrong, why, and what the fix gains on held-out
//! windows (issue 10).
//!
//! Pipeline of the study ([`run_study`]): read and repair the recording
//! ([`data`]), cut the calibration window (37–41 s, Lobo et al. 2020) and the
//! held-out windows, measure the seven [`features`] (one function for
//! measurement and simulation, 10 Hz low-pass), fit the baseline on the
//! calibration window ([`fit::derive`]), fit every candidate cause on the
//! calibration window and score it on the held-out windows with the
//! phase-insensitive misfit of [`score`], select by forward selection
//! ([`select`]), judge adequacy, and render tables, figures, `lavi.md` and
//! `lavi-diagnosis.json` ([`render`]).
//!
//! # Effect ids of this rig (the `effect` field of `lavi-diagnosis.json`)
//!
//! | id | picture | model change ([`sim`]) | parameters |
//! |---|---|---|---|
//! | `none` | the baseline explains the windows | — | — |
//! | `friction_law` | another law of the family: Coulomb (jump), Stribeck exponential or Gaussian, each with a viscous term | law refitted on the calibration window by simulation | `family` (0 Coulomb, 1 exponential, 2 Gaussian), `static_nm`, `kinetic_nm`, `stribeck_speed_rad_s`, `viscous_nm_s_rad` |
//! | `wob_normal_force` | the measured weight on bit is the contact's normal force: torque = WOB·μ(Ω) | law fitted to T·W_ref/W; W(t) drives the run | `reference_wob_n`, `mu_static`, `mu_kinetic` |
//! | `sensor_inertia` | an inertia between the torque sensor and the contact (the sensor above part of the bit): the sensor reads T_f + J_s Ω̇ | J_s (within J/10..10 J, reported at a bound) and the law fitted jointly by simulation, J, k, c re-derived by least squares on T − J_s Ω̇ for each J_s | `sensor_inertia_kgm2`, and `friction_law`'s keys |
//! | `friction_memory` | the friction follows its steady law with a lag | τ ṁ = T_ss(Ω) − m in slip | `lag_s` |
//! | `second_dof` | a second torsional degree of freedom (a mid inertia on the shaft) | J_1 between k_1 = k/s and k_2 = k/(1−s), then the law refitted by simulation as `friction_law`'s | `mid_inertia_kgm2`, `stiffness_split`, and `friction_law`'s keys |
//! | `absolute_damping` | the damping acts on the absolute bit speed (Eq. 4-7's placement), or on both it and the twist rate: J Ω̇ = k φ + c (Ω_top − Ω) − c_a Ω − T_f | J, k, c, c_a refitted by least squares on the calibration window; a damping below 0 pinned there and reported | `damping_nm_s_rad`, `absolute_damping_nm_s_rad` |
//! | `channel_delay` | the torque channel is late (or early) on the speed channels: T_m(t) = T_f(t − τ) | τ by least squares of the equation of motion over ±50 ms, J, k, c refitted with T_m(t + τ) as the contact torque, the law then refitted by simulation as `friction_law`'s; the simulated torque channel is read τ late, like the measured one, so every torque–speed feature compares one time base | `torque_delay_s`, and `friction_law`'s keys |
//! | `compliant_drive` | the top speed is not imposed: a PI speed loop on a motor inertia | J_m, K_p, K_i; set point = moving mean of the measured top speed (the law is kept: refitted by simulation it lowered the calibration misfit and raised the held-out one) | `drive_inertia_kgm2`, `kp_nm_s_rad`, `ki_nm_rad` |
//! | `motor_drive` | the top answers the bit: a motor under a speed loop whose speed responds to the string torque (the chapter's Eq. 4-6/4-7 motor row with its PI loop, [`drive`]) | J_m, K_p, K_i, T_0 identified by linear least squares on the calibration window (the top speed's response to the string torque; J_m below the chapter's motor inertia and K_i < 0 pinned, reported); reference = the measured top speed's moving mean; then the law decided on the calibration window by the joint score: the current one, or the least-squares law of the torque as the current structure reads it (the falling law, run again now that the top answers) | `drive_inertia_kgm2`, `kp_nm_s_rad`, `ki_nm_rad`, `load_nm`, `law_from_torque` (1: the least-squares law), and `friction_law`'s keys |
//! | `top_delay` | the top-speed channel is late (or early) on the bit speed: Ω_top(t) = Ω_top,m(t + τ_top), jointly with the torque channel's delay ([`top_delay`]) | τ_top over ±50 ms on the calibration window's free run of each structure's least-squares J, k, c and law (the torque delay by least squares for each τ_top), then the law refitted by simulation on that structure (like `channel_delay`'s); the better of the two on the calibration window | `top_delay_s`, `torque_delay_s`, `law_from_torque` (1: the least-squares law kept), and `friction_law`'s keys |
//! | `wob_level` | the contact's normal force is the weight on bit's slow level: torque = μ(Ω)·W̄(t), W̄ the measured WOB's centred moving mean over a span of at least a stick-slip cycle ([`wob_level`]) | the law kept, scaled by W̄(t)/W_ref, W_ref W̄'s mean over the calibration window; the span chosen on the calibration window among 0.5, 1, 2, 4 s | `wob_level_window_s`, `reference_wob_n` |
//! | `static_friction` | the stuck contact holds more than the kinetic law's zero-speed torque: a static level T(0) + ΔT_s above the Stribeck curve's start ([`static_friction`]) | ΔT_s on a grid of 1 % of T(0) up to 30 % by the calibration misfit, the law, J, k, c kept | `static_excess_nm`, `breakaway_nm` |
//! | `wob_angle` | the contact's normal force follows the bit's angle: N(θ)/N̄ = 1 + Σ_{h=1..3} (a_h cos hθ + b_h sin hθ), a face out of flat or square pushing the counter-face back per revolution ([`wob_angle`]) | a_h, b_h by linear least squares of the relative WOB on the measured bit angle's harmonics (calibration window); refused when they explain less than half its variance there; the law, J, k, c kept; in the free run θ is the simulated bit's | `wob_angle_amplitude_1..3`, `wob_angle_r2` |
//! | `unexplained` | a significant mismatch is left (adequacy below) | — | — |
//!
//! The structural candidates that change the motion (`channel_delay`,
//! `sensor_inertia`, `second_dof`) refit the law by simulation like
//! `friction_law`, so they are compared side by side on equal terms: a
//! structure is not handicapped by a least-squares law its rival gets to
//! refit (`compliant_drive` keeps its law: see its row).
//!
//! `params_stderr` in `lavi-diagnosis.json` is `null` for every parameter:
//! the candidates are fitted by simulation on one 4 s window, where no
//! covariance worth the name exists; the spread of the held-out misfits is
//! reported instead.
//!
//! # Adequacy
//!
//! The final model is adequate when its held-out misfit (RMS over the windows) is at most
//! `adequacy_threshold` (1: motion and torque level within their targets in
//! the joint RMS of [`score`], the five motion and the two torque features
//! weighing half each). Otherwise the verdict is `unexplained`, the selected
//! effects stay as a partial explanation, and the residual signature
//! ([`signature`]) says what the leftover torque follows.

pub mod data;
pub mod describe;
pub mod drive;
pub mod eom;
pub mod features;
pub mod fit;
pub mod lsq;
pub mod render;
pub mod score;
pub mod select;
pub mod signature;
pub mod sim;
pub mod static_friction;
pub mod study;
pub mod top_delay;
pub mod wob_angle;
pub mod wob_level;

pub use features::{FEATURES, FeatureOptions, Features, StickTorque, stick_torque, window_features};
pub use render::StudyOutput;
pub use study::{Study, run_study};

use serde::{Deserialize, Serialize};

/// Everything that can go wrong; each names what a person must fix.
#[derive(Debug, thiserror::Error)]
pub enum LaviError {
    #[error(transparent)]
    Ingest(#[from] rig_ingest::IngestError),
    #[error("signal processing: {0}")]
    Spectra(#[from] rig_spectra::SpectraError),
    #[error("1-DOF simulator core: {0}")]
    Model(#[from] rig_model::ModelError),
    #[error("{file}: {rule}")]
    Data { file: String, rule: String },
    #[error("pipeline.toml: stage lavi: param {key}: {rule}")]
    Params { key: &'static str, rule: String },
    #[error("{what}: {rule}")]
    Input { what: &'static str, rule: String },
    #[error("simulation diverged at sample {sample} of its span")]
    Diverged { sample: usize },
    #[error("{candidate}: {reason}")]
    Refused { candidate: &'static str, reason: String },
}

/// The candidate causes (effect ids in the crate docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Candidate {
    FrictionLaw,
    WobNormalForce,
    SensorInertia,
    FrictionMemory,
    SecondDof,
    CompliantDrive,
    AbsoluteDamping,
    ChannelDelay,
    MotorDrive,
    TopDelay,
    WobLevel,
    StaticFriction,
    WobAngle,
}

impl Candidate {
    pub const ALL: [Candidate; 13] = [
        Candidate::FrictionLaw,
        Candidate::WobNormalForce,
        Candidate::SensorInertia,
        Candidate::FrictionMemory,
        Candidate::SecondDof,
        Candidate::CompliantDrive,
        Candidate::AbsoluteDamping,
        Candidate::ChannelDelay,
        Candidate::MotorDrive,
        Candidate::TopDelay,
        Candidate::WobLevel,
        Candidate::StaticFriction,
        Candidate::WobAngle,
    ];

    pub fn id(self) -> &'static str {
        match self {
            Candidate::FrictionLaw => "friction_law",
            Candidate::WobNormalForce => "wob_normal_force",
            Candidate::SensorInertia => "sensor_inertia",
            Candidate::FrictionMemory => "friction_memory",
            Candidate::SecondDof => "second_dof",
            Candidate::CompliantDrive => "compliant_drive",
            Candidate::AbsoluteDamping => "absolute_damping",
            Candidate::ChannelDelay => "channel_delay",
            Candidate::MotorDrive => "motor_drive",
            Candidate::TopDelay => "top_delay",
            Candidate::WobLevel => "wob_level",
            Candidate::StaticFriction => "static_friction",
            Candidate::WobAngle => "wob_angle",
        }
    }
}

/// `[stage.params]` of the `lavi` stage (pipeline.toml), every key required.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyParams {
    /// The authors' calibration window (Lobo et al. 2020), s.
    pub window_start_s: f64,
    pub window_end_s: f64,
    /// Starts of the held-out windows, s.
    pub heldout_starts_s: Vec<f64>,
    pub heldout_length_s: f64,
    /// Free runs start this long before each window, from the measured state.
    pub warmup_s: f64,
    pub cutoff_hz: f64,
    pub transition_hz: f64,
    /// The top-speed dip detector's running-median window, s (counted in
    /// samples of the record by [`data::glitch_options`]).
    pub glitch_median_window_s: f64,
    pub glitch_threshold_rpm: f64,
    pub glitch_floor_rpm: f64,
    /// Added each side of a flagged run of dips, s (counted as a half window).
    pub glitch_dilate_s: f64,
    /// Bit speed above which the friction law is fitted, rpm.
    pub slip_speed_rpm: f64,
    /// Bins of the friction-vs-speed description.
    pub bins: usize,
    /// Bit speed below which a sample counts as stuck (`stick_fraction`), rpm.
    pub stick_speed_rpm: f64,
    /// Integration substeps per sample.
    pub substeps: usize,
    /// Nelder–Mead evaluations per candidate fit.
    pub fit_evaluations: usize,
    /// Moving mean of the measured top speed that the compliant drive follows, s.
    pub drive_ref_window_s: f64,
    /// pipeline.toml's `[shared.selection]`: the one engine's step rule
    /// (`rig_types::select`, the campaign diagnosis' and the slider's too).
    pub selection: rig_types::contract::SelectionRule,
    pub adequacy_threshold: f64,
    /// Start of the held-out window shown in the figures, s.
    pub figure_window_start_s: f64,
}
