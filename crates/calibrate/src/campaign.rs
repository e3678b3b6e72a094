//! Calibration of a recorded campaign (rig-campaign/1): force-sensor factor and
//! offset (Table 4.6's procedure), static stiffness (Table 4.3's), and the free
//! decay of every voltage step (Table 4.2's: δ, ξ, ω_d, ω_n, then J1 by Eq. 4-4).

use crate::signal::{self, DecayAnalysis};
use crate::stats;
use crate::{CalibrateError, formulas};
use rig_types::{Campaign, Run, RunKind, sensor};

pub use rig_types::contract::{
    CONFIDENCE, CalibrationSettings, CampaignCalibration, ForceRun, SkippedStep, StepDecay, TwistRun,
};

fn column<'a, T>(run: &'a Run, col: &'a Option<Vec<T>>, name: &str) -> Result<&'a [T], CalibrateError> {
    col.as_deref().ok_or_else(|| CalibrateError::MissingColumn { run: run.id.clone(), column: name.to_string() })
}

fn need(kind: &str, need: usize, got: usize) -> Result<(), CalibrateError> {
    if got < need { Err(CalibrateError::MissingRuns { kind: kind.to_string(), need, got }) } else { Ok(()) }
}

/// Force-sensor calibration (Table 4.6's procedure, plus an offset).
pub fn force_runs(c: &Campaign) -> Result<Vec<ForceRun>, CalibrateError> {
    let mut out = Vec::new();
    for run in c.runs_of("force_calibration") {
        let RunKind::ForceCalibration { load_n } = run.kind else { continue };
        let mv = column(run, &run.data.brake_force_mv, "brake_force_mv")?;
        let mean_mv = stats::mean(mv).ok_or_else(|| CalibrateError::MissingColumn {
            run: run.id.clone(),
            column: "brake_force_mv (no samples)".into(),
        })?;
        out.push(ForceRun {
            id: run.id.clone(),
            load_n,
            mean_mv,
            std_mv: stats::sample_std(mv).unwrap_or(0.0),
            samples: mv.len(),
            ratio_mv_per_n: (load_n != 0.0).then(|| formulas::force_factor_mv_per_n(mean_mv, load_n)),
        });
    }
    Ok(out)
}

/// Static twist runs: mean rotor angle from ticks (the motor side is locked,
/// so the rotor angle is the shaft twist).
pub fn twist_runs(c: &Campaign) -> Result<Vec<TwistRun>, CalibrateError> {
    let mut out = Vec::new();
    for run in c.runs_of("static_twist") {
        let RunKind::StaticTwist { torque_nm } = run.kind else { continue };
        let ticks = column(run, &run.data.rotor_ticks, "rotor_ticks")?;
        let angle = sensor::ticks_to_rad(ticks, c.rig.encoder_ticks_per_rev);
        let angle_rad = stats::mean(&angle).ok_or_else(|| CalibrateError::MissingColumn {
            run: run.id.clone(),
            column: "rotor_ticks (no samples)".into(),
        })?;
        out.push(TwistRun {
            id: run.id.clone(),
            torque_nm,
            angle_rad,
            angle_std_rad: stats::sample_std(&angle).unwrap_or(0.0),
            stiffness_nm_rad: (angle_rad != 0.0).then(|| formulas::static_stiffness_nm_rad(torque_nm, angle_rad)),
        });
    }
    Ok(out)
}

/// The whole campaign-side calibration.
///
/// Free decay: the voltage steps are analysed on the shaft twist φ2 − φ1.
/// With the motor side turning at Ω2, rotor 1 obeys J1 φ̈1 + C φ̇1 = K(φ2 − φ1)
/// (Eq. 4-7, brake open), so the twist θ = φ2 − φ1 is the 1-DOF oscillator of
/// Eqs. 4-2/4-3 about a constant offset C Ω2 / K. The twist needs no
/// differentiation (quantisation 0.006 rad against swings of radians), and
/// successive swings (peak to trough) cancel the offset. The rotor speed
/// Ω1 = Ω2 − θ̇ carries the same δ and ω_d; it is analysed too as a cross-check.
/// J1 = K/ω_n² (Eq. 4-4) with K the campaign's static stiffness.
pub fn calibrate_campaign(c: &Campaign) -> Result<CampaignCalibration, CalibrateError> {
    calibrate_campaign_with(c, &CalibrationSettings::default())
}

/// [`calibrate_campaign`] with explicit settings.
pub fn calibrate_campaign_with(c: &Campaign, s: &CalibrationSettings) -> Result<CampaignCalibration, CalibrateError> {
    let forces = force_runs(c)?;
    need("force_calibration", 3, forces.len())?;
    let loads: Vec<f64> = forces.iter().map(|f| f.load_n).collect();
    let mvs: Vec<f64> = forces.iter().map(|f| f.mean_mv).collect();
    let force_fit = stats::fit_with_offset(&loads, &mvs, s.confidence)?;
    let ratios: Vec<f64> = forces.iter().filter_map(|f| f.ratio_mv_per_n).collect();

    let twists = twist_runs(c)?;
    need("static_twist", 2, twists.len())?;
    let angles: Vec<f64> = twists.iter().map(|t| t.angle_rad).collect();
    let torques: Vec<f64> = twists.iter().map(|t| t.torque_nm).collect();
    let k_fit = stats::fit_through_origin(&angles, &torques, s.confidence)?;
    let k_offset = if twists.len() >= 3 {
        stats::fit_with_offset(&angles, &torques, s.confidence)?
    } else {
        k_fit.clone() // too few runs for an offset: repeat the origin fit (flagged by through_origin)
    };
    let k = k_fit.slope;

    let tset = s.twist(c.rig.encoder_ticks_per_rev);
    let sset = s.speed();
    let mut steps = Vec::new();
    let mut steps_without_decay = Vec::new();
    for run in c.runs_of("voltage_step") {
        let RunKind::VoltageStep { voltage_v } = run.kind else { continue };
        let t = &run.data.time_s;
        let mt = column(run, &run.data.motor_ticks, "motor_ticks")?;
        let rt = column(run, &run.data.rotor_ticks, "rotor_ticks")?;
        let twist_ticks: Vec<i64> = mt.iter().zip(rt).map(|(m, r)| m - r).collect();
        let twist = sensor::ticks_to_rad(&twist_ticks, c.rig.encoder_ticks_per_rev);
        let td = match signal::decay_analysis(&format!("run {} twist", run.id), t, &twist, &tset) {
            Ok(a) => a,
            // A step without a measurable decay is data: it is listed, and the others still calibrate.
            Err(e @ CalibrateError::NoDecay { .. }) => {
                steps_without_decay.push(SkippedStep { id: run.id.clone(), voltage_v, reason: e.to_string() });
                continue;
            }
            Err(e) => return Err(e),
        };
        let w1 = sensor::encoder_speed_rad_s(t, rt, c.rig.encoder_ticks_per_rev);
        let sd = signal::decay_analysis(&format!("run {} rotor speed", run.id), t, &w1, &sset).ok();
        let j = formulas::inertia_from_frequency_kgm2(k, td.natural_rad_s_mean);
        steps.push(StepDecay { id: run.id.clone(), voltage_v, twist: td, rotor_speed: sd, rotor_inertia_kgm2: j });
    }
    if steps.is_empty() {
        return Err(match steps_without_decay.first() {
            Some(first) => CalibrateError::NoDecay {
                what: format!("all {} voltage_step runs", steps_without_decay.len()),
                reason: first.reason.clone(),
            },
            None => CalibrateError::MissingRuns { kind: "voltage_step".into(), need: 1, got: 0 },
        });
    }

    // Across steps: mean of step means; stderr from the spread over steps, or
    // from the within-step spread over pairs when there is a single step.
    let across = |f: &dyn Fn(&DecayAnalysis) -> (f64, f64)| -> (f64, f64) {
        let v: Vec<f64> = steps.iter().map(|s| f(&s.twist).0).collect();
        let m = stats::mean(&v).unwrap_or(f64::NAN);
        let se = match stats::sample_std(&v) {
            Some(sd) => sd / (v.len() as f64).sqrt(),
            None => f(&steps[0].twist).1 / (steps[0].twist.pairs.len() as f64).sqrt(),
        };
        (m, se)
    };
    let (delta, delta_se) = across(&|a| (a.log_decrement_mean, a.log_decrement_std));
    let (xi, xi_se) = across(&|a| (a.damping_ratio_mean, a.damping_ratio_std));
    let (wd, wd_se) = across(&|a| (a.damped_rad_s_mean, a.damped_rad_s_std));
    let (wn, wn_se) = across(&|a| (a.natural_rad_s_mean, a.natural_rad_s_std));
    // Eq. 4-4 with the mean ω_n, as the chapter does; relative errors add in quadrature.
    let j1 = formulas::inertia_from_frequency_kgm2(k, wn);
    let j1_se = j1 * ((k_fit.slope_stderr / k).powi(2) + (2.0 * wn_se / wn).powi(2)).sqrt();

    Ok(CampaignCalibration {
        force_factor_mv_per_n: force_fit.slope,
        force_factor_mv_per_n_stderr: force_fit.slope_stderr,
        force_factor_mv_per_n_ci: force_fit.slope_ci,
        force_offset_mv: force_fit.intercept,
        force_offset_mv_stderr: force_fit.intercept_stderr,
        force_ratio_mean_mv_per_n: stats::mean(&ratios).unwrap_or(f64::NAN),
        force_runs: forces,
        stiffness_nm_rad: k,
        stiffness_nm_rad_stderr: k_fit.slope_stderr,
        stiffness_nm_rad_ci: k_fit.slope_ci,
        stiffness_with_offset: k_offset,
        twist_runs: twists,
        log_decrement: delta,
        log_decrement_stderr: delta_se,
        damping_ratio: xi,
        damping_ratio_stderr: xi_se,
        damped_frequency_rad_s: wd,
        damped_frequency_rad_s_stderr: wd_se,
        natural_frequency_rad_s: wn,
        natural_frequency_rad_s_stderr: wn_se,
        rotor_inertia_kgm2: j1,
        rotor_inertia_kgm2_stderr: j1_se,
        steps,
        steps_without_decay,
        settings: s.clone(),
        twist_settings: tset,
        speed_settings: sset,
    })
}

/// Friction torque on rotor 1 from the raw force-sensor voltage:
/// F = (mV − offset) / factor, T1 = F · r (the spec: "force * brake_disc_radius_m").
pub fn friction_torque_nm(force_mv: &[f64], cal: &CampaignCalibration, radius_m: f64) -> Vec<f64> {
    let line = sensor::ForceCal { factor_mv_per_n: cal.force_factor_mv_per_n, offset_mv: cal.force_offset_mv };
    sensor::force_n(force_mv, line).iter().map(|f| f * radius_m).collect()
}
