//! What a leftover mismatch follows: a library of signals computed from the
//! recordings, sparse regression of the final model's residual on them
//! (sequentially thresholded least squares, on faer through
//! `rig_estimate::linear::ols`), fitted on training folds and scored on the
//! held-out fold, and in words the physical causes each signal points to.
//!
//! Residuals: in the friction channel the relative slip-coefficient residual
//! ρ = μ_obs/μ̂ − 1 at slip samples (every 5th: 100 Hz), in the drive channel
//! (V − V̂)/V_supply (every 10th sample: 50 Hz). The library's signals, with
//! their names in `signature` of diagnosis.json:
//!
//! | signal | definition |
//! |---|---|
//! | `time_since_start_s` | t − t0 of the run |
//! | `slid_angle_rad` | ∫\|Ω1\| dt since the run started (distance slid, per radius) |
//! | `friction_work_j` | ∫ F r \|Ω1\| dt since the run started |
//! | `slip_speed_rad_s` | \|Ω1\| |
//! | `rotor_accel_rad_s2` | dΩ1/dt (centred difference of Ω1) |
//! | `normal_force_n` | the run's N0 |
//! | `shaft_twist_rad` | φ2 − φ1 |
//! | `twist_rate_rad_s` | Ω2 − Ω1 |
//! | `motor_speed_rad_s` | Ω2 |
//! | `speed_error_rad_s` | Ω_ref − Ω2 (the PI error) |
//! | `drive_voltage_v` | the recorded V |
//!
//! Signals with a per-run phase (angle orders, time sines) are the
//! vocabulary's modulations and the order-line test's; they are not repeated
//! here because a shared regression coefficient cannot follow a phase that is
//! free per run.

use crate::prepare::RunSignals;

/// Names of the library, in column order (module docs define them).
pub const SIGNALS: [&str; 11] = [
    "time_since_start_s",
    "slid_angle_rad",
    "friction_work_j",
    "slip_speed_rad_s",
    "rotor_accel_rad_s2",
    "normal_force_n",
    "shaft_twist_rad",
    "twist_rate_rad_s",
    "motor_speed_rad_s",
    "speed_error_rad_s",
    "drive_voltage_v",
];

/// What physical causes leave a residual that follows `signal`.
pub fn causes(signal: &str) -> &'static str {
    match signal {
        "time_since_start_s" | "slid_angle_rad" | "friction_work_j" => {
            "friction that changes as the pads heat, glaze or wear (fade, run-in), or a force sensor that drifts"
        }
        "slip_speed_rad_s" => {
            "a speed dependence of friction that the vocabulary's Stribeck and viscous laws do not have"
        }
        "rotor_accel_rad_s2" => {
            "inertia between the contact and the force sensor, or friction with memory (a lag, Dahl or LuGre)"
        }
        "normal_force_n" => "a friction coefficient that depends on the pad pressure, or a nonlinear force sensor",
        "shaft_twist_rad" | "twist_rate_rad_s" => {
            "a nonlinear or backlashed shaft or coupling, or the shaft load leaking into the force sensor"
        }
        _ => "a drive that is not the PI model (deadband, current limit, gain or supply change)",
    }
}

/// The signal library of one run at sample `k` (the module docs define each).
pub struct Library {
    cols: Vec<Vec<f64>>,
}

impl Library {
    pub fn of(s: &RunSignals, disc_radius_m: f64) -> Library {
        let n = s.time_s.len();
        let mut slid = vec![0.0; n];
        let mut work = vec![0.0; n];
        for k in 1..n {
            let dt = s.time_s[k] - s.time_s[k - 1];
            let w = 0.5 * (s.rotor_speed_rad_s[k].abs() + s.rotor_speed_rad_s[k - 1].abs());
            let p = 0.5
                * (s.friction_force_n[k] * s.rotor_speed_rad_s[k].abs()
                    + s.friction_force_n[k - 1] * s.rotor_speed_rad_s[k - 1].abs());
            slid[k] = slid[k - 1] + w * dt;
            work[k] = work[k - 1] + disc_radius_m * p * dt;
        }
        let accel = crate::prepare::centred_speed(&s.time_s, &s.rotor_speed_rad_s, 8);
        let t0 = s.time_s.first().copied().unwrap_or(0.0);
        let cols = vec![
            s.time_s.iter().map(|t| t - t0).collect(),
            slid,
            work,
            s.rotor_speed_rad_s.iter().map(|w| w.abs()).collect(),
            accel,
            vec![s.normal_force_n; n],
            s.motor_angle_rad.iter().zip(&s.rotor_angle_rad).map(|(a, b)| a - b).collect(),
            s.motor_speed_rad_s.iter().zip(&s.rotor_speed_rad_s).map(|(a, b)| a - b).collect(),
            s.motor_speed_rad_s.clone(),
            (0..n).map(|k| s.reference_rad_s(s.time_s[k]) - s.motor_speed_rad_s[k]).collect(),
            s.voltage_v.clone(),
        ];
        Library { cols }
    }

    pub fn row(&self, k: usize) -> Vec<f64> {
        self.cols.iter().map(|c| c[k]).collect()
    }
}

/// Residual samples of one channel: per sample its run's fold, the library
/// row, the residual and a weight that turns the residual back into the
/// channel's misfit units (μ̂ for ρ, 1 for the voltage).
#[derive(Debug, Clone, Default)]
pub struct Samples {
    pub run: Vec<usize>,
    pub fold: Vec<usize>,
    pub x: Vec<Vec<f64>>,
    pub y: Vec<f64>,
    pub scale: Vec<f64>,
}

/// One term of the signature.
#[derive(Debug, Clone, PartialEq)]
pub struct Term {
    pub signal: &'static str,
    /// "friction" or "drive".
    pub channel: &'static str,
    /// 1 − held-out RSS with the term / without it (intercept only), over the folds.
    pub heldout_gain: f64,
    /// Change of the residual per unit of the signal (fitted on all runs).
    pub slope: f64,
    /// Spearman-free summary: the residual's standard deviation explained, in the channel's units.
    pub residual_sd: f64,
}

/// The result of the sparse regression on one channel.
#[derive(Debug, Clone, Default)]
pub struct ChannelSignature {
    pub terms: Vec<Term>,
    /// Held-out gain of the whole sparse model (all retained terms together).
    pub combined_gain: f64,
    /// Per run: held-out RSS(after)/RSS(before) in misfit units (1 where the run has no samples).
    pub run_factor: Vec<f64>,
    /// Retained columns (library index) of the sparse model.
    pub retained: Vec<usize>,
}

fn standardise(x: &[Vec<f64>], rows: &[usize], cols: &[usize]) -> (Vec<f64>, Vec<f64>) {
    let n = rows.len().max(1) as f64;
    let mut mean = vec![0.0; cols.len()];
    let mut sd = vec![0.0; cols.len()];
    for (j, &c) in cols.iter().enumerate() {
        mean[j] = rows.iter().map(|&i| x[i][c]).sum::<f64>() / n;
        sd[j] = (rows.iter().map(|&i| (x[i][c] - mean[j]).powi(2)).sum::<f64>() / n).sqrt();
    }
    (mean, sd)
}

/// Least squares of y on [1, standardised columns] over `rows`; `None` when singular.
fn fit(x: &[Vec<f64>], y: &[f64], rows: &[usize], cols: &[usize]) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let (mean, sd) = standardise(x, rows, cols);
    if sd.iter().any(|&s| s <= 1e-12) {
        return None;
    }
    let design: Vec<Vec<f64>> = rows
        .iter()
        .map(|&i| {
            let mut r = vec![1.0];
            r.extend(cols.iter().enumerate().map(|(j, &c)| (x[i][c] - mean[j]) / sd[j]));
            r
        })
        .collect();
    let yy: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
    let f = rig_estimate::linear::ols(&design, &yy, "residual signature").ok()?;
    Some((f.beta, mean, sd))
}

fn predict(beta: &[f64], mean: &[f64], sd: &[f64], cols: &[usize], row: &[f64]) -> f64 {
    beta[0] + cols.iter().enumerate().map(|(j, &c)| beta[1 + j] * (row[c] - mean[j]) / sd[j]).sum::<f64>()
}

/// Sequentially thresholded least squares: fit on all columns, drop those
/// whose standardised coefficient is below `threshold` × sd(y), refit, until
/// nothing changes. Returns the retained columns.
pub fn stlsq(x: &[Vec<f64>], y: &[f64], rows: &[usize], threshold: f64) -> Vec<usize> {
    let ny = rows.len().max(1) as f64;
    let my = rows.iter().map(|&i| y[i]).sum::<f64>() / ny;
    let sy = (rows.iter().map(|&i| (y[i] - my).powi(2)).sum::<f64>() / ny).sqrt();
    let ncol = x.first().map_or(0, Vec::len);
    // Columns constant over the rows carry nothing.
    let mut active: Vec<usize> = (0..ncol)
        .filter(|&c| {
            let (_, sd) = standardise(x, rows, &[c]);
            sd[0] > 1e-12
        })
        .collect();
    for _ in 0..ncol + 1 {
        let Some((beta, _, _)) = fit(x, y, rows, &active) else {
            // Collinear: drop the last column and retry.
            active.pop();
            continue;
        };
        let keep: Vec<usize> =
            active.iter().enumerate().filter(|(j, _)| beta[1 + j].abs() >= threshold * sy).map(|(_, &c)| c).collect();
        if keep == active {
            break;
        }
        active = keep;
    }
    active
}

/// Held-out gain of a model on `cols` over the folds: 1 − Σ held-out RSS / Σ
/// held-out RSS of the training mean. Also the per-run RSS ratio in misfit units.
fn cv_gain(s: &Samples, cols: &[usize], folds: usize, n_runs: usize) -> (f64, Vec<f64>) {
    let mut before = vec![0.0; n_runs];
    let mut after = vec![0.0; n_runs];
    for f in 0..folds {
        let train: Vec<usize> = (0..s.y.len()).filter(|&i| s.fold[i] != f).collect();
        let held: Vec<usize> = (0..s.y.len()).filter(|&i| s.fold[i] == f).collect();
        if train.is_empty() || held.is_empty() {
            continue;
        }
        let mean_y = train.iter().map(|&i| s.y[i]).sum::<f64>() / train.len() as f64;
        let model = if cols.is_empty() { None } else { fit(&s.x, &s.y, &train, cols) };
        for &i in &held {
            let yhat = match &model {
                Some((b, m, sd)) => predict(b, m, sd, cols, &s.x[i]),
                None => mean_y,
            };
            let w = s.scale[i] * s.scale[i];
            before[s.run[i]] += w * s.y[i] * s.y[i];
            after[s.run[i]] += w * (s.y[i] - yhat).powi(2);
        }
    }
    let (tb, ta): (f64, f64) = (before.iter().sum(), after.iter().sum());
    let factor = before.iter().zip(&after).map(|(b, a)| if *b > 0.0 { a / b } else { 1.0 }).collect();
    (if tb > 0.0 { 1.0 - ta / tb } else { 0.0 }, factor)
}

/// The signature of one channel: the sparse model's retained terms, each
/// scored alone on held-out folds, best first, and the combined model's gain.
pub fn channel_signature(
    s: &Samples,
    channel: &'static str,
    folds: usize,
    n_runs: usize,
    threshold: f64,
) -> ChannelSignature {
    if s.y.len() < 50 {
        return ChannelSignature { run_factor: vec![1.0; n_runs], ..Default::default() };
    }
    let all: Vec<usize> = (0..s.y.len()).collect();
    let retained = stlsq(&s.x, &s.y, &all, threshold);
    let (combined_gain, run_factor) = cv_gain(s, &retained, folds, n_runs);
    let mut terms: Vec<Term> = retained
        .iter()
        .map(|&c| {
            let (g, _) = cv_gain(s, &[c], folds, n_runs);
            let (slope, sd_x) = match fit(&s.x, &s.y, &all, &[c]) {
                Some((b, _, sd)) => (b[1] / sd[0], sd[0]),
                None => (0.0, 0.0),
            };
            Term { signal: SIGNALS[c], channel, heldout_gain: g, slope, residual_sd: (slope * sd_x).abs() }
        })
        .collect();
    terms.sort_by(|a, b| b.heldout_gain.total_cmp(&a.heldout_gain).then(a.signal.cmp(b.signal)));
    ChannelSignature { terms, combined_gain, run_factor, retained }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A residual that follows column 1 (and noise) is found, scored positive
    /// on held-out folds; unrelated columns are dropped.
    #[test]
    fn stlsq_finds_the_signal_the_residual_follows() {
        let mut s = Samples::default();
        let mut seed = 3u64;
        let mut u = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for i in 0..4000 {
            let row: Vec<f64> = (0..SIGNALS.len()).map(|_| u()).collect();
            let y = 0.8 * row[1] + 0.05 * u();
            s.run.push(i % 8);
            s.fold.push((i % 8) % 4);
            s.x.push(row);
            s.y.push(y);
            s.scale.push(1.0);
        }
        let sig = channel_signature(&s, "friction", 4, 8, 0.05);
        assert_eq!(sig.retained, vec![1]);
        assert_eq!(sig.terms[0].signal, "slid_angle_rad");
        assert!(sig.terms[0].heldout_gain > 0.95 && (sig.terms[0].slope - 0.8).abs() < 0.01, "{:?}", sig.terms);
        assert!(sig.run_factor.iter().all(|f| *f < 0.1));
    }

    /// Pure noise keeps nothing (or nothing with a held-out gain).
    #[test]
    fn noise_has_no_signature() {
        let mut s = Samples::default();
        let mut seed = 5u64;
        let mut u = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for i in 0..4000 {
            let row: Vec<f64> = (0..SIGNALS.len()).map(|_| u()).collect();
            s.run.push(i % 8);
            s.fold.push((i % 8) % 4);
            s.x.push(row);
            s.y.push(u());
            s.scale.push(1.0);
        }
        let sig = channel_signature(&s, "friction", 4, 8, 0.05);
        assert!(sig.terms.iter().all(|t| t.heldout_gain < 0.01), "{:?}", sig.terms);
    }
}
