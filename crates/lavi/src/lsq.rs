//! The study's one linear least-squares path (moved from rig_model, which does
//! no fitting): normal equations accumulated and solved by the workspace's
//! one solver ([`rig_estimate::linear::Normal`], faer's Cholesky), with
//! (XᵀX)⁻¹ for the covariance. The equation-of-motion
//! fit ([`crate::eom`]) and the residual signature ([`crate::signature`]) call
//! [`least_squares`]; nothing else here solves a linear system.

use rig_estimate::linear::Normal;

/// A least-squares solution of y ≈ X β.
#[derive(Debug, Clone, PartialEq)]
pub struct LeastSquares {
    pub coef: Vec<f64>,
    /// (XᵀX)⁻¹: times the residual variance, the covariance of `coef`.
    pub inverse: Vec<Vec<f64>>,
    /// Σ (y − X β)².
    pub sse: f64,
    pub points: usize,
}

impl LeastSquares {
    /// Residual variance s² = SSE / (n − p).
    pub fn residual_variance(&self) -> f64 {
        self.sse / (self.points.saturating_sub(self.coef.len())).max(1) as f64
    }

    /// Standard error of coefficient `j` (white-residual assumption).
    pub fn stderr(&self, j: usize) -> f64 {
        (self.residual_variance() * self.inverse[j][j]).max(0.0).sqrt()
    }
}

/// Least squares of `y` on the rows produced by `row(i)` for i in 0..y.len()
/// (each of the same length p). `None` when XᵀX is singular (the
/// workspace's one rule: [`rig_estimate::linear::Normal`]).
pub fn least_squares(y: &[f64], p: usize, row: impl Fn(usize) -> Vec<f64>) -> Option<LeastSquares> {
    let mut normal = Normal::new(p);
    for (i, yi) in y.iter().enumerate() {
        normal.add_row(&row(i), *yi);
    }
    let coef = normal.solve()?;
    let flat = normal.inverse()?;
    let inverse = flat.chunks(p).map(<[f64]>::to_vec).collect();
    let sse = sse(y, &coef, |i, x: &mut [f64]| x.copy_from_slice(&row(i)));
    Some(LeastSquares { coef, inverse, sse, points: y.len() })
}

/// The most columns [`sse`] takes (the study's fits have at most 6).
pub const MAX_COLUMNS: usize = 8;

/// Σ (y − X β)² of the rows `row(i, x)` writes into `x` (p = β's length), summed
/// in row order: what [`least_squares`] reports, for a caller that summed the
/// normal equations itself ([`Normal::from_row_major`]) and solved them.
pub fn sse(y: &[f64], coef: &[f64], row: impl Fn(usize, &mut [f64])) -> f64 {
    assert!(coef.len() <= MAX_COLUMNS, "at most {MAX_COLUMNS} columns");
    let mut x = [0.0; MAX_COLUMNS];
    let x = &mut x[..coef.len()];
    y.iter()
        .enumerate()
        .map(|(i, yi)| {
            row(i, x);
            let pred: f64 = x.iter().zip(coef).map(|(x, b)| x * b).sum();
            (yi - pred).powi(2)
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_recovered_with_its_textbook_stderr() {
        // y = 1 + 2x + e, e = ±0.1 alternating on x = 0..9: β exact up to the
        // alternating residual, whose projection on (1, x) is known.
        let y: Vec<f64> = (0..10).map(|i| 1.0 + 2.0 * i as f64 + if i % 2 == 0 { 0.1 } else { -0.1 }).collect();
        let f = least_squares(&y, 2, |i| vec![1.0, i as f64]).unwrap();
        // Slope = 2 + Σ(x − x̄)e / Σ(x − x̄)² (the normal equations of a line).
        let sxx = 82.5;
        let sxe: f64 = (0..10).map(|i| (i as f64 - 4.5) * if i % 2 == 0 { 0.1 } else { -0.1 }).sum();
        assert!((f.coef[1] - (2.0 + sxe / sxx)).abs() < 1e-12, "{f:?}");
        let s2 = f.sse / 8.0;
        assert!((f.stderr(1) - (s2 / sxx).sqrt()).abs() < 1e-12);
        // Collinear columns are refused.
        assert!(least_squares(&y, 2, |i| vec![i as f64, 2.0 * i as f64]).is_none());
    }
}
