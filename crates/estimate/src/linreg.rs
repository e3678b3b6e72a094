//! Ordinary linear least squares with standard errors (σ²(XᵀX)⁻¹, σ² = SSR/(n − p)),
//! on column-scaled normal equations solved by Cholesky (faer).

use crate::EstimateError;
use faer::Mat;
use faer::linalg::solvers::{DenseSolveCore, Solve};

#[derive(Debug, Clone, PartialEq)]
pub struct OlsFit {
    pub beta: Vec<f64>,
    pub stderr: Vec<f64>,
    pub ssr: f64,
}

/// Fits y ≈ X β; `x` is row-major (n rows of p). `context` names the regression in errors.
pub fn ols(x: &[Vec<f64>], y: &[f64], context: &str) -> Result<OlsFit, EstimateError> {
    ols_eiv(x, y, &vec![0.0; x.first().map_or(0, Vec::len)], context)
}

/// Least squares corrected for known errors in the regressors (errors in
/// variables, "corrected least squares"): a regressor measured with
/// independent zero-mean error of variance s² inflates E[XᵀX] by n·s² on its
/// diagonal, which attenuates its coefficient; subtracting it removes the bias.
/// `noise_var[j]` is that variance for column j (0 for exact regressors).
pub fn ols_eiv(x: &[Vec<f64>], y: &[f64], noise_var: &[f64], context: &str) -> Result<OlsFit, EstimateError> {
    let (n, p, scale) = shape_and_scale(x, true, context)?;
    let xs = Mat::<f64>::from_fn(n, p, |i, j| x[i][j] / scale[j]);
    let ym = Mat::<f64>::from_fn(n, 1, |i, _| y[i]);
    let mut xtx = xs.transpose() * &xs;
    for j in 0..p {
        xtx[(j, j)] -= n as f64 * noise_var[j] / (scale[j] * scale[j]);
    }
    let xty = xs.transpose() * &ym;
    let singular = || EstimateError::Singular {
        context: context.into(),
        rule: "a regressor is constant zero or a combination of the others (or no larger than its known noise)",
    };
    let llt = xtx.llt(faer::Side::Lower).map_err(|_| singular())?;
    let mut b = xty.clone();
    llt.solve_in_place(b.as_mut());
    let inv = llt.inverse();
    let beta: Vec<f64> = (0..p).map(|j| b[(j, 0)] / scale[j]).collect();
    let ssr: f64 = x
        .iter()
        .zip(y)
        .map(|(r, yi)| {
            let f: f64 = r.iter().zip(&beta).map(|(a, c)| a * c).sum();
            (yi - f).powi(2)
        })
        .sum();
    let sigma2 = ssr / (n - p) as f64;
    let stderr = (0..p).map(|j| (sigma2 * inv[(j, j)]).sqrt() / scale[j]).collect();
    if beta.iter().any(|v| !v.is_finite()) {
        return Err(singular());
    }
    Ok(OlsFit { beta, stderr, ssr })
}

/// Instrumental-variable estimate β = (ZᵀX)⁻¹ Zᵀy for regressors measured with
/// noise: each instrument column correlates with the true regressor but not
/// with its noise. Standard errors σ²·(ZᵀX)⁻¹ ZᵀZ (XᵀZ)⁻¹, σ² = SSR/(n − p).
pub fn iv(x: &[Vec<f64>], z: &[Vec<f64>], y: &[f64], context: &str) -> Result<OlsFit, EstimateError> {
    let (n, p, scale) = shape_and_scale(x, z.len() == x.len(), context)?;
    let xs = Mat::<f64>::from_fn(n, p, |i, j| x[i][j] / scale[j]);
    let zs = Mat::<f64>::from_fn(n, p, |i, j| z[i][j] / scale[j]);
    let ym = Mat::<f64>::from_fn(n, 1, |i, _| y[i]);
    let ztx = zs.transpose() * &xs;
    let singular = || EstimateError::Singular {
        context: context.into(),
        rule: "an instrument is uncorrelated with its regressor, or regressors are collinear",
    };
    let lu = ztx.partial_piv_lu();
    let inv = lu.inverse();
    if (0..p).any(|i| (0..p).any(|j| !inv[(i, j)].is_finite())) {
        return Err(singular());
    }
    let zty = zs.transpose() * &ym;
    let b = &inv * &zty;
    let beta: Vec<f64> = (0..p).map(|j| b[(j, 0)] / scale[j]).collect();
    let ssr: f64 = x
        .iter()
        .zip(y)
        .map(|(r, yi)| {
            let f: f64 = r.iter().zip(&beta).map(|(a, c)| a * c).sum();
            (yi - f).powi(2)
        })
        .sum();
    let sigma2 = ssr / (n - p) as f64;
    let ztz = zs.transpose() * &zs;
    let cov = &inv * &ztz * inv.transpose();
    let stderr = (0..p).map(|j| (sigma2 * cov[(j, j)]).sqrt() / scale[j]).collect();
    if beta.iter().any(|v| !v.is_finite()) {
        return Err(singular());
    }
    Ok(OlsFit { beta, stderr, ssr })
}

/// Rows n, regressors p (refused unless n > p and `rows_match`), and each
/// column's RMS: scaling columns to unit RMS keeps the normal equations well
/// conditioned.
fn shape_and_scale(x: &[Vec<f64>], rows_match: bool, context: &str) -> Result<(usize, usize, Vec<f64>), EstimateError> {
    let n = x.len();
    let p = x.first().map_or(0, Vec::len);
    if n <= p || !rows_match {
        return Err(EstimateError::TooFewSamples {
            context: context.into(),
            got: n,
            need: p + 1,
            rule: "need more rows than regressors",
        });
    }
    let scale = (0..p)
        .map(|j| {
            let s = (x.iter().map(|r| r[j] * r[j]).sum::<f64>() / n as f64).sqrt();
            if s > 0.0 { s } else { 1.0 }
        })
        .collect();
    Ok((n, p, scale))
}
