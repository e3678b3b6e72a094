//! The estimation's knobs as pipeline.toml writes them (`[stage.params]` of
//! the `estimation` stage, with `[shared.voltage_steps]`, `[shared.integrator]`
//! and `[shared.stick_episodes]`), and the one mapping onto [`EstimateOptions`]:
//! the DAG's estimation stage and the diagnosis' blind chain
//! (`rig_diagnose::BlindChain`, the confusion battery's) both estimate
//! through [`EstimateParams::options`], so they cannot run other options.

use crate::friction::FrictionOptions;
use crate::lsq::SolverOptions;
use crate::options::{EstimateOptions, InitialValues, SolverKind};
use crate::pi::PiMethod;
use crate::steps::StepResidual;
use serde::{Deserialize, Serialize};

/// pipeline.toml's estimation params; every knob is explicit there (no defaults in code).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimateParams {
    pub gear_ratio: f64,
    pub free_inductance: bool,
    /// Comma-separated voltage-step ids; empty: the estimator's own split.
    pub holdout: String,
    pub whiteness_max_lag: usize,
    pub pi_method: Pi,
    pub pi_window_s: f64,
    pub saturation_margin_v: f64,
    /// pipeline.toml's `[shared.voltage_steps]`.
    pub voltage_steps: VoltageStepFit,
    /// pipeline.toml's `[shared.stick_episodes]`.
    pub stick_episodes: FrictionOptions,
    /// pipeline.toml's `[shared.integrator]`.
    pub integrator: rig_model::SimOptions,
}

/// The voltage-step fit (Table 4.4 → 4.5, thesis §4.2) as pipeline.toml's
/// `[shared.voltage_steps]` writes it: declared once, because two stages
/// must fit the steps alike — the estimation, and the diagnosis, whose step
/// checks window the same speeds and which refits the motor side under each
/// damping candidate ([`crate::refit_motor_side`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VoltageStepFit {
    pub solver: Solver,
    pub max_iterations: usize,
    pub ftol: f64,
    pub xtol: f64,
    pub gtol: f64,
    pub fd_step: f64,
    /// Window of the step residuals' window-mean speeds, s.
    pub residual_window_s: f64,
    pub residual: Residual,
}

impl VoltageStepFit {
    /// Which least-squares solver.
    pub fn solver_kind(&self) -> SolverKind {
        match self.solver {
            Solver::Lm => SolverKind::LevenbergMarquardt,
            Solver::GaussNewtonLs => SolverKind::GaussNewtonLineSearch,
        }
    }

    /// The solver's stopping rules and difference step (the initial
    /// Marquardt damping is the solver's own).
    pub fn solver_options(&self) -> SolverOptions {
        SolverOptions {
            max_iterations: self.max_iterations,
            ftol: self.ftol,
            xtol: self.xtol,
            gtol: self.gtol,
            fd_step: self.fd_step,
            ..SolverOptions::default()
        }
    }

    /// Which residual the steps are fitted on.
    pub fn step_residual(&self) -> StepResidual {
        match self.residual {
            Residual::Angle => StepResidual::Angle,
            Residual::Speed => StepResidual::Speed,
        }
    }
}

/// `solver = "lm" | "gauss_newton_ls"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    Lm,
    GaussNewtonLs,
}

/// `residual = "speed" | "angle"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Residual {
    Speed,
    Angle,
}

/// `pi_method = "corrected_ls" | "iv"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pi {
    CorrectedLs,
    Iv,
}

impl EstimateParams {
    /// The estimator's options from these params, started from `initial`
    /// (Table 4.4, `InitialValues::from_thesis_data` in the DAG and the blind chain).
    pub fn options(&self, initial: InitialValues) -> EstimateOptions {
        let mut o = EstimateOptions::new(initial, self.integrator.clone());
        let v = &self.voltage_steps;
        o.solver_kind = v.solver_kind();
        o.solver = v.solver_options();
        o.gear_ratio = self.gear_ratio;
        o.speed_window_s = v.residual_window_s;
        o.step_residual = v.step_residual();
        o.free_inductance = self.free_inductance;
        o.holdout =
            (!self.holdout.trim().is_empty()).then(|| self.holdout.split(',').map(|s| s.trim().to_string()).collect());
        o.whiteness_max_lag = self.whiteness_max_lag;
        o.pi.method = match self.pi_method {
            Pi::CorrectedLs => PiMethod::CorrectedLs,
            Pi::Iv => PiMethod::Iv,
        };
        o.pi.window_s = self.pi_window_s;
        o.pi.saturation_margin_v = self.saturation_margin_v;
        o.friction = self.stick_episodes.clone();
        o
    }
}
