//! The fit report (what MATLAB's identification toolbox prints): standard
//! errors from σ²(JᵀJ)⁻¹, the correlation matrix with non-separable pairs,
//! fit %, AIC/BIC, residual whiteness (autocorrelation, Ljung–Box).

use crate::lsq::{IterationRecord, LsqSolution};
use faer::Mat;
use serde::{Deserialize, Serialize};

/// Pairs with |ρ| above this are flagged "not separately identifiable".
pub const CORRELATION_FLAG: f64 = 0.9;

/// Whether the data determine a parameter on its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Identifiability {
    /// Estimated, no |ρ| > 0.9 with another estimated parameter.
    Yes,
    /// Estimated, but strongly correlated with another parameter (named).
    Correlated { with: Vec<String> },
    /// Held at its initial/calibrated value; the reason says why.
    Fixed { reason: String },
}

impl Identifiability {
    /// Short flag for the CSV table.
    pub fn flag(&self) -> String {
        match self {
            Identifiability::Yes => "yes".into(),
            Identifiability::Correlated { with } => format!("correlated with {}", with.join(" ")),
            Identifiability::Fixed { reason } => format!("fixed: {reason}"),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamEstimate {
    pub name: String,
    pub unit: String,
    pub initial: f64,
    pub estimate: f64,
    /// Standard error (delta method through the log transform); None when fixed.
    pub stderr: Option<f64>,
    pub identifiable: Identifiability,
}

/// Residual whiteness over lags 1..=max_lag, pooled over segments (runs × channels).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Whiteness {
    pub max_lag: usize,
    /// Autocorrelation of the residuals at lags 1..=max_lag.
    pub autocorrelation: Vec<f64>,
    /// 99 % band ±2.58/√N of a white sequence.
    pub bound: f64,
    pub fraction_outside: f64,
    /// Ljung–Box Q = N(N+2) Σ ρ_k²/(N−k).
    pub ljung_box_q: f64,
    /// 99 % critical value of χ²(max_lag) (Wilson–Hilferty).
    pub ljung_box_critical_99: f64,
}

/// Covariance summary of a least-squares solution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Covariance {
    /// σ² = SSR/(m − p).
    pub sigma2: f64,
    /// Standard errors of the natural parameters x (delta method).
    pub stderr: Vec<f64>,
    /// Correlation matrix (invariant to the log transform).
    pub correlation: Vec<Vec<f64>>,
    /// False when JᵀJ was not positive definite (then stderr are infinite).
    pub regular: bool,
}

/// σ²(JᵀJ)⁻¹ in θ, mapped to x by dx/dθ; correlations from the same matrix.
pub fn covariance(sol: &LsqSolution) -> Covariance {
    let m = sol.residuals.len();
    let p = sol.theta.len();
    let sigma2 = sol.ssr / (m.saturating_sub(p).max(1)) as f64;
    let jtj: Mat<f64> = sol.jacobian.transpose() * &sol.jacobian;
    match crate::linear::spd_inverse(&jtj) {
        Some(inv) => {
            let stderr = (0..p)
                .map(|j| (sigma2 * inv[(j, j)]).sqrt() * sol.transforms[j].dx_dtheta(sol.theta[j]).abs())
                .collect();
            let correlation =
                (0..p).map(|i| (0..p).map(|j| inv[(i, j)] / (inv[(i, i)] * inv[(j, j)]).sqrt()).collect()).collect();
            Covariance { sigma2, stderr, correlation, regular: true }
        }
        None => Covariance {
            sigma2,
            stderr: vec![f64::INFINITY; p],
            correlation: (0..p).map(|i| (0..p).map(|j| if i == j { 1.0 } else { f64::NAN }).collect()).collect(),
            regular: false,
        },
    }
}

/// Pairs (i, j), i < j, with |ρ| > CORRELATION_FLAG, in index order.
pub fn flagged_pairs(correlation: &[Vec<f64>]) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::new();
    for (i, row) in correlation.iter().enumerate() {
        for (j, &r) in row.iter().enumerate().skip(i + 1) {
            if !r.is_finite() || r.abs() > CORRELATION_FLAG {
                out.push((i, j, r));
            }
        }
    }
    out
}

/// ‖y − ŷ‖ / ‖y − ȳ‖ (normalised RMS error; 0 is perfect, 1 is "the mean").
pub fn nrmse(y: &[f64], yhat: &[f64]) -> f64 {
    let n = y.len().max(1) as f64;
    let mean = y.iter().sum::<f64>() / n;
    let num: f64 = y.iter().zip(yhat).map(|(a, b)| (a - b).powi(2)).sum();
    let den: f64 = y.iter().map(|a| (a - mean).powi(2)).sum();
    (num / den).sqrt()
}

/// Fit in simulation, % = 100·(1 − ‖y − ŷ‖/‖y − ȳ‖) (MATLAB's `compare`).
pub fn fit_percent(y: &[f64], yhat: &[f64]) -> f64 {
    100.0 * (1.0 - nrmse(y, yhat))
}

/// Gaussian likelihood with the ML variance SSR/n: −2 ln L = n(ln(2π·SSR/n) + 1).
/// `k` counts every estimated quantity (parameters + the noise variance).
pub fn aic_bic(ssr: f64, n: usize, k: usize) -> (f64, f64) {
    let nf = n as f64;
    let m2ll = nf * ((2.0 * std::f64::consts::PI * ssr / nf).ln() + 1.0);
    (m2ll + 2.0 * k as f64, m2ll + k as f64 * nf.ln())
}

/// Whiteness of residuals given as segments (each a contiguous time series);
/// lags never cross a segment boundary.
pub fn whiteness(segments: &[&[f64]], max_lag: usize) -> Whiteness {
    let n: usize = segments.iter().map(|s| s.len()).sum();
    let c0: f64 = segments.iter().flat_map(|s| s.iter()).map(|e| e * e).sum();
    let autocorrelation: Vec<f64> = (1..=max_lag)
        .map(|k| {
            let ck: f64 = segments
                .iter()
                .filter(|s| s.len() > k)
                .map(|s| (0..s.len() - k).map(|t| s[t] * s[t + k]).sum::<f64>())
                .sum();
            if c0 > 0.0 { ck / c0 } else { 0.0 }
        })
        .collect();
    let nf = n as f64;
    let bound = 2.58 / nf.sqrt();
    let outside = autocorrelation.iter().filter(|r| r.abs() > bound).count();
    let ljung_box_q =
        nf * (nf + 2.0) * autocorrelation.iter().enumerate().map(|(i, r)| r * r / (nf - (i + 1) as f64)).sum::<f64>();
    let h = max_lag as f64;
    let z99 = 2.326_347_874;
    let crit = h * (1.0 - 2.0 / (9.0 * h) + z99 * (2.0 / (9.0 * h)).sqrt()).powi(3);
    Whiteness {
        max_lag,
        autocorrelation,
        bound,
        fraction_outside: if max_lag > 0 { outside as f64 / max_lag as f64 } else { 0.0 },
        ljung_box_q,
        ljung_box_critical_99: crit,
    }
}

/// Fit of one run (estimation or held out).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunFit {
    pub run: String,
    /// True when the run was used for estimation, false when held out.
    pub used: bool,
    /// Per channel name, fit % and NRMSE.
    pub channels: Vec<ChannelFit>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelFit {
    pub channel: String,
    pub fit_percent: f64,
    pub nrmse: f64,
}

/// Everything a reader needs to judge an identification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    pub params: Vec<ParamEstimate>,
    /// Names of the estimated parameters, in `correlation` order.
    pub estimated: Vec<String>,
    pub correlation: Vec<Vec<f64>>,
    /// (a, b, ρ) with |ρ| > 0.9: "not separately identifiable".
    pub flagged_pairs: Vec<(String, String, f64)>,
    pub n_residuals: usize,
    pub ssr: f64,
    pub sigma2: f64,
    pub aic: f64,
    pub bic: f64,
    pub whiteness: Whiteness,
    pub converged: bool,
    pub iterations: usize,
    pub stop_reason: String,
    pub history: Vec<IterationRecord>,
    /// Per run, in campaign order: used or held out, fit % and NRMSE.
    pub runs: Vec<RunFit>,
}
