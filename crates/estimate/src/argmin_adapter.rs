//! An [`LsqProblem`] seen through argmin's problem traits (`Operator` for the
//! residuals, `Jacobian` for the finite-difference Jacobian, both on faer
//! `Mat<f64>` columns in transformed coordinates), and the alternative solver
//! argmin 0.11 offers: Gauss–Newton with a backtracking Armijo line search
//! (c = 1e-4; guide/CRATES.md: 0.5 stops after two iterations).

use crate::EstimateError;
use crate::lsq::{IterationRecord, LsqProblem, LsqSolution, SolverOptions, Transform, fd_jacobian};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Error, Executor, IterState, Jacobian, KV, Operator, State};
use argmin::solver::gaussnewton::GaussNewtonLS;
use argmin::solver::linesearch::BacktrackingLineSearch;
use argmin::solver::linesearch::condition::ArmijoCondition;
use faer::Mat;
use std::sync::{Arc, Mutex};

/// A least-squares problem in θ coordinates for argmin.
pub struct ArgminLsq<'a, P: LsqProblem> {
    pub problem: &'a P,
    pub transforms: Vec<Transform>,
    pub fd_step: f64,
}

fn col(v: &[f64]) -> Mat<f64> {
    Mat::from_fn(v.len(), 1, |i, _| v[i])
}

fn to_vec(m: &Mat<f64>) -> Vec<f64> {
    (0..m.nrows()).map(|i| m[(i, 0)]).collect()
}

impl<P: LsqProblem> ArgminLsq<'_, P> {
    fn x(&self, theta: &Mat<f64>) -> Vec<f64> {
        (0..theta.nrows()).map(|i| self.transforms[i].to_x(theta[(i, 0)])).collect()
    }
}

impl<P: LsqProblem> Operator for ArgminLsq<'_, P> {
    type Param = Mat<f64>;
    type Output = Mat<f64>;
    fn apply(&self, theta: &Mat<f64>) -> Result<Mat<f64>, Error> {
        let r = self.problem.residuals(&self.x(theta)).map_err(|e| Error::msg(e.to_string()))?;
        Ok(col(&r))
    }
}

impl<P: LsqProblem> Jacobian for ArgminLsq<'_, P> {
    type Param = Mat<f64>;
    type Jacobian = Mat<f64>;
    fn jacobian(&self, theta: &Mat<f64>) -> Result<Mat<f64>, Error> {
        let th = to_vec(theta);
        let m = self.problem.residuals(&self.x(theta)).map_err(|e| Error::msg(e.to_string()))?.len();
        fd_jacobian(self.problem, &th, &self.transforms, self.fd_step, m).map_err(|e| Error::msg(e.to_string()))
    }
}

/// Records the cost after each iteration (argmin's cost here is ‖r‖, not ‖r‖²).
struct CostTrace(Arc<Mutex<Vec<f64>>>);

impl<I: State<Float = f64>> Observe<I> for CostTrace {
    fn observe_iter(&mut self, state: &I, _kv: &KV) -> Result<(), Error> {
        self.0.lock().expect("observer lock").push(state.get_cost());
        Ok(())
    }
}

/// Gauss–Newton with line search from `x0`, reported like [`crate::lsq::levenberg_marquardt`].
pub fn gauss_newton_ls<P: LsqProblem>(
    problem: &P,
    x0: &[f64],
    transforms: &[Transform],
    opts: &SolverOptions,
) -> Result<LsqSolution, EstimateError> {
    let theta0: Vec<f64> = x0.iter().zip(transforms).map(|(x, t)| t.to_theta(*x)).collect();
    let op = ArgminLsq { problem, transforms: transforms.to_vec(), fd_step: opts.fd_step };
    let r0 = problem.residuals(x0)?;
    let ssr0: f64 = r0.iter().map(|v| v * v).sum();
    let condition = ArmijoCondition::new(1e-4).map_err(|e| EstimateError::Argmin(e.to_string()))?;
    let solver = GaussNewtonLS::new(BacktrackingLineSearch::new(condition))
        .with_tolerance(opts.ftol * ssr0.sqrt())
        .map_err(|e| EstimateError::Argmin(e.to_string()))?;
    let trace = Arc::new(Mutex::new(Vec::new()));
    let res = Executor::new(op, solver)
        .configure(|s: IterState<Mat<f64>, Mat<f64>, Mat<f64>, (), (), f64>| {
            s.param(col(&theta0)).max_iters(opts.max_iterations as u64)
        })
        .timer(false)
        .add_observer(CostTrace(trace.clone()), ObserverMode::Always)
        .run()
        .map_err(|e| EstimateError::Argmin(e.to_string()))?;
    let state = res.state();
    let theta = to_vec(state.get_best_param().or(state.get_param()).expect("argmin keeps a parameter"));
    let x: Vec<f64> = theta.iter().zip(transforms).map(|(t, f)| f.to_x(*t)).collect();
    let residuals = problem.residuals(&x)?;
    let m = residuals.len();
    let jacobian = fd_jacobian(problem, &theta, transforms, opts.fd_step, m)?;
    let ssr: f64 = residuals.iter().map(|v| v * v).sum();
    let iterations = state.get_iter() as usize;
    let mut history = vec![IterationRecord { iteration: 0, ssr: ssr0, lambda: 0.0, evaluations: 1 }];
    for (k, c) in trace.lock().expect("observer lock").iter().enumerate() {
        history.push(IterationRecord { iteration: k + 1, ssr: c * c, lambda: 0.0, evaluations: 0 });
    }
    let converged = state.get_termination_status().terminated() && iterations < opts.max_iterations;
    Ok(LsqSolution {
        x,
        theta,
        transforms: transforms.to_vec(),
        residuals,
        jacobian,
        ssr,
        iterations,
        converged,
        stop_reason: format!("{:?}", state.get_termination_reason()),
        history,
    })
}
