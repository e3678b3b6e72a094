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

    /// [a, b, c] of mV = a + b·F + c·F² through the means and its residual
    /// sum of squares, mV² (`None` below 4 runs at 3 loads).
    fn parabola_fit(&self) -> Option<([f64; 3], f64)> {
        let (n, distinct) = self.counts();
        if n < 4 || distinct < 3 {
            return None;
        }
        let x: Vec<Vec<f64>> = self.loads.iter().map(|&l| vec![1.0, l, l * l]).collect();
        let (q, rss) = ols(&x, &self.means)?;
        Some(([q[0], q[1], q[2]], rss))
    }
}

/// The parabola mV = a + b·F + c·F² through the calibration runs' means
/// ([a, b, c]), the sensor law the diagnosis reads forces through when
/// [`force_linearity_check`] rejects the line; `None` with fewer than four
/// runs at three loads.
pub fn force_parabola(c: &Campaign) -> Option<[f64; 3]> {
    calibration_means(c).parabola_fit().map(|p| p.0)
}

/// Linearity of the force sensor over the `force_calibration` runs, judged
/// by what a bend would do to μ at the operating points.
///
/// The calibration (thesis §4.1, rig-calibrate) fits the straight line
/// mV = offset + factor·F through the runs' mean readings at their known
/// loads, and every measured friction force, hence every μ_obs the diagnosis
/// regresses, goes through that line. A load cell or bridge that is not
/// linear bends its readings smoothly with the load: to first order a
/// quadratic term, mV = a + b·F + c·F². Read through the line, a force F
/// comes out off by (c/b)·r(F), r(F) = F² − (α + β·F) with α + β·F the
/// straight line through the calibration loads' F² (the parabola minus the
/// line, both least squares through the same means: Frisch–Waugh), so μ_obs
/// = F/N is off by the relative error e(F) = c·r(F)/(b·F), which varies with
/// the force level — a μ that depends on the load, which no friction law in
/// the vocabulary describes.
///
/// Statistic: the bend c against its standard error, the t of the
/// quadratic term: se(c) = s/√Σr(F_i)² over the loads, s² the pooled
/// variance of a run's mean from the within-run half-run differences (each
/// run's first-half mean minus its second-half mean has four times the
/// variance of its whole-run mean: Σd²/4, n dof) and the parabola's residual
/// (RSS, n − 3 dof), s² = (Σd²/4 + RSS)/(2n − 3). For a linear sensor t is
/// Student's with 2n − 3 dof (7 with the protocol's 5 loads: P(|t| > 6) =
/// 5.4e-4), so the threshold `force_linearity_ratio` stays 6. The
/// consequence: flagged only when the bend also moves μ by more than μ's
/// own relative uncertainty (`mu_relative_se`: the kinetic level's standard
/// error over its value, rig-estimate's between-run scatter) at one of the
/// operating points' friction forces (each run's mean reading through the
/// line; the largest |e| over the runs is reported): a bend below that
/// changes nothing the records can tell μ by. Without operating points the
/// bend's t alone decides.
///
/// This replaces the line's lack of fit (residual SD over the within-run
/// floor alone, an F test of 3 against 5 dof), which any scatter of the
/// means about the line raised, bent or not, and a floor small by chance
/// inflated: full battery `ladder-normal_force_modulation-2-16` read 7.37
/// there (residual 0.166 mV against a floor of 0.023 mV) with a parabola of
/// +0.0034 ± 0.0178 mV/N² (t 0.19; docs/findings.md, twelfth session).
pub fn force_linearity_check(c: &Campaign, o: &ChannelOptions, mu_relative_se: Option<f64>) -> ChannelCheck {
    let name = "force_calibration.linearity";
    let m = calibration_means(c);
    let (n, distinct) = m.counts();
    let parabola = m.parabola_fit();
    let Means { ids, loads, means, d2 } = m;
    if n < 4 || distinct < 3 {
        return ChannelCheck::not_testable(
            name,
            ids,
            format!("{n} force-calibration runs at {distinct} loads; the linearity test needs 4 runs at 3 loads"),
        );
    }
    let line: Vec<Vec<f64>> = loads.iter().map(|&l| vec![1.0, l]).collect();
    // The loads' F² on the line: α, β and Σ r(F_i)² (Frisch–Waugh).
    let squares: Vec<f64> = loads.iter().map(|l| l * l).collect();
    let (Some((b, _)), Some((ab, r2)), Some((q, rss_q))) = (ols(&line, &means), ols(&line, &squares), parabola) else {
        return ChannelCheck::not_testable(name, ids, "the calibration line or parabola is singular".into());
    };
    if b[1] == 0.0 || r2 <= 0.0 {
        return ChannelCheck::not_testable(name, ids, "the calibration line has no slope".into());
    }
    let s = ((d2 / 4.0 + rss_q) / (2 * n - 3) as f64).sqrt();
    let se_c = s / r2.sqrt();
    let r = |f: f64| f * f - (ab[0] + ab[1] * f);
    // Relative error of μ_obs at force F read through the line, and its standard error.
    let e = |f: f64| q[2] * r(f) / (b[1] * f);
    let se_e = |f: f64| se_c * r(f).abs() / (b[1] * f).abs();
    let forces: Vec<f64> = c
        .runs
        .iter()
        .filter(|run| matches!(run.kind, RunKind::OperatingPoint { .. }))
        .filter_map(|run| run.data.brake_force_mv.as_ref().filter(|v| !v.is_empty()))
        .map(|mv| (mv.iter().sum::<f64>() / mv.len() as f64 - b[0]) / b[1])
        .filter(|f| f.abs() > 0.0 && f.is_finite())
        .collect();
    let worst = forces.iter().copied().max_by(|x, y| e(*x).abs().total_cmp(&e(*y).abs()));
    let mu_se = mu_relative_se.filter(|v| v.is_finite() && *v > 0.0).unwrap_or(0.0);
    let (lo, hi) = loads.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &l| (a.0.min(l), a.1.max(l)));
    let head = format!(
        "mV = {:.2} + {:.3}·F through {n} calibration means ({lo:.2}–{hi:.2} N); a parabola through them bends by \
         {:+.4} ± {se_c:.4} mV/N² (t = {:.2}; a mean's noise {s:.3} mV, within the runs and about the parabola)",
        b[0],
        b[1],
        q[2],
        q[2] / se_c
    );
    let mut check = ChannelCheck::new(name, ids, q[2].abs(), se_c, o.force_linearity_ratio, String::new());
    check.detail = match worst {
        Some(f) => {
            // The consequence: a bend that moves μ by less than μ's own
            // uncertainty at every operating force changes nothing.
            let matters = e(f).abs() > mu_se;
            check.flagged &= matters;
            format!(
                "{head}, which reads μ {:+.3} % ± {:.3} % off at the operating force where it matters most \
                 ({f:.2} N of {} runs' mean forces), against μ's own relative uncertainty {:.3} %{} (a sensor that \
                 is not linear makes μ_obs depend on the force level)",
                100.0 * e(f),
                100.0 * se_e(f),
                forces.len(),
                100.0 * mu_se,
                if matters { "" } else { ": of no consequence" }
            )
        }
        None => format!("{head}; no operating point's force to judge it at"),
    };
    check
}
