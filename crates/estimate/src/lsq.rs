//! A generic nonlinear least-squares core: a problem states residuals r(x);
//! the solver (a small Levenberg–Marquardt, argmin 0.11 has none) minimises
//! ½‖r‖² in transformed coordinates (log for positive quantities) with a
//! central finite-difference Jacobian, and returns its iteration history.

use crate::EstimateError;
use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A least-squares problem: residuals at natural parameter values `x`.
/// `Sync` because Jacobian columns are evaluated in parallel.
pub trait LsqProblem: Sync {
    /// Residual vector r(x); its length must not depend on `x`.
    fn residuals(&self, x: &[f64]) -> Result<Vec<f64>, EstimateError>;
}

/// How a parameter is represented inside the solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Transform {
    /// θ = x (signed quantities).
    Identity,
    /// θ = ln x: keeps a positive quantity positive and makes steps relative.
    Log,
}

impl Transform {
    pub fn to_theta(self, x: f64) -> f64 {
        match self {
            Transform::Identity => x,
            Transform::Log => x.ln(),
        }
    }
    pub fn to_x(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => theta,
            Transform::Log => theta.exp(),
        }
    }
    /// dx/dθ at θ (delta method for standard errors).
    pub fn dx_dtheta(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => 1.0,
            Transform::Log => theta.exp(),
        }
    }
}

/// Solver settings (from pipeline.toml `[stage.params]`, never globals).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolverOptions {
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the SSR by less than this fraction.
    pub ftol: f64,
    /// Stop when the step in θ is below xtol·(‖θ‖ + xtol).
    pub xtol: f64,
    /// Stop when the scaled gradient max|Jᵀr|/(‖r‖·‖J_j‖) is below gtol.
    pub gtol: f64,
    /// Central-difference step in θ: h_j = fd_step · max(|θ_j|, 1).
    pub fd_step: f64,
    /// Initial Marquardt damping λ (dimensionless: the step solves (A + λ·diag A) δ = −g).
    pub initial_lambda: f64,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions { max_iterations: 40, ftol: 1e-8, xtol: 1e-8, gtol: 1e-8, fd_step: 1e-4, initial_lambda: 1e-3 }
    }
}

/// One iteration of the solver (Fig. 4.12: misfit vs iteration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    pub iteration: usize,
    /// Sum of squared residuals after the iteration.
    pub ssr: f64,
    /// Marquardt damping used for the accepted step (0 for argmin's Gauss–Newton).
    pub lambda: f64,
    /// Residual evaluations so far (including Jacobian columns).
    pub evaluations: usize,
}

/// The solver's answer. `converged == false` is data, not an error.
#[derive(Debug, Clone)]
pub struct LsqSolution {
    pub x: Vec<f64>,
    pub theta: Vec<f64>,
    pub transforms: Vec<Transform>,
    pub residuals: Vec<f64>,
    /// Jacobian dr/dθ at the solution (transformed coordinates).
    pub jacobian: Mat<f64>,
    pub ssr: f64,
    pub iterations: usize,
    pub converged: bool,
    pub stop_reason: String,
    /// Entry 0 is the initial point.
    pub history: Vec<IterationRecord>,
}

fn ssr(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

fn x_of(theta: &[f64], tr: &[Transform]) -> Vec<f64> {
    theta.iter().zip(tr).map(|(t, f)| f.to_x(*t)).collect()
}

/// Central finite-difference Jacobian dr/dθ (m × p), columns evaluated in
/// parallel and assembled in column order (deterministic).
pub fn fd_jacobian<P: LsqProblem>(
    problem: &P,
    theta: &[f64],
    transforms: &[Transform],
    fd_step: f64,
    m: usize,
) -> Result<Mat<f64>, EstimateError> {
    let p = theta.len();
    let cols: Vec<Result<Vec<f64>, EstimateError>> = (0..p)
        .into_par_iter()
        .map(|j| {
            let h = fd_step * theta[j].abs().max(1.0);
            let mut tp = theta.to_vec();
            let mut tm = theta.to_vec();
            tp[j] += h;
            tm[j] -= h;
            let rp = problem.residuals(&x_of(&tp, transforms))?;
            let rm = problem.residuals(&x_of(&tm, transforms))?;
            if rp.len() != m || rm.len() != m {
                return Err(EstimateError::Residuals(format!("residual length changed with parameter {j}")));
            }
            Ok(rp.iter().zip(&rm).map(|(a, b)| (a - b) / (2.0 * h)).collect())
        })
        .collect();
    let mut jac = Mat::<f64>::zeros(m, p);
    for (j, col) in cols.into_iter().enumerate() {
        let col = col?;
        for i in 0..m {
            jac[(i, j)] = col[i];
        }
    }
    Ok(jac)
}

/// JᵀJ (p × p) and Jᵀr (p).
pub fn normal_equations(jac: &Mat<f64>, r: &[f64]) -> (Mat<f64>, Vec<f64>) {
    let p = jac.ncols();
    let jtj = jac.transpose() * jac;
    let g: Vec<f64> = (0..p).map(|j| (0..jac.nrows()).map(|i| jac[(i, j)] * r[i]).sum()).collect();
    (jtj, g)
}

/// Solves (A + λ·diag(A)) δ = −g (`crate::linear::spd_solve`); `None` if not positive definite.
fn damped_step(jtj: &Mat<f64>, g: &[f64], lambda: f64) -> Option<Vec<f64>> {
    let p = g.len();
    let mut a = jtj.clone();
    for j in 0..p {
        // A floor on the diagonal keeps a parameter the data do not see from
        // making the system singular (it then simply does not move).
        let d = jtj[(j, j)].max(1e-12 * (1.0 + jtj[(j, j)]));
        a[(j, j)] += lambda * d;
    }
    let minus_g: Vec<f64> = g.iter().map(|v| -v).collect();
    crate::linear::spd_solve(&a, &minus_g)
}

/// Marquardt's damping λ (λ·diag(JᵀJ) added to the normal equations) with
/// Nielsen's update (H. B. Nielsen, *Damping parameter in Marquardt's
/// method*, IMM-REP-1999-05; Madsen, Nielsen & Tingleff 2004, §3.2): a
/// step that lowers the cost with gain ratio ρ (actual over predicted
/// decrease) scales λ by max(1/3, 1 − (2ρ − 1)³) and resets ν to 2; a step
/// refused, or none, scales λ by ν and doubles ν. The one home of the
/// update: this crate's solver and the drive's gains fit
/// (`rig_diagnose::drive::gains`) both step it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damping {
    /// The current λ.
    pub lambda: f64,
    nu: f64,
}

impl Damping {
    /// λ = `lambda`, ν = 2.
    pub fn new(lambda: f64) -> Damping {
        Damping { lambda, nu: 2.0 }
    }

    /// A step accepted with gain ratio `rho`.
    pub fn accept(&mut self, rho: f64) {
        self.lambda *= (1.0_f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
        self.nu = 2.0;
    }

    /// A step refused, or no step (a singular damped system).
    pub fn refuse(&mut self) {
        self.lambda *= self.nu;
        self.nu *= 2.0;
    }
}

/// Levenberg–Marquardt (Marquardt scaling, Nielsen's damping update) from
/// `x0`. Trial points where the residuals fail are rejected steps.
pub fn levenberg_marquardt<P: LsqProblem>(
    problem: &P,
    x0: &[f64],
    transforms: &[Transform],
    opts: &SolverOptions,
) -> Result<LsqSolution, EstimateError> {
    solve(problem, x0, transforms, opts, true)
}

/// A [`levenberg_marquardt`] minimum without the Jacobian at it: the same
/// iterations, the same point and SSR to the bit, but where an accepted
/// step ends the search (its SSR decrease below `ftol`) the central
/// differences at the new point, 2·p residual evaluations that only the
/// returned Jacobian would read, are not taken. For callers that use the
/// fitted point alone (the motor side's refit,
/// [`crate::refit_motor_side`]).
#[derive(Debug, Clone)]
pub struct LsqMinimum {
    pub x: Vec<f64>,
    pub residuals: Vec<f64>,
    pub ssr: f64,
    pub iterations: usize,
    pub converged: bool,
    pub stop_reason: String,
    /// Entry 0 is the initial point.
    pub history: Vec<IterationRecord>,
}

/// [`levenberg_marquardt`] to its minimum alone ([`LsqMinimum`]).
pub fn levenberg_marquardt_minimum<P: LsqProblem>(
    problem: &P,
    x0: &[f64],
    transforms: &[Transform],
    opts: &SolverOptions,
) -> Result<LsqMinimum, EstimateError> {
    let s = solve(problem, x0, transforms, opts, false)?;
    Ok(LsqMinimum {
        x: s.x,
        residuals: s.residuals,
        ssr: s.ssr,
        iterations: s.iterations,
        converged: s.converged,
        stop_reason: s.stop_reason,
        history: s.history,
    })
}

/// The iterations of [`levenberg_marquardt`]; the solution's `jacobian` is
/// at the solution when `final_jacobian`, else the last one computed (the
/// central differences after a step that ends the search are skipped;
/// [`levenberg_marquardt_minimum`] drops it).
fn solve<P: LsqProblem>(
    problem: &P,
    x0: &[f64],
    transforms: &[Transform],
    opts: &SolverOptions,
    final_jacobian: bool,
) -> Result<LsqSolution, EstimateError> {
    assert_eq!(x0.len(), transforms.len(), "one transform per parameter");
    for (i, (x, t)) in x0.iter().zip(transforms).enumerate() {
        if !x.is_finite() || (*t == Transform::Log && *x <= 0.0) {
            return Err(EstimateError::InvalidOption {
                name: format!("initial value of parameter {i}"),
                value: *x,
                rule: "must be finite, and > 0 for a log-transformed (positive) parameter",
            });
        }
    }
    let p = x0.len();
    let mut theta: Vec<f64> = x0.iter().zip(transforms).map(|(x, t)| t.to_theta(*x)).collect();
    let mut r = problem.residuals(x0)?;
    let m = r.len();
    if m < p {
        return Err(EstimateError::TooFewSamples {
            context: "least squares".into(),
            got: m,
            need: p,
            rule: "need at least as many residuals as parameters",
        });
    }
    let mut cost = ssr(&r);
    let mut evals = 1usize;
    let mut history = vec![IterationRecord { iteration: 0, ssr: cost, lambda: 0.0, evaluations: evals }];
    let mut jac = fd_jacobian(problem, &theta, transforms, opts.fd_step, m)?;
    evals += 2 * p;
    let (mut jtj, mut g) = normal_equations(&jac, &r);
    // Marquardt scaling (λ·diag(A)) makes λ dimensionless.
    let mut damping = Damping::new(opts.initial_lambda);
    let mut converged = false;
    let mut stop_reason = format!("reached max_iterations = {}", opts.max_iterations);
    let mut iterations = 0;

    let gradient_small = |jtj: &Mat<f64>, g: &[f64], cost: f64| {
        (0..p).all(|j| {
            let norm = (jtj[(j, j)] * cost).sqrt();
            norm == 0.0 || (g[j] / norm).abs() < opts.gtol
        })
    };
    if gradient_small(&jtj, &g, cost) {
        converged = true;
        stop_reason = "gradient below gtol at the initial point".into();
    }

    while !converged && iterations < opts.max_iterations {
        iterations += 1;
        // Inner loop: raise the damping until a step lowers the cost.
        let mut accepted = false;
        for _ in 0..30 {
            let Some(step) = damped_step(&jtj, &g, damping.lambda) else {
                damping.refuse();
                continue;
            };
            let step_norm = step.iter().map(|v| v * v).sum::<f64>().sqrt();
            let theta_norm = theta.iter().map(|v| v * v).sum::<f64>().sqrt();
            if step_norm <= opts.xtol * (theta_norm + opts.xtol) {
                converged = true;
                stop_reason = "step below xtol".into();
                break;
            }
            let trial: Vec<f64> = theta.iter().zip(&step).map(|(t, s)| t + s).collect();
            evals += 1;
            let trial_r = problem.residuals(&x_of(&trial, transforms)).ok().filter(|v| v.len() == m);
            let trial_cost = trial_r.as_ref().map(|v| ssr(v)).filter(|c| c.is_finite()).unwrap_or(f64::INFINITY);
            // Predicted reduction of ½‖r‖² by the linear model: −gᵀδ − ½δᵀAδ.
            let a_step: Vec<f64> = (0..p).map(|i| (0..p).map(|j| jtj[(i, j)] * step[j]).sum()).collect();
            let pred = -step.iter().zip(&g).map(|(s, gi)| s * gi).sum::<f64>()
                - 0.5 * step.iter().zip(&a_step).map(|(s, a)| s * a).sum::<f64>();
            let rho = if pred > 0.0 { 0.5 * (cost - trial_cost) / pred } else { -1.0 };
            if trial_cost < cost && rho > 0.0 {
                let rel_drop = (cost - trial_cost) / cost.max(f64::MIN_POSITIVE);
                theta = trial;
                r = trial_r.expect("finite cost implies residuals");
                cost = trial_cost;
                damping.accept(rho);
                accepted = true;
                if rel_drop < opts.ftol {
                    converged = true;
                    stop_reason = "relative SSR decrease below ftol".into();
                }
                break;
            }
            damping.refuse();
        }
        if accepted && converged && !final_jacobian {
            // The search ends here and nothing reads the Jacobian at theta.
        } else if accepted {
            jac = fd_jacobian(problem, &theta, transforms, opts.fd_step, m)?;
            evals += 2 * p;
            (jtj, g) = normal_equations(&jac, &r);
            if !converged && gradient_small(&jtj, &g, cost) {
                converged = true;
                stop_reason = "scaled gradient below gtol".into();
            }
        } else if !converged {
            stop_reason = "no damped step lowers the SSR (local minimum to solver precision)".into();
            // Cannot improve further: treat as converged only if the gradient is small.
            converged = gradient_small(&jtj, &g, cost);
            history.push(IterationRecord {
                iteration: iterations,
                ssr: cost,
                lambda: damping.lambda,
                evaluations: evals,
            });
            break;
        }
        history.push(IterationRecord { iteration: iterations, ssr: cost, lambda: damping.lambda, evaluations: evals });
    }

    Ok(LsqSolution {
        x: x_of(&theta, transforms),
        theta,
        transforms: transforms.to_vec(),
        residuals: r,
        jacobian: jac,
        ssr: cost,
        iterations,
        converged,
        stop_reason,
        history,
    })
}
