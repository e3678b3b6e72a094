//! Least-squares identification on the rig model (argmin, faer) with covariance and a fit report.
//!
//! Front door: [`estimate_rig`] (voltage steps → motor/shaft parameters,
//! operating points → PI gains and Coulomb friction) returning a
//! [`RigEstimate`] with its [`FitReport`]. The pieces are public for tests
//! and for the diagnosis: [`lsq`] (the solver core), [`report`], [`pi`],
//! [`friction`].

pub mod argmin_adapter;
mod error;
pub mod friction;
pub mod linreg;
pub mod lsq;
pub mod pi;
pub mod report;
pub mod signals;

pub use error::EstimateError;
pub use friction::{FrictionEstimate, FrictionOptions, estimate_friction};
pub use lsq::{IterationRecord, LsqProblem, LsqSolution, SolverOptions, Transform, levenberg_marquardt};
pub use pi::{PiEstimate, PiOptions, estimate_pi};
pub use report::{FitReport, Identifiability, ParamEstimate};
