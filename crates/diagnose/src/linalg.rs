//! Small dense least squares: normal equations solved by Cholesky, with the
//! inverse for parameter covariances. The systems here have at most a few
//! dozen unknowns (shared parameters plus one phase per run), so a hand
//! written factorisation is simpler than a dependency and deterministic.

/// Accumulates JᵀJ and Jᵀr for a least-squares problem with `n` unknowns.
#[derive(Debug, Clone)]
pub struct Normal {
    pub n: usize,
    /// Row-major n×n.
    pub ata: Vec<f64>,
    pub atb: Vec<f64>,
}

impl Normal {
    pub fn new(n: usize) -> Self {
        Normal { n, ata: vec![0.0; n * n], atb: vec![0.0; n] }
    }

    /// Adds one residual row given by its non-zero entries `(column, value)` and target `y`.
    pub fn add_sparse(&mut self, row: &[(usize, f64)], y: f64) {
        for &(i, vi) in row {
            self.atb[i] += vi * y;
            for &(j, vj) in row {
                self.ata[i * self.n + j] += vi * vj;
            }
        }
    }

    /// Solves (JᵀJ) x = Jᵀy; `None` when the matrix is not positive definite
    /// (an unidentifiable parameter), which callers report as data.
    pub fn solve(&self) -> Option<Vec<f64>> {
        let l = cholesky(&self.ata, self.n)?;
        Some(cho_solve(&l, self.n, &self.atb))
    }

    /// (JᵀJ)⁻¹, for covariances σ²(JᵀJ)⁻¹.
    pub fn inverse(&self) -> Option<Vec<f64>> {
        let l = cholesky(&self.ata, self.n)?;
        let mut inv = vec![0.0; self.n * self.n];
        for c in 0..self.n {
            let mut e = vec![0.0; self.n];
            e[c] = 1.0;
            let x = cho_solve(&l, self.n, &e);
            for r in 0..self.n {
                inv[r * self.n + c] = x[r];
            }
        }
        Some(inv)
    }
}

/// Lower Cholesky factor of a symmetric positive definite row-major matrix.
/// A pivot below 1e-13 of the diagonal scale counts as singular.
fn cholesky(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let scale = (0..n).map(|i| a[i * n + i].abs()).fold(0.0_f64, f64::max).max(f64::MIN_POSITIVE);
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if s <= 1e-13 * scale || !s.is_finite() {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    Some(l)
}

fn cho_solve(l: &[f64], n: usize, b: &[f64]) -> Vec<f64> {
    let mut y = b.to_vec();
    for i in 0..n {
        for k in 0..i {
            y[i] -= l[i * n + k] * y[k];
        }
        y[i] /= l[i * n + i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            y[i] -= l[k * n + i] * y[k];
        }
        y[i] /= l[i * n + i];
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_line_and_its_covariance() {
        // y = 2 + 3x exactly: the solution is exact and (JᵀJ)⁻¹ matches the closed form.
        let mut ne = Normal::new(2);
        let xs = [0.0, 1.0, 2.0, 3.0];
        for &x in &xs {
            ne.add_sparse(&[(0, 1.0), (1, x)], 2.0 + 3.0 * x);
        }
        let p = ne.solve().unwrap();
        assert!((p[0] - 2.0).abs() < 1e-12 && (p[1] - 3.0).abs() < 1e-12);
        let inv = ne.inverse().unwrap();
        // Var(slope) / σ² = 1 / Σ(x − x̄)² = 1/5.
        assert!((inv[3] - 0.2).abs() < 1e-12);
    }

    #[test]
    fn singular_is_none() {
        let mut ne = Normal::new(2);
        ne.add_sparse(&[(0, 1.0), (1, 1.0)], 1.0);
        ne.add_sparse(&[(0, 2.0), (1, 2.0)], 2.0);
        assert!(ne.solve().is_none());
    }
}
