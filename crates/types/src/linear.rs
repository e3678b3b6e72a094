//! The workspace's one linear least-squares solver (ARCHITECTURE.md, "one home
//! per idea"; a tidy test refuses a second). It lives in `rig-types`, the
//! crate every other depends on, so that calibration (which the estimation
//! depends on) solves here too. Symmetric positive definite
//! systems by faer's Cholesky ([`spd_solve`], [`spd_inverse`]), the normal
//! equations they come from ([`Normal`], accumulated row by row), ordinary
//! least squares with standard errors (σ²(XᵀX)⁻¹, σ² = SSR/(n − p)) on
//! column-scaled normal equations ([`ols`]), its errors-in-variables
//! correction ([`ols_eiv`]) and instrumental variables ([`iv`]). The
//! estimation's Levenberg–Marquardt steps and fit covariances, the
//! diagnosis' linear fits and calibration's refined extrema solve here
//! (`rig_estimate::linear` re-exports it).

use faer::Mat;
use faer::linalg::solvers::{DenseSolveCore, Solve};

/// Solves A x = b for a symmetric positive definite A (only its lower
/// triangle is read); `None` when A is not positive definite or the solution
/// is not finite.
pub fn spd_solve(a: &Mat<f64>, b: &[f64]) -> Option<Vec<f64>> {
    let llt = a.llt(faer::Side::Lower).ok()?;
    let mut rhs = Mat::<f64>::from_fn(b.len(), 1, |i, _| b[i]);
    llt.solve_in_place(rhs.as_mut());
    let x: Vec<f64> = (0..b.len()).map(|i| rhs[(i, 0)]).collect();
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// A⁻¹ of a symmetric positive definite A (covariances σ²(JᵀJ)⁻¹); `None`
/// when A is not positive definite.
pub fn spd_inverse(a: &Mat<f64>) -> Option<Mat<f64>> {
    a.llt(faer::Side::Lower).ok().map(|llt| llt.inverse())
}

/// Normal equations AᵀA x = Aᵀy of a least-squares problem with `n`
/// unknowns, accumulated one (sparse) row at a time. Solved by [`spd_solve`]
/// after a conditioning check: a Cholesky pivot below 1e-13 of the largest
/// diagonal entry counts as singular (an unidentifiable parameter, which
/// callers report as data, not as an error).
#[derive(Debug, Clone)]
pub struct Normal {
    pub n: usize,
    /// AᵀA, n × n.
    pub ata: Mat<f64>,
    pub atb: Vec<f64>,
}

impl Normal {
    pub fn new(n: usize) -> Self {
        Normal { n, ata: Mat::zeros(n, n), atb: vec![0.0; n] }
    }

    /// Normal equations already summed: AᵀA row-major (n × n) and Aᵀy.
    pub fn from_row_major(n: usize, ata: &[f64], atb: Vec<f64>) -> Self {
        Normal { n, ata: Mat::from_fn(n, n, |i, j| ata[i * n + j]), atb }
    }

    /// Adds one residual row given by its non-zero entries `(column, value)` and target `y`.
    pub fn add_sparse(&mut self, row: &[(usize, f64)], y: f64) {
        // Entry (i, j) lives at row i of column j's slice: the same products
        // added in the same order as `ata[(i, j)]`, without faer's per-entry
        // index arithmetic and checks (23 % of a battery campaign's CPU).
        for &(i, vi) in row {
            self.atb[i] += vi * y;
            for &(j, vj) in row {
                self.ata.col_as_slice_mut(j)[i] += vi * vj;
            }
        }
    }

    /// Adds one dense residual row `x` with target `y`.
    pub fn add_row(&mut self, x: &[f64], y: f64) {
        let row: Vec<(usize, f64)> = x.iter().copied().enumerate().collect();
        self.add_sparse(&row, y);
    }

    /// The Cholesky factor's pivots all above 1e-13 of the diagonal scale.
    fn regular(&self) -> bool {
        let n = self.n;
        let scale = (0..n).map(|i| self.ata[(i, i)].abs()).fold(0.0_f64, f64::max).max(f64::MIN_POSITIVE);
        let Ok(llt) = self.ata.llt(faer::Side::Lower) else { return false };
        let l = llt.L();
        (0..n).all(|i| {
            let d = l[(i, i)] * l[(i, i)];
            d.is_finite() && d > 1e-13 * scale
        })
    }

    /// Solves (AᵀA) x = Aᵀy; `None` when the matrix is singular (see the type's docs).
    pub fn solve(&self) -> Option<Vec<f64>> {
        if !self.regular() {
            return None;
        }
        spd_solve(&self.ata, &self.atb)
    }

    /// (AᵀA)⁻¹ row-major, for covariances σ²(AᵀA)⁻¹; `None` when singular.
    pub fn inverse(&self) -> Option<Vec<f64>> {
        if !self.regular() {
            return None;
        }
        let inv = spd_inverse(&self.ata)?;
        Some((0..self.n * self.n).map(|k| inv[(k / self.n, k % self.n)]).collect())
    }
}

/// The normal equations of rows that each touch the `K` shared columns
/// (0..K) and one block of `W` columns among `blocks` (block b's columns are
/// K + b·W .. K + (b + 1)·W), e.g. shared parameters and one phase per run:
/// AᵀA is an arrow, dense on the shared columns, block diagonal elsewhere.
/// [`ArrowNormal::add`] accumulates each entry's products in the same order
/// as [`Normal::add_sparse`] of the same rows (an entry of AᵀA and its mirror
/// are the same products, kept once), so [`ArrowNormal::into_normal`] is the
/// same [`Normal`] to the last bit, without a dense update per row; `K` and
/// `W` are constants, so a row's products are unrolled.
#[derive(Debug, Clone)]
pub struct ArrowNormal<const K: usize, const W: usize> {
    /// Upper triangle used.
    shared: [[f64; K]; K],
    shared_b: [f64; K],
    blocks: Vec<ArrowBlock<K, W>>,
}

/// One block's sums: its columns against the shared ones, against each
/// other (upper triangle used), and against the target.
#[derive(Debug, Clone, Copy)]
struct ArrowBlock<const K: usize, const W: usize> {
    cross: [[f64; K]; W],
    inner: [[f64; W]; W],
    b: [f64; W],
}

impl<const K: usize, const W: usize> ArrowNormal<K, W> {
    pub fn new(blocks: usize) -> Self {
        let empty = ArrowBlock { cross: [[0.0; K]; W], inner: [[0.0; W]; W], b: [0.0; W] };
        ArrowNormal { shared: [[0.0; K]; K], shared_b: [0.0; K], blocks: vec![empty; blocks] }
    }

    /// Adds one residual row: `shared` on the shared columns, `values` on
    /// block `block`'s, target `y`.
    #[inline]
    // Indices, as the entries (a, b) of AᵀA they accumulate.
    #[allow(clippy::needless_range_loop)]
    pub fn add(&mut self, shared: &[f64; K], block: usize, values: &[f64; W], y: f64) {
        for a in 0..K {
            self.shared_b[a] += shared[a] * y;
            for b in a..K {
                self.shared[a][b] += shared[a] * shared[b];
            }
        }
        if W == 0 {
            return;
        }
        let blk = &mut self.blocks[block];
        for q in 0..W {
            blk.b[q] += values[q] * y;
            for a in 0..K {
                blk.cross[q][a] += shared[a] * values[q];
            }
            for p in q..W {
                blk.inner[q][p] += values[q] * values[p];
            }
        }
    }

    /// The accumulated normal equations, K + blocks·W unknowns.
    pub fn into_normal(self) -> Normal {
        let n = K + self.blocks.len() * W;
        let mut ata = vec![0.0; n * n];
        for a in 0..K {
            for b in a..K {
                ata[a * n + b] = self.shared[a][b];
                ata[b * n + a] = self.shared[a][b];
            }
        }
        let mut atb = self.shared_b.to_vec();
        for (k, blk) in self.blocks.iter().enumerate() {
            for q in 0..W {
                let j = K + k * W + q;
                for a in 0..K {
                    ata[a * n + j] = blk.cross[q][a];
                    ata[j * n + a] = blk.cross[q][a];
                }
                for p in q..W {
                    let i = K + k * W + p;
                    ata[j * n + i] = blk.inner[q][p];
                    ata[i * n + j] = blk.inner[q][p];
                }
            }
            atb.extend_from_slice(&blk.b);
        }
        Normal::from_row_major(n, &ata, atb)
    }
}

/// A regression the data cannot determine: which one (`context`) and why (`rule`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinearError {
    /// The normal equations are singular (e.g. a regressor that never varies).
    Singular { context: String, rule: &'static str },
    /// Fewer rows than the regression needs.
    TooFewRows { context: String, got: usize, need: usize, rule: &'static str },
}

impl std::fmt::Display for LinearError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinearError::Singular { context, rule } => write!(f, "{context}: normal equations are singular ({rule})"),
            LinearError::TooFewRows { context, got, need, rule } => {
                write!(f, "{context}: {got} samples, need {need} ({rule})")
            }
        }
    }
}

impl std::error::Error for LinearError {}

#[derive(Debug, Clone, PartialEq)]
pub struct OlsFit {
    pub beta: Vec<f64>,
    pub stderr: Vec<f64>,
    pub ssr: f64,
}

/// Fits y ≈ X β; `x` is row-major (n rows of p). `context` names the regression in errors.
pub fn ols(x: &[Vec<f64>], y: &[f64], context: &str) -> Result<OlsFit, LinearError> {
    ols_eiv(x, y, &vec![0.0; x.first().map_or(0, Vec::len)], context)
}

/// Least squares corrected for known errors in the regressors (errors in
/// variables, "corrected least squares"): a regressor measured with
/// independent zero-mean error of variance s² inflates E[XᵀX] by n·s² on its
/// diagonal, which attenuates its coefficient; subtracting it removes the bias.
/// `noise_var[j]` is that variance for column j (0 for exact regressors).
pub fn ols_eiv(x: &[Vec<f64>], y: &[f64], noise_var: &[f64], context: &str) -> Result<OlsFit, LinearError> {
    let (n, p, scale) = shape_and_scale(x, true, context)?;
    let xs = Mat::<f64>::from_fn(n, p, |i, j| x[i][j] / scale[j]);
    let ym = Mat::<f64>::from_fn(n, 1, |i, _| y[i]);
    let mut xtx = xs.transpose() * &xs;
    for j in 0..p {
        xtx[(j, j)] -= n as f64 * noise_var[j] / (scale[j] * scale[j]);
    }
    let xty = xs.transpose() * &ym;
    let singular = || LinearError::Singular {
        context: context.into(),
        rule: "a regressor is constant zero or a combination of the others (or no larger than its known noise)",
    };
    let llt = xtx.llt(faer::Side::Lower).map_err(|_| singular())?;
    let mut b = xty.clone();
    llt.solve_in_place(b.as_mut());
    let inv = llt.inverse();
    let beta: Vec<f64> = (0..p).map(|j| b[(j, 0)] / scale[j]).collect();
    let ssr = residual_sum_of_squares(x, y, &beta);
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
pub fn iv(x: &[Vec<f64>], z: &[Vec<f64>], y: &[f64], context: &str) -> Result<OlsFit, LinearError> {
    let (n, p, scale) = shape_and_scale(x, z.len() == x.len(), context)?;
    let xs = Mat::<f64>::from_fn(n, p, |i, j| x[i][j] / scale[j]);
    let zs = Mat::<f64>::from_fn(n, p, |i, j| z[i][j] / scale[j]);
    let ym = Mat::<f64>::from_fn(n, 1, |i, _| y[i]);
    let ztx = zs.transpose() * &xs;
    let singular = || LinearError::Singular {
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
    let ssr = residual_sum_of_squares(x, y, &beta);
    let sigma2 = ssr / (n - p) as f64;
    let ztz = zs.transpose() * &zs;
    let cov = &inv * &ztz * inv.transpose();
    let stderr = (0..p).map(|j| (sigma2 * cov[(j, j)]).sqrt() / scale[j]).collect();
    if beta.iter().any(|v| !v.is_finite()) {
        return Err(singular());
    }
    Ok(OlsFit { beta, stderr, ssr })
}

/// Σ (y − X β)² over the rows of `x`.
fn residual_sum_of_squares(x: &[Vec<f64>], y: &[f64], beta: &[f64]) -> f64 {
    x.iter()
        .zip(y)
        .map(|(r, yi)| {
            let f: f64 = r.iter().zip(beta).map(|(a, c)| a * c).sum();
            (yi - f).powi(2)
        })
        .sum()
}

/// Rows n, regressors p (refused unless n > p and `rows_match`), and each
/// column's RMS: scaling columns to unit RMS keeps the normal equations well
/// conditioned.
fn shape_and_scale(x: &[Vec<f64>], rows_match: bool, context: &str) -> Result<(usize, usize, Vec<f64>), LinearError> {
    let n = x.len();
    let p = x.first().map_or(0, Vec::len);
    if n <= p || !rows_match {
        return Err(LinearError::TooFewRows {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_equations_recover_a_line_and_its_covariance() {
        // y = 2 + 3x exactly: the solution is exact and (AᵀA)⁻¹ matches the closed form.
        let mut ne = Normal::new(2);
        for x in [0.0, 1.0, 2.0, 3.0] {
            ne.add_row(&[1.0, x], 2.0 + 3.0 * x);
        }
        let p = ne.solve().unwrap();
        assert!((p[0] - 2.0).abs() < 1e-12 && (p[1] - 3.0).abs() < 1e-12);
        let inv = ne.inverse().unwrap();
        // Var(slope) / σ² = 1 / Σ(x − x̄)² = 1/5.
        assert!((inv[3] - 0.2).abs() < 1e-12);
        let fit =
            ols(&[vec![1.0, 0.0], vec![1.0, 1.0], vec![1.0, 2.0], vec![1.0, 3.5]], &[2.0, 5.0, 8.0, 12.5], "line")
                .unwrap();
        assert!((fit.beta[0] - 2.0).abs() < 1e-12 && (fit.beta[1] - 3.0).abs() < 1e-12);
    }

    #[test]
    fn singular_normal_equations_are_none() {
        let mut ne = Normal::new(2);
        ne.add_sparse(&[(0, 1.0), (1, 1.0)], 1.0);
        ne.add_sparse(&[(0, 2.0), (1, 2.0)], 2.0);
        assert!(ne.solve().is_none());
        assert!(ne.inverse().is_none());
        let mut near = Normal::new(2);
        near.add_row(&[1.0, 1.0], 1.0);
        near.add_row(&[1.0, 1.0 + 1e-9], 1.0);
        assert!(near.solve().is_none(), "a pivot of 1e-18 of the scale is singular");
    }

    /// The arrow accumulator is `add_sparse` of the same rows to the last bit
    /// (entries in any order within a row, empty blocks left zero).
    #[test]
    fn arrow_normal_equals_add_sparse_bit_for_bit() {
        let (k, width, blocks) = (3, 2, 4);
        let n = k + width * blocks;
        let mut dense = Normal::new(n);
        let mut arrow = ArrowNormal::<3, 2>::new(blocks);
        let mut x = 0.37_f64;
        let mut next = || {
            x = (x * 3.9 * (1.0 - x)).fract();
            x - 0.41
        };
        for i in 0..500 {
            let block = [0, 2, 3][i % 3];
            let shared: [f64; 3] = std::array::from_fn(|_| next() * 1e3);
            let values: [f64; 2] = std::array::from_fn(|_| next() / 7.0);
            let y = next();
            let mut row: Vec<(usize, f64)> =
                values.iter().enumerate().map(|(q, &v)| (k + block * width + q, v)).collect();
            row.extend(shared.iter().copied().enumerate());
            dense.add_sparse(&row, y);
            arrow.add(&shared, block, &values, y);
        }
        let arrow = arrow.into_normal();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&arrow.atb), bits(&dense.atb));
        for j in 0..n {
            assert_eq!(bits(arrow.ata.col_as_slice(j)), bits(dense.ata.col_as_slice(j)), "column {j}");
        }
        let mut only_shared = ArrowNormal::<2, 0>::new(0);
        let mut d2 = Normal::new(2);
        for i in 0..50 {
            let r = [(0, next()), (1, next() * i as f64)];
            let y = next();
            only_shared.add(&[r[0].1, r[1].1], 0, &[], y);
            d2.add_sparse(&r, y);
        }
        let o = only_shared.into_normal();
        assert_eq!(bits(&o.atb), bits(&d2.atb));
        assert_eq!(bits(o.ata.col_as_slice(1)), bits(d2.ata.col_as_slice(1)));
    }

    #[test]
    fn spd_solve_refuses_an_indefinite_matrix() {
        let a = Mat::<f64>::from_fn(2, 2, |i, j| if i == j { 1.0 } else { 2.0 });
        assert!(spd_solve(&a, &[1.0, 1.0]).is_none());
        let b = Mat::<f64>::from_fn(2, 2, |i, j| if i == j { 2.0 } else { 1.0 });
        let x = spd_solve(&b, &[3.0, 3.0]).unwrap();
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
    }
}
