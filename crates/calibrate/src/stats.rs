//! Small statistics the calibrations need: mean and spread, Student-t
//! quantiles (own regularised incomplete beta, no crate), and least-squares
//! lines through the origin and with an offset, with confidence intervals.

use crate::CalibrateError;
pub use rig_types::contract::LineFit;

/// Arithmetic mean; `None` for an empty slice.
pub fn mean(x: &[f64]) -> Option<f64> {
    if x.is_empty() { None } else { Some(x.iter().sum::<f64>() / x.len() as f64) }
}

/// Sample standard deviation (n − 1 in the denominator); `None` below two values.
pub fn sample_std(x: &[f64]) -> Option<f64> {
    if x.len() < 2 {
        return None;
    }
    let m = mean(x)?;
    Some((x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt())
}

/// ln Γ(x) for x > 0, Lanczos approximation (g = 7, 9 terms; |error| < 1e-13 here).
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection keeps the series in its accurate range.
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Continued fraction of the incomplete beta (modified Lentz; Numerical Recipes `betacf`).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..=300 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// Regularised incomplete beta I_x(a, b).
pub fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    // The continued fraction converges fast for x < (a+1)/(a+b+2); use the symmetry otherwise.
    if x < (a + 1.0) / (a + b + 2.0) { front * beta_cf(a, b, x) / a } else { 1.0 - front * beta_cf(b, a, 1.0 - x) / b }
}

/// Student-t cumulative distribution with `dof` degrees of freedom.
pub fn student_t_cdf(t: f64, dof: f64) -> f64 {
    let tail = 0.5 * incomplete_beta(dof / 2.0, 0.5, dof / (dof + t * t));
    if t >= 0.0 { 1.0 - tail } else { tail }
}

/// Quantile t_p of Student's t (e.g. p = 0.975 for a two-sided 95 % interval),
/// by bisection on the CDF (monotone, so bisection cannot fail to converge).
pub fn student_t_quantile(p: f64, dof: f64) -> Result<f64, CalibrateError> {
    if !(p > 0.0 && p < 1.0) || dof.is_nan() || dof <= 0.0 {
        return Err(CalibrateError::Domain(format!(
            "t quantile needs 0 < p < 1 and dof > 0 (got p = {p}, dof = {dof})"
        )));
    }
    if p < 0.5 {
        return Ok(-student_t_quantile(1.0 - p, dof)?);
    }
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    while student_t_cdf(hi, dof) < p {
        hi *= 2.0;
        if hi > 1e12 {
            return Err(CalibrateError::Domain(format!("t quantile p = {p} dof = {dof} out of range")));
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if student_t_cdf(mid, dof) < p { lo = mid } else { hi = mid }
    }
    Ok(0.5 * (lo + hi))
}

fn check_xy(x: &[f64], y: &[f64], min_n: usize, what: &str) -> Result<(), CalibrateError> {
    if x.len() != y.len() {
        return Err(CalibrateError::Domain(format!("{what}: x has {} values, y has {}", x.len(), y.len())));
    }
    if x.len() < min_n {
        return Err(CalibrateError::TooFewPoints { what: what.to_string(), need: min_n, got: x.len() });
    }
    if x.iter().chain(y).any(|v| !v.is_finite()) {
        return Err(CalibrateError::Domain(format!("{what}: non-finite value")));
    }
    Ok(())
}

/// y = b·x by least squares: b = Σxy/Σx², s² = Σr²/(n−1), se(b) = s/√Σx².
pub fn fit_through_origin(x: &[f64], y: &[f64], confidence: f64) -> Result<LineFit, CalibrateError> {
    check_xy(x, y, 2, "line fit through the origin")?;
    let sxx: f64 = x.iter().map(|v| v * v).sum();
    if sxx == 0.0 {
        return Err(CalibrateError::Domain("line fit through the origin: all x are zero".into()));
    }
    let b = x.iter().zip(y).map(|(a, c)| a * c).sum::<f64>() / sxx;
    let dof = x.len() - 1;
    let ss: f64 = x.iter().zip(y).map(|(a, c)| (c - b * a).powi(2)).sum();
    let s = (ss / dof as f64).sqrt();
    let se = s / sxx.sqrt();
    let t = student_t_quantile(0.5 + confidence / 2.0, dof as f64)?;
    Ok(LineFit {
        slope: b,
        slope_stderr: se,
        slope_ci: [b - t * se, b + t * se],
        intercept: 0.0,
        intercept_stderr: 0.0,
        intercept_ci: [0.0, 0.0],
        residual_std: s,
        dof,
        confidence,
        through_origin: true,
    })
}

/// y = a + b·x by ordinary least squares; se(b) = s/√Sxx, se(a) = s·√(1/n + x̄²/Sxx), n − 2 dof.
pub fn fit_with_offset(x: &[f64], y: &[f64], confidence: f64) -> Result<LineFit, CalibrateError> {
    check_xy(x, y, 3, "line fit with offset")?;
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    if sxx == 0.0 {
        return Err(CalibrateError::Domain("line fit with offset: all x are equal".into()));
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, c)| (a - mx) * (c - my)).sum();
    let b = sxy / sxx;
    let a = my - b * mx;
    let dof = x.len() - 2;
    let ss: f64 = x.iter().zip(y).map(|(u, v)| (v - a - b * u).powi(2)).sum();
    let s = (ss / dof as f64).sqrt();
    let (se_b, se_a) = (s / sxx.sqrt(), s * (1.0 / n + mx * mx / sxx).sqrt());
    let t = student_t_quantile(0.5 + confidence / 2.0, dof as f64)?;
    Ok(LineFit {
        slope: b,
        slope_stderr: se_b,
        slope_ci: [b - t * se_b, b + t * se_b],
        intercept: a,
        intercept_stderr: se_a,
        intercept_ci: [a - t * se_a, a + t * se_a],
        residual_std: s,
        dof,
        confidence,
        through_origin: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two-sided 95 % critical values t_{0.975,ν} from any printed t table.
    #[test]
    fn t_quantile_matches_tables() {
        for (dof, tab) in [(1.0, 12.706), (2.0, 4.303), (3.0, 3.182), (4.0, 2.776), (10.0, 2.228), (30.0, 2.042)] {
            let q = student_t_quantile(0.975, dof).unwrap();
            assert!((q - tab).abs() < 6e-4, "dof {dof}: {q} vs {tab}");
        }
        // One-sided 99.5 % for ν = 5 is 4.032; and symmetry.
        assert!((student_t_quantile(0.995, 5.0).unwrap() - 4.032).abs() < 6e-4);
        assert!((student_t_quantile(0.025, 4.0).unwrap() + 2.776).abs() < 6e-4);
    }

    #[test]
    fn t_cdf_for_one_dof_is_cauchy() {
        for t in [-3.0, -0.5, 0.0, 0.7, 5.0] {
            let cauchy = 0.5 + f64::atan(t) / std::f64::consts::PI;
            assert!((student_t_cdf(t, 1.0) - cauchy).abs() < 1e-12);
        }
    }

    #[test]
    fn exact_line_is_recovered_with_zero_error() {
        let x = [0.5, 1.0, 1.5, 2.0];
        let y: Vec<f64> = x.iter().map(|v| 0.27 * v).collect();
        let f = fit_through_origin(&x, &y, 0.95).unwrap();
        assert!((f.slope - 0.27).abs() < 1e-15 && f.slope_stderr < 1e-15);
        let y2: Vec<f64> = x.iter().map(|v| 3.0 + 214.0 * v).collect();
        let g = fit_with_offset(&x, &y2, 0.95).unwrap();
        assert!((g.slope - 214.0).abs() < 1e-12 && (g.intercept - 3.0).abs() < 1e-12);
    }

    /// Hand computation: x = 1,2,3, y = 1,3,2 → b = 0.5, a = 1, Σr² = 1.5,
    /// s = √1.5, se(b) = √1.5/√2, 95 % CI half-width = 12.706·se(b).
    #[test]
    fn offset_fit_errors_match_hand_computation() {
        let g = fit_with_offset(&[1.0, 2.0, 3.0], &[1.0, 3.0, 2.0], 0.95).unwrap();
        assert!((g.slope - 0.5).abs() < 1e-12 && (g.intercept - 1.0).abs() < 1e-12);
        let se = (1.5f64).sqrt() / 2f64.sqrt();
        assert!((g.slope_stderr - se).abs() < 1e-12);
        assert!((g.slope_ci[1] - 0.5 - 12.7062 * se).abs() < 1e-3);
        // se(a) = s·√(1/3 + 4/2)
        assert!((g.intercept_stderr - 1.5f64.sqrt() * (1.0 / 3.0 + 2.0f64).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn mean_and_std() {
        assert_eq!(mean(&[]), None);
        assert_eq!(sample_std(&[1.0]), None);
        assert!((sample_std(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]).unwrap() - 2.138_089_935).abs() < 1e-9);
    }
}
