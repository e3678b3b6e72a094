//! What an estimation is told: initial values (Table 4.4), the gear ratio,
//! solver settings, which voltage steps are held out, and the settings of
//! the PI and friction estimators. Plain data; the stage fills it from
//! pipeline.toml and data/thesis.json.

use crate::EstimateError;
use crate::friction::FrictionOptions;
use crate::lsq::SolverOptions;
use crate::pi::PiOptions;
use crate::steps::StepResidual;
use rig_model::SimOptions;
use serde::{Deserialize, Serialize};

/// Table 4.4: initial values of the least-squares identification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InitialValues {
    pub motor_inertia_kgm2: f64,
    pub inductance_h: f64,
    pub resistance_ohm: f64,
    pub torque_constant_nm_a: f64,
    pub voltage_constant_v_s_rad: f64,
    pub friction_torque_nm: f64,
    pub speed_regulation_nm_s_rad: f64,
    pub rotor_inertia_kgm2: f64,
    pub shaft_stiffness_nm_rad: f64,
}

impl InitialValues {
    /// From Table 4.4 by the symbols of data/thesis/table-4-4.csv
    /// (J_m, L_DC, R_DC, k_T, k_e, T_f, C_m, J_1, K_s).
    pub fn from_table_4_4(value_of: impl Fn(&str) -> Option<f64>) -> Result<Self, EstimateError> {
        let get = |s: &str| {
            value_of(s).ok_or_else(|| EstimateError::InvalidOption {
                name: format!("Table 4.4 symbol {s}"),
                value: f64::NAN,
                rule: "data/thesis/table-4-4.csv must have a row for every motor and rotor parameter",
            })
        };
        Ok(InitialValues {
            motor_inertia_kgm2: get("J_m")?,
            inductance_h: get("L_DC")?,
            resistance_ohm: get("R_DC")?,
            torque_constant_nm_a: get("k_T")?,
            voltage_constant_v_s_rad: get("k_e")?,
            friction_torque_nm: get("T_f")?,
            speed_regulation_nm_s_rad: get("C_m")?,
            rotor_inertia_kgm2: get("J_1")?,
            shaft_stiffness_nm_rad: get("K_s")?,
        })
    }
}

impl InitialValues {
    /// From `data/thesis.json` (Table 4.4 as the thesis-tables stage wrote it).
    pub fn from_thesis_data(t: &rig_calibrate::ThesisData) -> Self {
        let m = &t.motor_initial;
        InitialValues {
            motor_inertia_kgm2: m.inertia_kgm2,
            inductance_h: m.inductance_h,
            resistance_ohm: m.resistance_ohm,
            torque_constant_nm_a: m.torque_constant_nm_a,
            voltage_constant_v_s_rad: m.voltage_constant_v_s_rad,
            friction_torque_nm: m.friction_torque_nm,
            speed_regulation_nm_s_rad: m.speed_regulation_nm_s_rad,
            rotor_inertia_kgm2: t.rotor_inertia_initial_kgm2,
            shaft_stiffness_nm_rad: t.shaft_stiffness_initial_nm_rad,
        }
    }
}

/// Where the rig model's viscous damping acts while the voltage steps are
/// fitted (issue 25). The log decrement (Eqs. 4-2/4-3) measures one number C
/// whichever placement — in the free decay the motor side is held, so the
/// twist rate and the absolute rotor speed are the same — but in steady
/// rotation the placements differ: a drag C_r on Ω1 loads the motor by C_r·Ω1
/// (C_r·Ω1/n at the armature), which a fit under [`DampingStructure::TwistRate`]
/// absorbs into k_T, k_e and T_f. A structural candidate is only compared
/// fairly when the motor constants are estimated under it.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "placement")]
pub enum DampingStructure {
    /// C on the twist rate Ω2 − Ω1, C_r = 0: the rig model's structure (default;
    /// the shipped estimate).
    #[default]
    TwistRate,
    /// C on the absolute rotor speed Ω1 only (Eq. 4-7's diag(C, C_m) as
    /// published): the twist-rate damping is 0 and the rotor drag C_r
    /// (`RigParams::rotor_damping_nm_s_rad`) takes its place.
    RotorAbsolute { rotor_damping: RotorDamping },
    /// Both: C on the twist rate (fitted, as in `TwistRate`) and a drag C_r on Ω1.
    Both { rotor_damping: RotorDamping },
}

/// How a structure's rotor drag C_r enters the voltage-step fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "how")]
pub enum RotorDamping {
    /// Estimated with the other free parameters, started at the log
    /// decrement's C = 2ξ√(J1 K) (the natural prior: in the free decay C and
    /// C_r are the same number).
    Fitted,
    /// Held at a value found elsewhere (e.g. the diagnosis' rotor
    /// torque-balance fit), N·m·s/rad; the motor constants are fitted under it.
    Held { nm_s_rad: f64 },
}

/// Which solver minimises the voltage-step misfit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolverKind {
    /// Own Levenberg–Marquardt (default; robust from far starts).
    LevenbergMarquardt,
    /// argmin's Gauss–Newton with Armijo backtracking (c = 1e-4).
    GaussNewtonLineSearch,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateOptions {
    pub initial: InitialValues,
    /// Gear ratio n (thesis §4.2: 8:1). Not identifiable from shaft-side data:
    /// any n fits equally with rescaled motor constants, so it is fixed.
    pub gear_ratio: f64,
    /// Start J1 and K_s from the campaign calibration (static twist, Eq. 4-4)
    /// instead of Table 4.4's analytical values.
    pub initial_from_calibration: bool,
    pub solver: SolverOptions,
    pub solver_kind: SolverKind,
    /// Voltage-step run ids held out for validation. `None`: estimate on the
    /// lowest and the highest voltage, hold out the ones in between
    /// (validation by interpolation); with two or fewer steps none is held out.
    pub holdout: Option<Vec<String>>,
    /// Window of the voltage-step residuals, s (angles are compared every
    /// window; speeds are means over windows), counted in samples from each
    /// run's time column ([`rig_types::sensor::window_samples`]).
    pub speed_window_s: f64,
    pub step_residual: StepResidual,
    /// Estimate the armature inductance too (default: held at Table 4.4,
    /// since L/R is about one sample interval; the report gives the
    /// correlation and standard error it would have if freed).
    pub free_inductance: bool,
    /// Integrator tolerances of the fits: pipeline.toml's `[shared.integrator]`
    /// (the estimation stage lists it), the same as every simulating stage.
    /// No default in code: [`EstimateOptions::new`] is given it.
    pub integrator: SimOptions,
    /// Lags of the residual whiteness test (in speed windows).
    pub whiteness_max_lag: usize,
    pub pi: PiOptions,
    pub friction: FrictionOptions,
    /// Where the damping acts during the voltage-step fit (default: the
    /// twist rate, the shipped estimate; absent from JSON when default).
    #[serde(default, skip_serializing_if = "is_twist_rate")]
    pub damping: DampingStructure,
}

fn is_twist_rate(d: &DampingStructure) -> bool {
    *d == DampingStructure::TwistRate
}

impl EstimateOptions {
    /// Defaults around the given Table 4.4 values, integrating with
    /// `integrator` (pipeline.toml's `[shared.integrator]`:
    /// `SimOptions::from_pipeline_toml`, or a stage's params).
    pub fn new(initial: InitialValues, integrator: SimOptions) -> Self {
        EstimateOptions {
            initial,
            gear_ratio: 8.0,
            initial_from_calibration: true,
            solver: SolverOptions::default(),
            solver_kind: SolverKind::LevenbergMarquardt,
            holdout: None,
            speed_window_s: 0.05,
            step_residual: StepResidual::Speed,
            free_inductance: false,
            integrator,
            whiteness_max_lag: 25,
            pi: PiOptions::default(),
            friction: FrictionOptions::default(),
            damping: DampingStructure::TwistRate,
        }
    }

    /// [`EstimateOptions::new`] from Table 4.4 symbols (see [`InitialValues::from_table_4_4`]).
    pub fn from_thesis_table_4_4(
        value_of: impl Fn(&str) -> Option<f64>,
        integrator: SimOptions,
    ) -> Result<Self, EstimateError> {
        Ok(Self::new(InitialValues::from_table_4_4(value_of)?, integrator))
    }
}
