//! The front door [`estimate_rig`]: voltage steps → motor and string
//! parameters with the full fit report; operating points → PI gains and the
//! baseline Coulomb friction; all assembled into a `RigParams` (kind Rig).
//! Blind: reads only the campaign and its calibration.

use crate::EstimateError;
use crate::argmin_adapter::gauss_newton_ls;
use crate::fit_stats::{
    ChannelFit, FitReport, Identifiability, ParamEstimate, RunFit, aic_bic, covariance, fit_percent, flagged_pairs,
    nrmse, whiteness,
};
use crate::friction::{FrictionEstimate, estimate_friction};
use crate::lsq::{LsqSolution, Transform, fd_jacobian, levenberg_marquardt};
use crate::options::{DampingStructure, EstimateOptions, RotorDamping, SolverKind};
use crate::pi::{PiEstimate, estimate_pi};
use crate::steps::{
    FREE, HELD, StepData, StepProblem, coupled_mode, get_param, scales_with_torque, simulate_step, split, step_data,
    unit_of,
};
use rayon::prelude::*;
use rig_calibrate::CampaignCalibration;
use rig_model::SimOptions;
use rig_types::{Campaign, DriveParams, FrictionLaw, ModelKind, MotorParams, RigParams};
use serde::{Deserialize, Serialize};

/// Measured and simulated window speeds of one voltage step (Fig. 4.11).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepFit {
    pub run: String,
    pub used: bool,
    pub voltage_v: f64,
    pub time_s: Vec<f64>,
    pub motor_speed_meas_rad_s: Vec<f64>,
    pub motor_speed_sim_rad_s: Vec<f64>,
    pub rotor_speed_meas_rad_s: Vec<f64>,
    pub rotor_speed_sim_rad_s: Vec<f64>,
}

/// Damping and frequency of the fitted model against the log decrement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeComparison {
    /// Coupled mode of the fitted 2-DOF model (motor side free, damped by the drive).
    pub coupled_natural_rad_s: Option<f64>,
    pub coupled_damping_ratio: Option<f64>,
    /// Motor side held fixed: ω = √(K/J1), ξ = (C + C_r)/(2√(J1 K)) (the chapter's 1-DOF reading, Eq. 4-4;
    /// with the motor side held both dampings act on Ω1).
    pub fixed_base_natural_rad_s: f64,
    pub fixed_base_damping_ratio: f64,
    /// Log decrement of the same steps (campaign calibration, Eqs. 4-2/4-3).
    pub log_decrement_natural_rad_s: f64,
    pub log_decrement_natural_rad_s_stderr: f64,
    pub log_decrement_damping_ratio: f64,
    pub log_decrement_damping_ratio_stderr: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigEstimate {
    pub params: RigParams,
    pub report: FitReport,
    pub pi: PiEstimate,
    pub friction: FrictionEstimate,
    pub steps: Vec<StepFit>,
    pub modes: ModeComparison,
    /// Table 4.4 values as given (for the table's first column).
    pub table_4_4: Vec<(String, Option<f64>)>,
}

fn sim_options(o: &EstimateOptions) -> SimOptions {
    o.integrator.clone()
}

/// The starting `RigParams`: Table 4.4 motor, J1/K from the calibration,
/// C = 2ξ√(J1 K) with the log-decrement ξ (Eq. 4-7's definition).
fn initial_params(c: &Campaign, cal: &CampaignCalibration, o: &EstimateOptions) -> Result<RigParams, EstimateError> {
    let i = &o.initial;
    // The calibration's values when asked and usable (finite, > 0), else Table 4.4's.
    let usable = |v: f64| v.is_finite() && v > 0.0;
    let pick = |cal_v: f64, table_v: f64| if o.initial_from_calibration && usable(cal_v) { cal_v } else { table_v };
    let (j1, k) =
        (pick(cal.rotor_inertia_kgm2, i.rotor_inertia_kgm2), pick(cal.stiffness_nm_rad, i.shaft_stiffness_nm_rad));
    for (name, v) in [("J1 initial", j1), ("K_s initial", k), ("gear_ratio", o.gear_ratio)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(EstimateError::InvalidOption { name: name.into(), value: v, rule: "must be finite and > 0" });
        }
    }
    let xi = if cal.damping_ratio.is_finite() && cal.damping_ratio > 0.0 { cal.damping_ratio } else { 0.05 };
    let c_decay = 2.0 * xi * (j1 * k).sqrt();
    let (c_twist, c_rotor) = initial_damping(c_decay, &o.damping)?;
    Ok(RigParams {
        kind: ModelKind::Rig,
        rotor_inertia_kgm2: j1,
        shaft_stiffness_nm_rad: k,
        shaft_damping_nm_s_rad: c_twist,
        rotor_damping_nm_s_rad: c_rotor,
        motor: MotorParams {
            inertia_kgm2: i.motor_inertia_kgm2,
            inductance_h: i.inductance_h,
            resistance_ohm: i.resistance_ohm,
            torque_constant_nm_a: i.torque_constant_nm_a,
            voltage_constant_v_s_rad: i.voltage_constant_v_s_rad,
            friction_torque_nm: i.friction_torque_nm,
            speed_regulation_nm_s_rad: i.speed_regulation_nm_s_rad,
            gear_ratio: o.gear_ratio,
        },
        // Placeholders until the operating points are analysed (voltage steps bypass the drive and the brake).
        drive: DriveParams { kp_v_s_rad: 0.0, ki_v_rad: 0.0, limit_v: c.rig.supply_voltage_v },
        friction: FrictionLaw::Coulomb { mu_static: 0.0, mu_kinetic: 0.0 },
        brake_disc_radius_m: c.rig.brake_disc_radius_m,
        effects: Vec::new(),
        harmonic: None,
    })
}

/// Starting (C on the twist rate, C_r on Ω1) of a damping structure from the
/// log decrement's C (Eq. 4-7's C = 2ξ√(J1 K)): the free decay (motor side
/// held) measures C + C_r whichever placement, so a fitted C_r starts there
/// and, with both fitted, each starts at half of it.
fn initial_damping(c_decay: f64, d: &DampingStructure) -> Result<(f64, f64), EstimateError> {
    let held = |v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(EstimateError::InvalidOption {
                name: "damping.rotor_damping.nm_s_rad".into(),
                value: v,
                rule: "a held rotor drag C_r must be finite and >= 0",
            })
        }
    };
    Ok(match d {
        DampingStructure::TwistRate => (c_decay, 0.0),
        DampingStructure::RotorAbsolute { rotor_damping: RotorDamping::Fitted } => (0.0, c_decay),
        DampingStructure::RotorAbsolute { rotor_damping: RotorDamping::Held { nm_s_rad } } => (0.0, held(*nm_s_rad)?),
        DampingStructure::Both { rotor_damping: RotorDamping::Fitted } => (0.5 * c_decay, 0.5 * c_decay),
        DampingStructure::Both { rotor_damping: RotorDamping::Held { nm_s_rad } } => (c_decay, held(*nm_s_rad)?),
    })
}

/// The voltage-step free set under a damping structure: [`FREE`] (C on the
/// twist rate) with C replaced by C_r, dropped, or joined by C_r.
fn free_set(d: &DampingStructure) -> Vec<&'static str> {
    let mut free: Vec<&'static str> = FREE.to_vec();
    match d {
        DampingStructure::TwistRate | DampingStructure::Both { rotor_damping: RotorDamping::Held { .. } } => {}
        DampingStructure::RotorAbsolute { rotor_damping: RotorDamping::Fitted } => {
            free.iter_mut().filter(|n| **n == "C").for_each(|n| *n = "C_r")
        }
        DampingStructure::RotorAbsolute { rotor_damping: RotorDamping::Held { .. } } => free.retain(|n| *n != "C"),
        DampingStructure::Both { rotor_damping: RotorDamping::Fitted } => free.push("C_r"),
    }
    free
}

/// Why a parameter is fixed by the damping structure (not estimated, not a held motor constant).
fn structural_reason(name: &str, d: &DampingStructure) -> String {
    match (name, d) {
        ("C", _) => "0: the damping structure puts C on the absolute rotor speed (C_r)".into(),
        ("C_r", DampingStructure::TwistRate) => "0: the damping structure puts C on the twist rate".into(),
        ("C_r", _) => "held by the damping structure (value given, e.g. the rotor torque balance)".into(),
        _ => "held".into(),
    }
}

/// Why a held parameter is held, with the correlation it would have if freed.
fn held_reason(name: &str, corr: Option<(&str, f64)>, rel_se: Option<f64>) -> String {
    let why = match name {
        "R_DC" => "enters only as k_T/R",
        "L_DC" => "L/R is about one sample interval",
        "C_m" => "enters only via k_e + R C_m/k_T",
        _ => "held",
    };
    match (corr, rel_se) {
        (Some((other, r)), Some(se)) => {
            format!("{why}; if freed |rho| = {:.3} with {other}, rel. stderr {:.0} %", r.abs(), 100.0 * se)
        }
        (Some((other, r)), None) => format!("{why}; if freed |rho| = {:.3} with {other}", r.abs()),
        _ => format!("{why}; freed: normal matrix singular"),
    }
}

/// A held parameter's strongest partner (name, ρ) and relative standard error, if freed.
type HeldInfo = (Option<(&'static str, f64)>, Option<f64>);

/// Identifiability of each held parameter: freed alone next to the estimated
/// ones, the Jacobian at the solution gives its strongest correlation and
/// the relative standard error it would have.
fn held_analysis(
    problem: &StepProblem,
    sol: &LsqSolution,
    o: &EstimateOptions,
    held: &[&'static str],
) -> Result<Vec<HeldInfo>, EstimateError> {
    let free = &problem.names;
    held.iter()
        .map(|h| {
            let mut names: Vec<&'static str> = free.clone();
            names.push(h);
            let mut x: Vec<f64> = sol.x.clone();
            x.push(get_param(&problem.base, h));
            let full = StepProblem {
                base: problem.base.clone(),
                names: names.clone(),
                steps: problem.steps.clone(),
                sim: problem.sim.clone(),
                residual: problem.residual,
            };
            let tr = vec![Transform::Log; names.len()];
            let theta: Vec<f64> = x.iter().map(|v| v.ln()).collect();
            let jac = fd_jacobian(&full, &theta, &tr, o.solver.fd_step, sol.residuals.len())?;
            let trial = LsqSolution {
                x: x.clone(),
                theta,
                transforms: tr,
                residuals: sol.residuals.clone(),
                jacobian: jac,
                ..sol.clone()
            };
            let cov = covariance(&trial);
            let i = free.len();
            if !cov.regular {
                return Ok((None, None));
            }
            let best = (0..i)
                .max_by(|&a, &b| cov.correlation[i][a].abs().total_cmp(&cov.correlation[i][b].abs()))
                .map(|j| (names[j], cov.correlation[i][j]));
            Ok((best, Some(cov.stderr[i] / x[i])))
        })
        .collect()
}

/// Estimates the rig model from a campaign (see the module docs of [`crate::steps`]).
pub fn estimate_rig(
    c: &Campaign,
    cal: &CampaignCalibration,
    o: &EstimateOptions,
) -> Result<RigEstimate, EstimateError> {
    let steps = step_data(c, o.speed_window_s)?;
    if steps.is_empty() {
        return Err(EstimateError::MissingRuns {
            campaign: c.name.clone(),
            what: "no voltage_step run".into(),
            rule: "the identification needs at least one open-brake voltage step",
        });
    }
    let used = split(&steps, o.holdout.as_deref());
    if !used.iter().any(|u| *u) {
        return Err(EstimateError::MissingRuns {
            campaign: c.name.clone(),
            what: "every voltage step is held out".into(),
            rule: "holdout must leave at least one voltage step for estimation",
        });
    }
    let base = initial_params(c, cal, o)?;
    let sim = sim_options(o);
    let est_steps: Vec<&StepData> = steps.iter().zip(&used).filter(|(_, u)| **u).map(|(s, _)| s).collect();
    // The free set: FREE, plus L when asked (see EstimateOptions::free_inductance).
    let mut free: Vec<&'static str> = free_set(&o.damping);
    let mut held: Vec<&'static str> = HELD.to_vec();
    if o.free_inductance {
        free.push("L_DC");
        held.retain(|h| *h != "L_DC");
    }
    let problem = StepProblem {
        base: base.clone(),
        names: free.clone(),
        steps: est_steps,
        sim: sim.clone(),
        residual: o.step_residual,
    };
    let x0: Vec<f64> = free.iter().map(|n| get_param(&base, n)).collect();
    let tr = vec![Transform::Log; free.len()];
    let sol = match o.solver_kind {
        SolverKind::LevenbergMarquardt => levenberg_marquardt(&problem, &x0, &tr, &o.solver)?,
        SolverKind::GaussNewtonLineSearch => gauss_newton_ls(&problem, &x0, &tr, &o.solver)?,
    };
    let cov = covariance(&sol);
    // K's relative error joins the torque-scaled parameters' (only when K is the calibration's).
    let k_rel = if base.shaft_stiffness_nm_rad == cal.stiffness_nm_rad {
        cal.stiffness_nm_rad_stderr / cal.stiffness_nm_rad
    } else {
        f64::NAN
    };
    let fitted = problem.params_at(&sol.x);
    let held_info = held_analysis(&problem, &sol, o, &held)?;

    // Parameter table in the chapter's order, then C and the gear.
    let pairs = flagged_pairs(&cov.correlation);
    let mut params = Vec::new();
    let order = ["J_m", "L_DC", "R_DC", "k_T", "k_e", "T_f", "C_m", "J_1", "K_s", "C"];
    // C_r gets a row only under a structure that has one (the default table is unchanged).
    let with_rotor = if o.damping == DampingStructure::TwistRate { &[][..] } else { &["C_r"][..] };
    for &name in order.iter().chain(with_rotor) {
        let initial = get_param(&base, name);
        let estimate = get_param(&fitted, name);
        let (stderr, identifiable) = if let Some(j) = free.iter().position(|f| *f == name) {
            let mut se = cov.stderr[j];
            if scales_with_torque(name) && k_rel.is_finite() {
                se = estimate * ((se / estimate).powi(2) + k_rel * k_rel).sqrt();
            }
            let with: Vec<String> = pairs
                .iter()
                .filter_map(|(a, b, _)| {
                    if *a == j {
                        Some(free[*b].to_string())
                    } else if *b == j {
                        Some(free[*a].to_string())
                    } else {
                        None
                    }
                })
                .collect();
            let id = if with.is_empty() { Identifiability::Yes } else { Identifiability::Correlated { with } };
            (cov.regular.then_some(se), id)
        } else if name == "K_s" {
            (
                k_rel.is_finite().then_some(cal.stiffness_nm_rad_stderr),
                Identifiability::Fixed {
                    reason: if k_rel.is_finite() {
                        "static-twist calibration; steps fix torques only relative to K".into()
                    } else {
                        "Table 4.4 (no usable static-twist calibration); steps fix torques only relative to K".into()
                    },
                },
            )
        } else if let Some(h) = held.iter().position(|f| *f == name) {
            (None, Identifiability::Fixed { reason: held_reason(name, held_info[h].0, held_info[h].1) })
        } else {
            (None, Identifiability::Fixed { reason: structural_reason(name, &o.damping) })
        };
        params.push(ParamEstimate {
            name: name.into(),
            unit: unit_of(name).into(),
            initial,
            estimate,
            stderr,
            identifiable,
        });
    }
    params.push(ParamEstimate {
        name: "n".into(),
        unit: "".into(),
        initial: o.gear_ratio,
        estimate: o.gear_ratio,
        stderr: None,
        identifiable: Identifiability::Fixed { reason: "enters only as n k_T, n k_e, n^2 J_m (thesis 8:1)".into() },
    });

    // Every step simulated at the estimate: fit on used and held-out runs.
    type Speeds = (Vec<f64>, Vec<f64>);
    let sims: Vec<Result<Speeds, EstimateError>> = steps
        .par_iter()
        .map(|s| simulate_step(&fitted, s, &sim).map_err(|source| EstimateError::Model { run: s.id.clone(), source }))
        .collect();
    let mut step_fits = Vec::new();
    let mut runs = Vec::new();
    for ((s, u), r) in steps.iter().zip(&used).zip(sims) {
        let (w2, w1) = r?;
        runs.push(RunFit {
            run: s.id.clone(),
            used: *u,
            channels: vec![
                ChannelFit {
                    channel: "motor_speed".into(),
                    fit_percent: fit_percent(&s.motor_speed_rad_s, &w2),
                    nrmse: nrmse(&s.motor_speed_rad_s, &w2),
                },
                ChannelFit {
                    channel: "rotor_speed".into(),
                    fit_percent: fit_percent(&s.rotor_speed_rad_s, &w1),
                    nrmse: nrmse(&s.rotor_speed_rad_s, &w1),
                },
            ],
        });
        step_fits.push(StepFit {
            run: s.id.clone(),
            used: *u,
            voltage_v: s.voltage_v,
            time_s: s.window_time_s.clone(),
            motor_speed_meas_rad_s: s.motor_speed_rad_s.clone(),
            motor_speed_sim_rad_s: w2,
            rotor_speed_meas_rad_s: s.rotor_speed_rad_s.clone(),
            rotor_speed_sim_rad_s: w1,
        });
    }

    // Whiteness per (run, channel) segment of the estimation residuals.
    let mut segments: Vec<&[f64]> = Vec::new();
    let mut offset = 0;
    for s in &problem.steps {
        // Both residual kinds have one entry per window per channel.
        let n = s.motor_speed_rad_s.len();
        segments.push(&sol.residuals[offset..offset + n]);
        segments.push(&sol.residuals[offset + n..offset + 2 * n]);
        offset += 2 * n;
    }
    let white = whiteness(&segments, o.whiteness_max_lag);
    let m = sol.residuals.len();
    // k: free parameters and the noise variance.
    let (aic, bic) = aic_bic(sol.ssr, m, free.len() + 1);

    let pi = estimate_pi(c, c.rig.supply_voltage_v, &o.pi)?;
    let friction = estimate_friction(c, cal.force_offset_mv, cal.force_factor_mv_per_n, &o.friction)?;
    let mut final_params = fitted.clone();
    final_params.drive =
        DriveParams { kp_v_s_rad: pi.kp_v_s_rad, ki_v_rad: pi.ki_v_rad, limit_v: c.rig.supply_voltage_v };
    final_params.friction = FrictionLaw::Coulomb { mu_static: friction.mu_static, mu_kinetic: friction.mu_kinetic };

    let (cwn, cxi) = coupled_mode(&fitted).map_or((None, None), |(w, x)| (Some(w), Some(x)));
    // Motor side held (the log decrement's reading): C and C_r both act on Ω1.
    let (j1, k, cc) = (
        fitted.rotor_inertia_kgm2,
        fitted.shaft_stiffness_nm_rad,
        fitted.shaft_damping_nm_s_rad + fitted.rotor_damping_nm_s_rad,
    );
    let modes = ModeComparison {
        coupled_natural_rad_s: cwn,
        coupled_damping_ratio: cxi,
        fixed_base_natural_rad_s: (k / j1).sqrt(),
        fixed_base_damping_ratio: cc / (2.0 * (j1 * k).sqrt()),
        log_decrement_natural_rad_s: cal.natural_frequency_rad_s,
        log_decrement_natural_rad_s_stderr: cal.natural_frequency_rad_s_stderr,
        log_decrement_damping_ratio: cal.damping_ratio,
        log_decrement_damping_ratio_stderr: cal.damping_ratio_stderr,
    };
    let i = &o.initial;
    let table_4_4 = order
        .iter()
        .map(|n| {
            let v = match *n {
                "J_m" => Some(i.motor_inertia_kgm2),
                "L_DC" => Some(i.inductance_h),
                "R_DC" => Some(i.resistance_ohm),
                "k_T" => Some(i.torque_constant_nm_a),
                "k_e" => Some(i.voltage_constant_v_s_rad),
                "T_f" => Some(i.friction_torque_nm),
                "C_m" => Some(i.speed_regulation_nm_s_rad),
                "J_1" => Some(i.rotor_inertia_kgm2),
                "K_s" => Some(i.shaft_stiffness_nm_rad),
                _ => None,
            };
            (n.to_string(), v)
        })
        .collect();
    Ok(RigEstimate {
        params: final_params,
        report: FitReport {
            params,
            estimated: free.iter().map(|s| s.to_string()).collect(),
            correlation: cov.correlation.clone(),
            flagged_pairs: pairs.iter().map(|(a, b, r)| (free[*a].to_string(), free[*b].to_string(), *r)).collect(),
            n_residuals: m,
            ssr: sol.ssr,
            sigma2: cov.sigma2,
            aic,
            bic,
            whiteness: white,
            converged: sol.converged,
            iterations: sol.iterations,
            stop_reason: sol.stop_reason.clone(),
            history: sol.history.clone(),
            runs,
        },
        pi,
        friction,
        steps: step_fits,
        modes,
        table_4_4,
    })
}

/// The voltage-step parameters other than the damping: the motor side
/// (J_m, k_T, k_e, T_f) and J1, [`FREE`] without C.
pub const MOTOR_SIDE: [&str; 5] = ["J_m", "k_T", "k_e", "T_f", "J_1"];

/// A [`refit_motor_side`] answer: the model with its motor side refitted,
/// and how the fit went.
#[derive(Debug, Clone, PartialEq)]
pub struct MotorRefit {
    pub params: RigParams,
    /// Voltage-step SSR at the start (the model as given) and at the refit, (rad/s)².
    pub ssr_start: f64,
    pub ssr: f64,
    pub iterations: usize,
    pub converged: bool,
}

/// The motor side re-estimated under the damping a model has (issue 25):
/// the voltage-step fit of [`estimate_rig`] (same residual, integrator,
/// solver and default step split: the lowest and highest voltage) with
/// [`MOTOR_SIDE`] free and the damping held where and as `model` puts it —
/// C on the twist rate and C_r on Ω1, e.g. a structural candidate's values
/// from the rotor torque balance. Warm-started at `model`'s motor side (the
/// estimate under the twist-rate placement), so a structure that moves only
/// part of the damping costs a few iterations. Everything else of `model`
/// (drive, friction, effects) is returned unchanged.
///
/// Why: the steps estimate k_T, k_e, T_f *together with* the damping
/// placement they are fitted under ([`DampingStructure`]'s docs: a drag on
/// Ω1 loads the motor in steady rotation, which a twist-rate fit absorbs into
/// the motor constants), so a structure compared on the twist-rate estimate's
/// motor side counts that load twice or not at all.
pub fn refit_motor_side(
    c: &Campaign,
    model: &RigParams,
    window_s: f64,
    residual: crate::steps::StepResidual,
    sim: &SimOptions,
    solver: &crate::lsq::SolverOptions,
) -> Result<MotorRefit, EstimateError> {
    let steps = step_data(c, window_s)?;
    let used = split(&steps, None);
    let est_steps: Vec<&StepData> = steps.iter().zip(&used).filter(|(_, u)| **u).map(|(s, _)| s).collect();
    if est_steps.is_empty() {
        return Err(EstimateError::MissingRuns {
            campaign: c.name.clone(),
            what: "no voltage_step run".into(),
            rule: "the motor side is re-estimated on the open-brake voltage steps",
        });
    }
    let names = MOTOR_SIDE.to_vec();
    let problem =
        StepProblem { base: model.clone(), names: names.clone(), steps: est_steps, sim: sim.clone(), residual };
    let x0: Vec<f64> = names.iter().map(|n| get_param(model, n)).collect();
    // The fitted point alone is read: no Jacobian after the last step.
    let sol = crate::lsq::levenberg_marquardt_minimum(&problem, &x0, &vec![Transform::Log; names.len()], solver)?;
    Ok(MotorRefit {
        params: problem.params_at(&sol.x),
        ssr_start: sol.history.first().map_or(f64::NAN, |h| h.ssr),
        ssr: sol.ssr,
        iterations: sol.iterations,
        converged: sol.converged,
    })
}
