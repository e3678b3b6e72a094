//! The least-squares core and the fit-report statistics on a damped oscillator
//! simulated in the test (closed form), with seeded noise.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rig_estimate::argmin_adapter::gauss_newton_ls;
use rig_estimate::fit_stats::{aic_bic, covariance, fit_percent, flagged_pairs, whiteness};
use rig_estimate::{
    EstimateError, LsqProblem, SolverOptions, Transform, levenberg_marquardt, levenberg_marquardt_minimum,
};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Free decay x(t) = A e^{−ζωt} cos(ω√(1−ζ²) t); parameters (A, ω, ζ).
fn decay(p: &[f64], t: f64) -> f64 {
    let (a, w, z) = (p[0], p[1], p[2]);
    a * (-z * w * t).exp() * (w * (1.0 - z * z).sqrt() * t).cos()
}

struct Decay {
    t: Vec<f64>,
    y: Vec<f64>,
}

impl LsqProblem for Decay {
    fn residuals(&self, p: &[f64]) -> Result<Vec<f64>, EstimateError> {
        Ok(self.t.iter().zip(&self.y).map(|(&t, &y)| y - decay(p, t)).collect())
    }
}

const TRUE: [f64; 3] = [1.1, 3.05, 0.098];
const NOISE: f64 = 0.02;

fn data(seed: u64) -> Decay {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = Normal::new(0.0, NOISE).unwrap();
    let t: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
    let y = t.iter().map(|&t| decay(&TRUE, t) + n.sample(&mut rng)).collect();
    Decay { t, y }
}

const LOG: [Transform; 3] = [Transform::Log; 3];
const X0: [f64; 3] = [0.8, 2.6, 0.15];

#[test]
fn lm_recovers_the_oscillator_within_its_standard_errors() {
    let prob = data(1);
    let sol = levenberg_marquardt(&prob, &X0, &LOG, &SolverOptions::default()).unwrap();
    assert!(sol.converged, "{}", sol.stop_reason);
    let cov = covariance(&sol);
    for (j, truth) in TRUE.iter().enumerate() {
        let err = (sol.x[j] - truth).abs();
        assert!(err < 4.0 * cov.stderr[j], "param {j}: error {err} vs stderr {}", cov.stderr[j]);
        // Recovery within 2 % (ω, A) and 5 % (ζ) at 2 % noise on 1000 samples.
        let tol = if j == 2 { 0.05 } else { 0.02 };
        assert!(err / truth < tol, "param {j}: {} vs {truth}", sol.x[j]);
    }
    // σ² estimates the noise variance.
    assert!((cov.sigma2.sqrt() / NOISE - 1.0).abs() < 0.1, "sigma {}", cov.sigma2.sqrt());
    // The misfit history starts at the initial point and never increases.
    assert!(sol.history.len() >= 3);
    assert!(sol.history.windows(2).all(|w| w[1].ssr <= w[0].ssr));
    assert!(fit_percent(&prob.y, &prob.y.iter().zip(&sol.residuals).map(|(y, r)| y - r).collect::<Vec<_>>()) > 90.0);
}

/// The standard errors are calibrated: over 40 noise draws about 68 % of the
/// estimates of ω lie within one standard error of the truth.
#[test]
fn standard_errors_have_nominal_coverage() {
    let mut inside = 0;
    let draws = 40;
    for seed in 0..draws {
        let prob = data(100 + seed);
        let sol = levenberg_marquardt(&prob, &X0, &LOG, &SolverOptions::default()).unwrap();
        let cov = covariance(&sol);
        if (sol.x[1] - TRUE[1]).abs() < cov.stderr[1] {
            inside += 1;
        }
    }
    let frac = inside as f64 / draws as f64;
    // Binomial(40, 0.683): 99 % interval ≈ [0.49, 0.87].
    assert!((0.45..=0.9).contains(&frac), "coverage {frac}");
}

#[test]
fn argmin_gauss_newton_reaches_the_same_minimum() {
    let prob = data(2);
    let opts = SolverOptions::default();
    let lm = levenberg_marquardt(&prob, &X0, &LOG, &opts).unwrap();
    let gn = gauss_newton_ls(&prob, &X0, &LOG, &opts).unwrap();
    assert!((gn.ssr / lm.ssr - 1.0).abs() < 1e-6, "GN {} vs LM {}", gn.ssr, lm.ssr);
    for j in 0..3 {
        assert!((gn.x[j] / lm.x[j] - 1.0).abs() < 1e-4);
    }
    assert!(gn.history.len() >= 2);
}

/// y = a·b·t cannot separate a from b: the correlation is flagged (|ρ| ≈ 1)
/// or the normal matrix is singular.
#[test]
fn a_product_of_parameters_is_flagged_not_identifiable() {
    struct Product(Vec<f64>, Vec<f64>);
    impl LsqProblem for Product {
        fn residuals(&self, p: &[f64]) -> Result<Vec<f64>, EstimateError> {
            Ok(self.0.iter().zip(&self.1).map(|(t, y)| y - p[0] * p[1] * t - p[2]).collect())
        }
    }
    let t: Vec<f64> = (0..50).map(|i| i as f64).collect();
    let y: Vec<f64> = t.iter().enumerate().map(|(i, t)| 2.0 * t + 1.0 + 0.01 * ((i * 7919) % 13) as f64).collect();
    let prob = Product(t, y);
    let tr = [Transform::Log, Transform::Log, Transform::Identity];
    let sol = levenberg_marquardt(&prob, &[1.0, 1.0, 0.0], &tr, &SolverOptions::default()).unwrap();
    let cov = covariance(&sol);
    let pairs = flagged_pairs(&cov.correlation);
    assert!(!cov.regular || pairs.iter().any(|(i, j, _)| (*i, *j) == (0, 1)), "{:?}", cov.correlation);
    // The product itself is determined.
    assert!((sol.x[0] * sol.x[1] - 2.0).abs() < 1e-3);
}

#[test]
fn whiteness_accepts_white_noise_and_rejects_ar1() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let n = Normal::new(0.0, 1.0).unwrap();
    let white: Vec<f64> = (0..4000).map(|_| n.sample(&mut rng)).collect();
    let w = whiteness(&[&white], 20);
    assert!(w.ljung_box_q < w.ljung_box_critical_99, "Q {} crit {}", w.ljung_box_q, w.ljung_box_critical_99);
    assert!(w.fraction_outside <= 0.1);
    let mut ar = vec![0.0; 4000];
    for i in 1..ar.len() {
        ar[i] = 0.6 * ar[i - 1] + white[i];
    }
    let w = whiteness(&[&ar], 20);
    assert!(w.ljung_box_q > 10.0 * w.ljung_box_critical_99);
    assert!((w.autocorrelation[0] - 0.6).abs() < 0.05);
    // χ²(20) 99 % quantile is 37.57 (tables); Wilson–Hilferty within 0.2.
    assert!((w.ljung_box_critical_99 - 37.57).abs() < 0.2);
}

#[test]
fn aic_bic_match_the_gaussian_likelihood_by_hand() {
    // n = 100, SSR = 4 → σ² = 0.04; −2lnL = 100(ln(2π·0.04) + 1) = −38.0999 (computed in Python).
    let (aic, bic) = aic_bic(4.0, 100, 3);
    let m2ll = 100.0 * ((2.0 * std::f64::consts::PI * 0.04_f64).ln() + 1.0);
    assert!((aic - (m2ll + 6.0)).abs() < 1e-12);
    assert!((bic - (m2ll + 3.0 * 100f64.ln())).abs() < 1e-12);
    assert!((m2ll + 38.0999).abs() < 1e-3);
}

/// A problem that counts its residual evaluations.
struct Counted<'a>(&'a Decay, AtomicUsize);

impl LsqProblem for Counted<'_> {
    fn residuals(&self, p: &[f64]) -> Result<Vec<f64>, EstimateError> {
        self.1.fetch_add(1, Ordering::Relaxed);
        self.0.residuals(p)
    }
}

/// The minimum alone (`levenberg_marquardt_minimum`, the motor side's
/// refit) is the full solver's point, SSR, iterations and history to the
/// bit, and where the search ends on the SSR's decrease it skips the
/// central differences at the last point: 2·p = 6 evaluations fewer.
#[test]
fn the_minimum_alone_is_the_solution_without_its_last_jacobian() {
    for seed in [1, 2, 3] {
        let prob = data(seed);
        let (full, alone) = (Counted(&prob, AtomicUsize::new(0)), Counted(&prob, AtomicUsize::new(0)));
        let opts = SolverOptions { ftol: 1e-6, ..SolverOptions::default() };
        let a = levenberg_marquardt(&full, &X0, &LOG, &opts).unwrap();
        let b = levenberg_marquardt_minimum(&alone, &X0, &LOG, &opts).unwrap();
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.x), bits(&b.x));
        assert_eq!(bits(&a.residuals), bits(&b.residuals));
        assert_eq!((a.ssr.to_bits(), a.iterations, a.converged), (b.ssr.to_bits(), b.iterations, b.converged));
        assert_eq!(a.stop_reason, b.stop_reason);
        assert_eq!(a.history.len(), b.history.len());
        assert!(a.history.iter().zip(&b.history).all(|(u, v)| u.ssr.to_bits() == v.ssr.to_bits()));
        assert_eq!(a.stop_reason, "relative SSR decrease below ftol", "seed {seed}");
        let (n_full, n_alone) = (full.1.load(Ordering::Relaxed), alone.1.load(Ordering::Relaxed));
        assert_eq!(n_full, n_alone + 6, "seed {seed}: {n_full} against {n_alone} evaluations");
    }
}
