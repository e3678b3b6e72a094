//! Residual signature: what the final model's leftover torque follows.
//!
//! On slip samples (|Ω| above `slip_speed_rpm`) the teacher-forced residual
//! r = T_meas − T_model(Ω_meas, W_meas) − J_s Ω̇_meas is regressed on a library
//! of signals from the recording by sequentially thresholded least squares
//! (STLSQ: Brunton et al. 2016) on the calibration window (standardised
//! regressors, threshold 10 % of the largest coefficient, 10 rounds). Each kept
//! term is then scored alone on the held-out windows with its calibration
//! coefficient: heldout_gain = 1 − Σ(r − βx)² / Σ r².

use crate::LaviError;
use crate::data::{RPM_TO_RAD_S, derivative};
use crate::score::Evaluator;
use crate::sim::Model;
use serde::Serialize;

/// One signal the leftover torque follows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SignatureTerm {
    pub signal: String,
    pub heldout_gain: f64,
    pub description: String,
}

/// Signal names of the library (units in the names) and their meaning.
pub const LIBRARY: [(&str, &str); 5] = [
    ("bit_acceleration_rad_s2", "the bit's angular acceleration"),
    ("wob_deviation_n", "the weight on bit minus its window mean"),
    ("wob_rate_n_s", "the rate of change of the weight on bit"),
    ("twist_rate_rad_s", "top speed minus bit speed"),
    ("bit_speed_rad_s", "the bit speed"),
];

struct Samples {
    x: Vec<[f64; 5]>,
    r: Vec<f64>,
}

fn samples(ev: &Evaluator, m: &Model, wi: usize) -> Samples {
    let d = ev.data;
    let w = &ev.windows[wi];
    let r = (w.span.start + w.window.start)..(w.span.start + w.window.end);
    let bit: Vec<f64> = d.bit_rpm[r.clone()].iter().map(|v| v * RPM_TO_RAD_S).collect();
    let acc = derivative(&bit, d.fs_hz);
    let top = crate::fit::top_rad_s(d, r.clone(), m.structure.top_delay_s);
    let wob = &d.wob_n[r.clone()];
    let wdot = derivative(wob, d.fs_hz);
    let wmean = wob.iter().sum::<f64>() / wob.len() as f64;
    let mut s = Samples { x: Vec::new(), r: Vec::new() };
    for (k, i) in r.enumerate() {
        if d.bit_rpm[i].abs() <= ev.slip_speed_rpm {
            continue;
        }
        let g = m.wob_ref_n.map_or(1.0, |w_ref| wob[k] / w_ref);
        let pred = bit[k].signum() * g * m.friction.slip_nm(bit[k]) + m.sensor_inertia_kgm2 * acc[k];
        s.r.push(d.torque_nm[i] - pred);
        s.x.push([acc[k], wob[k] - wmean, wdot[k], top[k] - bit[k], bit[k]]);
    }
    s
}

/// Least squares with an intercept on the columns `cols` of `x` (the study's one
/// path, [`crate::lsq::least_squares`]); returns (intercept, coefficients).
fn lsq(x: &[[f64; 5]], y: &[f64], cols: &[usize]) -> Option<(f64, Vec<f64>)> {
    let row = |i: usize| -> Vec<f64> { std::iter::once(1.0).chain(cols.iter().map(|&c| x[i][c])).collect() };
    let fit = crate::lsq::least_squares(y, cols.len() + 1, row)?;
    Some((fit.coef[0], fit.coef[1..].to_vec()))
}

/// The signature of `m`'s leftover torque, best held-out gain first (terms with gain > 0 only).
pub fn residual_signature(ev: &Evaluator, m: &Model) -> Result<Vec<SignatureTerm>, LaviError> {
    let cal = samples(ev, m, ev.calibration());
    if cal.r.len() < 20 {
        return Ok(Vec::new());
    }
    // Standardise on the calibration window so the threshold compares like with like.
    let n = cal.r.len() as f64;
    let sd: Vec<f64> = (0..5)
        .map(|c| {
            let mu = cal.x.iter().map(|x| x[c]).sum::<f64>() / n;
            (cal.x.iter().map(|x| (x[c] - mu).powi(2)).sum::<f64>() / n).sqrt().max(1e-12)
        })
        .collect();
    let xs: Vec<[f64; 5]> = cal.x.iter().map(|x| std::array::from_fn(|c| x[c] / sd[c])).collect();
    let mut active: Vec<usize> = (0..5).collect();
    let mut coef = vec![0.0; 5];
    for _ in 0..10 {
        let Some((_, beta)) = lsq(&xs, &cal.r, &active) else { break };
        coef = vec![0.0; 5];
        for (k, &c) in active.iter().enumerate() {
            coef[c] = beta[k];
        }
        let big = coef.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let keep: Vec<usize> = active.iter().copied().filter(|&c| coef[c].abs() >= 0.1 * big).collect();
        if keep == active {
            break;
        }
        active = keep;
    }
    let held: Vec<Samples> = ev.heldout().into_iter().map(|w| samples(ev, m, w)).collect();
    let mut out = Vec::new();
    for &c in &active {
        // Coefficient of this term alone on the calibration window (with intercept), physical units.
        let Some((b0, b)) = lsq(&cal.x, &cal.r, &[c]) else { continue };
        let (mut sse, mut sst) = (0.0, 0.0);
        for s in &held {
            for (x, r) in s.x.iter().zip(&s.r) {
                sse += (r - b0 - b[0] * x[c]).powi(2);
                sst += r * r;
            }
        }
        let gain = 1.0 - sse / sst.max(1e-300);
        if gain > 0.0 {
            let (name, what) = LIBRARY[c];
            out.push(SignatureTerm {
                signal: name.to_string(),
                heldout_gain: gain,
                description: format!(
                    "the leftover torque on slip samples follows {what} with {:.4} N m per unit (standardised STLSQ weight {:.3} N m); \
                     that term alone removes {:.0} % of the held-out residual sum of squares",
                    b[0],
                    coef[c],
                    100.0 * gain
                ),
            });
        }
    }
    out.sort_by(|a, b| b.heldout_gain.total_cmp(&a.heldout_gain).then(a.signal.cmp(&b.signal)));
    Ok(out)
}
