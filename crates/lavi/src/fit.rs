//! Fitting on the calibration window only: the baseline by least squares
//! (J, k, c on the equation of motion; the friction law on the slip samples),
//! and each candidate cause by Nelder–Mead on the calibration window's
//! feature misfit, starting from the current model.

use crate::data::{Prepared, RPM_TO_RAD_S, WindowSpec, derivative};
use crate::score::Evaluator;
use crate::sim::{Drive, FrictionLaw, MidDof, Model};
use crate::{Candidate, LaviError};
use rig_model::one_dof::fit_one_dof;
use rig_spectra::stickslip::fit_weakening;
use serde::Serialize;
use std::collections::BTreeMap;

/// What the least-squares derivation found (for the report).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Derivation {
    pub damping_unconstrained_nm_s_rad: f64,
    /// True when the unconstrained damping came out negative and was fixed at 0.
    pub damping_fixed: bool,
    pub r_squared: f64,
    pub law_rmse_nm: f64,
    pub law_constant_rmse_nm: f64,
}

/// The baseline procedure on the calibration window, with two switches the
/// candidates use: `wob` (fit the law to T·W_ref/W, torque = WOB·μ) and
/// `sensor_inertia_kgm2` (friction = T_m − J_s Ω̇ before anything is fitted).
/// J, k, c: linear least squares of rig_model::one_dof::fit_one_dof; c fixed at
/// 0 when negative (negative damping feeds energy in). Law: the better (lower
/// rmse) of T = a + b exp(−(v/v_s)^δ), δ = 1, 2, on samples with v > slip_speed_rpm.
pub fn derive(
    d: &Prepared,
    cal: &WindowSpec,
    slip_speed_rpm: f64,
    wob: bool,
    sensor_inertia_kgm2: f64,
) -> Result<(Model, Derivation), LaviError> {
    let r = (cal.span.start + cal.window.start)..(cal.span.start + cal.window.end);
    let t = &d.time_s[r.clone()];
    let rad = |x: &[f64]| x.iter().map(|v| v * RPM_TO_RAD_S).collect::<Vec<f64>>();
    let (top, bit) = (rad(&d.top_rpm[r.clone()]), rad(&d.bit_rpm[r.clone()]));
    let acc = derivative(&bit, d.fs_hz);
    let tf: Vec<f64> = d.torque_nm[r.clone()].iter().zip(&acc).map(|(tm, a)| tm - sensor_inertia_kgm2 * a).collect();
    let w = &d.wob_n[r.clone()];
    let w_ref = w.iter().sum::<f64>() / w.len() as f64;
    let free = fit_one_dof(t, &top, &bit, &acc, &tf, None)?;
    let fixed = free.damping_nm_s_rad < 0.0;
    let dof = if fixed { fit_one_dof(t, &top, &bit, &acc, &tf, Some(0.0))? } else { free };
    let bit_rpm = &d.bit_rpm[r];
    let (vs, ys): (Vec<f64>, Vec<f64>) = (0..t.len())
        .filter(|&i| bit_rpm[i] > slip_speed_rpm)
        .map(|i| (bit_rpm[i], if wob { tf[i] * w_ref / w[i] } else { tf[i] }))
        .unzip();
    let e = fit_weakening(&vs, &ys, 1.0, 0.5, 2000.0)?;
    let g = fit_weakening(&vs, &ys, 2.0, 0.5, 2000.0)?;
    let f = if g.rmse <= e.rmse { g } else { e };
    let model = Model {
        inertia_kgm2: dof.inertia_kgm2,
        stiffness_nm_rad: dof.stiffness_nm_rad,
        damping_nm_s_rad: dof.damping_nm_s_rad,
        friction: FrictionLaw {
            static_nm: f.a + f.b.max(0.0),
            kinetic_nm: f.a,
            stribeck_speed_rad_s: f.vs * RPM_TO_RAD_S,
            shape_exponent: f.shape_exponent,
            viscous_nm_s_rad: 0.0,
        },
        wob_ref_n: wob.then_some(w_ref),
        sensor_inertia_kgm2,
        friction_lag_s: 0.0,
        mid: None,
        drive: None,
    };
    let info = Derivation {
        damping_unconstrained_nm_s_rad: free.damping_nm_s_rad,
        damping_fixed: fixed,
        r_squared: dof.r_squared,
        law_rmse_nm: f.rmse,
        law_constant_rmse_nm: f.rmse_constant,
    };
    Ok((model, info))
}

/// A candidate fitted on the calibration window.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fitted {
    pub model: Model,
    /// The candidate's own parameters (JSON keys of diagnosis.json), in a fixed order.
    pub params: BTreeMap<String, f64>,
    pub calibration_misfit: f64,
    pub evaluations: usize,
}

fn logistic(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

/// Fits candidate `c` on top of `current` on the calibration window of `ev`.
pub fn fit_candidate(c: Candidate, current: &Model, ev: &Evaluator, max_evals: usize) -> Result<Fitted, LaviError> {
    let cal = ev.calibration();
    let carry = |mut m: Model| {
        m.friction_lag_s = current.friction_lag_s;
        m.mid = current.mid;
        m.drive = current.drive;
        m
    };
    let misfit = |m: &Model| ev.misfit(m, cal);
    let j = current.inertia_kgm2;
    let mut params = BTreeMap::new();
    let (model, evals) = match c {
        Candidate::WobNormalForce => {
            // The law stays as the current model has it when a simulation fit chose it;
            // a least-squares law is refitted as μ = T/W (torque = WOB·μ).
            let (m, _) = derive(ev.data, &ev.windows[cal], ev.slip_speed_rpm, true, current.sensor_inertia_kgm2)?;
            let m = if law_is_derived(current, ev)? { carry(m) } else { Model { wob_ref_n: m.wob_ref_n, ..*current } };
            let w_ref = m.wob_ref_n.unwrap_or(1.0);
            params.insert("reference_wob_n".into(), w_ref);
            params.insert("mu_static".into(), m.friction.static_nm / w_ref);
            params.insert("mu_kinetic".into(), m.friction.kinetic_nm / w_ref);
            (m, 1)
        }
        Candidate::SensorInertia => {
            let wob = current.wob_ref_n.is_some();
            let keep_law = !law_is_derived(current, ev)?;
            let build = |x: &[f64]| -> Option<Model> {
                let js = j * x[0].exp();
                derive(ev.data, &ev.windows[cal], ev.slip_speed_rpm, wob, js).ok().map(|(m, _)| {
                    let m = carry(m);
                    if keep_law { Model { friction: current.friction, ..m } } else { m }
                })
            };
            let (x, _, n) = nelder_mead(|x| build(x).map_or(1e9, |m| misfit(&m)), &[-2.0], &[1.0], max_evals);
            let m = build(&x).ok_or(LaviError::Input {
                what: "sensor_inertia",
                rule: "no sensor inertia gives a valid least-squares fit of J, k, c on the calibration window".into(),
            })?;
            params.insert("sensor_inertia_kgm2".into(), m.sensor_inertia_kgm2);
            (m, n)
        }
        Candidate::FrictionLaw => {
            // Three families, each fitted; the best on the calibration window is kept.
            let mut best: Option<(f64, Model, usize, f64)> = None;
            let mut total = 0;
            for family in [0.0, 1.0, 2.0] {
                let f0 = current.friction;
                let build = |x: &[f64]| -> Model {
                    let ts = x[0].exp();
                    let law = FrictionLaw {
                        static_nm: ts,
                        kinetic_nm: ts * logistic(x[1]),
                        // Coulomb: the fall from T_s to T_k happens within 0.01 rad/s (a jump).
                        stribeck_speed_rad_s: if family == 0.0 { 0.01 } else { x[2].exp() },
                        shape_exponent: if family == 0.0 { 1.0 } else { family },
                        viscous_nm_s_rad: x[3].exp(),
                    };
                    Model { friction: law, ..*current }
                };
                let ratio = (f0.kinetic_nm / f0.static_nm).clamp(0.05, 0.95);
                let x0 = [f0.static_nm.ln(), logit(ratio), f0.stribeck_speed_rad_s.ln(), (1e-4f64).ln()];
                let (x, v, n) = nelder_mead(|x| misfit(&build(x)), &x0, &[0.2, 0.5, 0.5, 2.0], max_evals);
                total += n;
                if best.as_ref().is_none_or(|b| v < b.0) {
                    best = Some((v, build(&x), n, family));
                }
            }
            let (_, m, _, family) = best.expect("three families tried");
            params.insert("family".into(), family);
            params.insert("static_nm".into(), m.friction.static_nm);
            params.insert("kinetic_nm".into(), m.friction.kinetic_nm);
            params.insert("stribeck_speed_rad_s".into(), m.friction.stribeck_speed_rad_s);
            params.insert("viscous_nm_s_rad".into(), m.friction.viscous_nm_s_rad);
            (m, total)
        }
        Candidate::FrictionMemory => {
            // The lag is kept within 0.1 ms-1 s (longer than a cycle is no memory but a frozen friction).
            let build = |x: &[f64]| Model { friction_lag_s: x[0].clamp(-9.2, 0.0).exp(), ..*current };
            let (x, _, n) = nelder_mead(|x| misfit(&build(x)), &[(0.02f64).ln()], &[1.0], max_evals);
            let m = build(&x);
            params.insert("lag_s".into(), m.friction_lag_s);
            (m, n)
        }
        Candidate::SecondDof => {
            let build = |x: &[f64]| Model {
                mid: Some(MidDof { inertia_kgm2: j * x[0].exp(), split: logistic(x[1]).clamp(0.02, 0.98) }),
                ..*current
            };
            let (x, _, n) = nelder_mead(|x| misfit(&build(x)), &[0.0, 0.0], &[1.0, 1.0], max_evals);
            let m = build(&x);
            let mid = m.mid.expect("set above");
            params.insert("mid_inertia_kgm2".into(), mid.inertia_kgm2);
            params.insert("stiffness_split".into(), mid.split);
            (m, n)
        }
        Candidate::CompliantDrive => {
            // Start: motor inertia 10 J, a 2 Hz speed loop with a 0.5 Hz integral corner.
            let jm0 = 10.0 * j;
            let kp0 = jm0 * 2.0 * std::f64::consts::TAU;
            let ki0 = kp0 * 0.5 * std::f64::consts::TAU;
            let build = |x: &[f64]| Model {
                drive: Some(Drive {
                    inertia_kgm2: jm0 * x[0].exp(),
                    kp_nm_s_rad: kp0 * x[1].exp(),
                    ki_nm_rad: ki0 * x[2].exp(),
                }),
                ..*current
            };
            let (x, _, n) = nelder_mead(|x| misfit(&build(x)), &[0.0, 0.0, 0.0], &[1.0, 1.0, 1.0], max_evals);
            let m = build(&x);
            let dr = m.drive.expect("set above");
            params.insert("drive_inertia_kgm2".into(), dr.inertia_kgm2);
            params.insert("kp_nm_s_rad".into(), dr.kp_nm_s_rad);
            params.insert("ki_nm_rad".into(), dr.ki_nm_rad);
            (m, n)
        }
    };
    let calibration_misfit = misfit(&model);
    Ok(Fitted { model, params, calibration_misfit, evaluations: evals })
}

/// True when `current`'s law is still the least-squares one of [`derive`] (no simulation fit chose it).
fn law_is_derived(current: &Model, ev: &Evaluator) -> Result<bool, LaviError> {
    let (m, _) = derive(
        ev.data,
        &ev.windows[ev.calibration()],
        ev.slip_speed_rpm,
        current.wob_ref_n.is_some(),
        current.sensor_inertia_kgm2,
    )?;
    Ok(m.friction == current.friction)
}

/// Nelder–Mead simplex (standard coefficients 1, 2, ½, ½), deterministic, at
/// most `max_evals` evaluations. Returns (x, f(x), evaluations).
pub fn nelder_mead(f: impl Fn(&[f64]) -> f64, x0: &[f64], step: &[f64], max_evals: usize) -> (Vec<f64>, f64, usize) {
    let n = x0.len();
    let fx = |x: &[f64]| {
        let v = f(x);
        if v.is_finite() { v } else { 1e9 }
    };
    let mut pts: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    pts.push((x0.to_vec(), fx(x0)));
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step[i];
        let v = fx(&x);
        pts.push((x, v));
    }
    let mut evals = n + 1;
    while evals < max_evals {
        pts.sort_by(|a, b| a.1.total_cmp(&b.1));
        if (pts[n].1 - pts[0].1).abs() < 1e-6 * (1.0 + pts[0].1.abs()) {
            break;
        }
        let centroid: Vec<f64> = (0..n).map(|k| pts[..n].iter().map(|p| p.0[k]).sum::<f64>() / n as f64).collect();
        let along = |t: f64| -> Vec<f64> { (0..n).map(|k| centroid[k] + t * (pts[n].0[k] - centroid[k])).collect() };
        let xr = along(-1.0);
        let fr = fx(&xr);
        evals += 1;
        if fr < pts[0].1 {
            let xe = along(-2.0);
            let fe = fx(&xe);
            evals += 1;
            pts[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < pts[n - 1].1 {
            pts[n] = (xr, fr);
        } else {
            let xc = if fr < pts[n].1 { along(-0.5) } else { along(0.5) };
            let fc = fx(&xc);
            evals += 1;
            if fc < fr.min(pts[n].1) {
                pts[n] = (xc, fc);
            } else {
                let best = pts[0].0.clone();
                for p in pts.iter_mut().skip(1) {
                    let x: Vec<f64> = (0..n).map(|k| best[k] + 0.5 * (p.0[k] - best[k])).collect();
                    *p = (x.clone(), fx(&x));
                    evals += 1;
                }
            }
        }
    }
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (x, v) = pts.swap_remove(0);
    (x, v, evals)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nelder_mead_finds_a_quadratic_minimum() {
        let (x, v, _) =
            nelder_mead(|x| (x[0] - 1.0).powi(2) + 3.0 * (x[1] + 2.0).powi(2), &[0.0, 0.0], &[1.0, 1.0], 500);
        assert!((x[0] - 1.0).abs() < 1e-3 && (x[1] + 2.0).abs() < 1e-3 && v < 1e-6, "{x:?}");
    }
}
