//! Least-squares identification on the rig model (argmin, faer) with covariance and a fit report.
//!
//! Front door: [`estimate_rig`] (voltage steps → motor/string parameters,
//! operating points → PI gains and Coulomb friction) returning a
//! [`RigEstimate`] with its [`FitReport`]. The pieces are public for tests
//! and for the diagnosis: [`lsq`] (the solver core), [`report`], [`pi`],
//! [`friction`], [`steps`].

pub mod argmin_adapter;
mod error;
pub mod fit_stats;
pub mod friction;
pub mod linear;
pub mod lsq;
mod options;
pub mod params;
pub mod pi;
pub mod render;
mod rig;
pub mod signals;
pub mod steps;

pub use error::EstimateError;
pub use fit_stats::{FitReport, Identifiability, ParamEstimate};
pub use friction::{FrictionEstimate, FrictionOptions, estimate_friction};
pub use lsq::{
    IterationRecord, LsqMinimum, LsqProblem, LsqSolution, SolverOptions, Transform, levenberg_marquardt,
    levenberg_marquardt_minimum,
};
pub use options::{DampingStructure, EstimateOptions, InitialValues, RotorDamping, SolverKind};
pub use params::{EstimateParams, VoltageStepFit};
pub use pi::{PiEstimate, PiMethod, PiOptions, estimate_pi};
pub use rig::{MOTOR_SIDE, ModeComparison, MotorRefit, RigEstimate, StepFit, estimate_rig, refit_motor_side};
pub use steps::StepResidual;
