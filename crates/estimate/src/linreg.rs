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
    let n = x.len();
    let p = x.first().map_or(0, Vec::len);
    if n <= p {
        return Err(EstimateError::TooFewSamples {
            context: context.into(),
            got: n,
            need: p + 1,
            rule: "need more rows than regressors",
        });
    }
    // Scaling each column to unit RMS keeps the normal equations well conditioned.
    let scale: Vec<f64> = (0..p)
        .map(|j| {
            let s = (x.iter().map(|r| r[j] * r[j]).sum::<f64>() / n as f64).sqrt();
            if s > 0.0 { s } else { 1.0 }
        })
        .collect();
    let xs = Mat::<f64>::from_fn(n, p, |i, j| x[i][j] / scale[j]);
    let ym = Mat::<f64>::from_fn(n, 1, |i, _| y[i]);
    let xtx = xs.transpose() * &xs;
    let xty = xs.transpose() * &ym;
    let singular = || EstimateError::Singular {
        context: context.into(),
        rule: "a regressor is constant zero or a combination of the others",
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
