//! The force sensor's calibration runs: is mV against load a straight line?

use super::{ChannelCheck, ChannelOptions, ols};
use rig_types::{Campaign, RunKind};

/// The calibration runs' ids, loads, mean readings and Σ d² of their
/// half-run differences.
struct Means {
    ids: Vec<String>,
    loads: Vec<f64>,
    means: Vec<f64>,
    d2: f64,
}

fn calibration_means(c: &Campaign) -> Means {
    let mut m = Means { ids: Vec::new(), loads: Vec::new(), means: Vec::new(), d2: 0.0 };
    for run in &c.runs {
        let RunKind::ForceCalibration { load_n } = run.kind else { continue };
        let Some(mv) = run.data.brake_force_mv.as_ref().filter(|v| v.len() >= 8) else { continue };
        let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
        let half = mv.len() / 2;
        m.ids.push(run.id.clone());
        m.loads.push(load_n);
        m.means.push(mean(mv));
        m.d2 += (mean(&mv[..half]) - mean(&mv[half..])).powi(2);
    }
    m
}

impl Means {
    /// Runs and distinct loads: the line and the parabola need 4 runs at 3 loads.
    fn counts(&self) -> (usize, usize) {
        let mut l = self.loads.clone();
        l.sort_by(f64::total_cmp);
        l.dedup();
        (self.loads.len(), l.len())
    }

    /// [a, b, c] of mV = a + b·F + c·F² through the means (`None` below 4 runs at 3 loads).
    fn parabola(&self) -> Option<[f64; 3]> {
        let (n, distinct) = self.counts();
        if n < 4 || distinct < 3 {
            return None;
        }
        let x: Vec<Vec<f64>> = self.loads.iter().map(|&l| vec![1.0, l, l * l]).collect();
        let (q, _) = ols(&x, &self.means)?;
        Some([q[0], q[1], q[2]])
    }
}

/// The parabola mV = a + b·F + c·F² through the calibration runs' means
/// ([a, b, c]), the sensor law the diagnosis reads forces through when
/// [`force_linearity_check`] rejects the line; `None` with fewer than four
/// runs at three loads.
pub fn force_parabola(c: &Campaign) -> Option<[f64; 3]> {
    calibration_means(c).parabola()
}

/// Linearity of the force sensor over the `force_calibration` runs.
///
/// The calibration (thesis §4.1, rig-calibrate) fits the straight line
/// mV = offset + factor·F through the runs' mean readings at their known
/// loads, and every measured friction force, hence every μ_obs the diagnosis
/// regresses, goes through that line. A sensor that is not linear (a
/// quadratic term, saturation, a load-dependent offset) bends the readings
/// away from the line; the slip channels would then see a μ that depends on
/// the force level, which no friction law in the vocabulary describes.
///
/// Statistic: the residual standard deviation of the line through the runs'
/// means, √(RSS/(n − 2)), mV. Floor: the means' own noise, from inside the
/// runs: each run's mean over its first half minus over its second half has
/// four times the variance of the whole-run mean, floor = √(Σ d²/(4n)) (as
/// [`super::drive_balance_check`]; no noise model needed, and a reading that
/// wanders within a run raises the floor rather than the statistic). For a
/// linear sensor, ratio² is F-distributed with (n − 2, n) degrees of
/// freedom: with the protocol's 5 loads its 99.9 % point is a ratio of 5.8,
/// so the calibrated threshold (`force_linearity_ratio`) is 6.
///
/// The detail reports the quadratic term of a parabola through the same
/// means and what it does where the campaign runs: the relative error of the
/// line's force at the largest normal force of the operating points.
pub fn force_linearity_check(c: &Campaign, o: &ChannelOptions) -> ChannelCheck {
    let name = "force_calibration.linearity";
    let m = calibration_means(c);
    let (n, distinct) = m.counts();
    let parabola = m.parabola();
    let Means { ids, loads, means, d2 } = m;
    if n < 4 || distinct < 3 {
        return ChannelCheck::not_testable(
            name,
            ids,
            format!("{n} force-calibration runs at {distinct} loads; the linearity test needs 4 runs at 3 loads"),
        );
    }
    let line: Vec<Vec<f64>> = loads.iter().map(|&l| vec![1.0, l]).collect();
    let Some((b, rss)) = ols(&line, &means) else {
        return ChannelCheck::not_testable(name, ids, "the calibration line is singular".into());
    };
    let stat = (rss / (n - 2) as f64).sqrt();
    let floor = (d2 / (4 * n) as f64).sqrt();
    let n_max = c
        .runs
        .iter()
        .filter_map(|r| match r.kind {
            RunKind::OperatingPoint { normal_force_n, .. } => Some(normal_force_n),
            _ => None,
        })
        .fold(0.0, f64::max);
    let bend = match parabola {
        Some(q) if n_max > 0.0 && b[1] != 0.0 => format!(
            "; a parabola through the same means has {:+.3} mV/N², which at the largest normal force of the \
             operating points ({n_max:.1} N) reads {:+.1} % off the line",
            q[2],
            100.0 * q[2] * n_max / b[1]
        ),
        _ => String::new(),
    };
    let (lo, hi) = loads.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &l| (a.0.min(l), a.1.max(l)));
    ChannelCheck::new(
        name,
        ids,
        stat,
        floor,
        o.force_linearity_ratio,
        format!(
            "mV = {:.2} + {:.3}·F through {n} calibration means ({lo:.2}–{hi:.2} N): residual {stat:.3} mV against \
             {floor:.3} mV within the runs{bend} (a sensor that is not linear makes μ_obs depend on the force level)",
            b[0], b[1]
        ),
    )
}
