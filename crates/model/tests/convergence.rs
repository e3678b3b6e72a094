//! The integrator converges: errors against a tight-tolerance reference fall
//! as the tolerance tightens (rig model with located stick/slip events and the
//! stiff thesis lookup), and no operating point of the range gives NaN.

mod common;

use common::*;
use rig_model::{SimOptions, simulate, simulate_with_stats};
use rig_types::{RigParams, RunInput};

/// The step cap is lifted so that the tolerance, not `max_step_s`, sets the step.
fn max_rotor_speed_error(p: &RigParams, input: &RunInput, t: &[f64], tol: f64, reference: &[f64]) -> f64 {
    let tr = simulate(p, input, t, &SimOptions { max_step_s: 1.0, ..at_rtol(tol) }).unwrap();
    tr.rotor_speed_rad_s.iter().zip(reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
}

fn check_convergence(p: &RigParams, input: &RunInput, t_end: f64) -> Vec<f64> {
    let t = grid(t_end, 200.0);
    let reference = simulate(p, input, &t, &at_rtol(1e-13)).unwrap();
    let errors: Vec<f64> = [1e-5, 1e-7, 1e-9, 1e-11]
        .iter()
        .map(|&tol| max_rotor_speed_error(p, input, &t, tol, &reference.rotor_speed_rad_s))
        .collect();
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "error must fall as tol tightens: {errors:?}");
    }
    eprintln!("{:?} errors at tol 1e-5, 1e-7, 1e-9, 1e-11: {errors:?}", p.kind);
    errors
}

#[test]
fn rig_model_converges_through_stick_slip() {
    let p = rig_params();
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 5.0, normal_force_n: 30.0, ramp_s: 2.0 };
    let (_, stats) = simulate_with_stats(&p, &input, &grid(20.0, 200.0), &at_rtol(1e-9)).unwrap();
    assert!(stats.events >= 6, "the run must contain stick/slip events: {stats:?}");
    let errors = check_convergence(&p, &input, 20.0);
    // Rotor speed peaks at ~3 rad/s: at tol 1e-9 the error is well below 1e-5 rad/s.
    assert!(errors[2] < 1e-5, "{errors:?}");
    assert!(errors[0] / errors[3] > 1e3, "{errors:?}");
}

#[test]
fn thesis_model_converges_through_creep() {
    let p = thesis_params();
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 20.0, normal_force_n: 10.0, ramp_s: 2.0 };
    let errors = check_convergence(&p, &input, 10.0);
    assert!(errors[2] < 1e-4, "{errors:?}");
}

/// Motor 5–150 rpm, N 0–30 N, both models: every channel finite.
#[test]
fn no_nan_over_the_operating_range() {
    let t = grid(20.0, 50.0);
    for p in [rig_params(), thesis_params()] {
        for rpm in [5.0, 20.0, 55.0, 100.0, 150.0] {
            for n in [0.0, 1.0, 7.5, 15.0, 30.0] {
                let input = RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: n, ramp_s: 2.0 };
                let tr = simulate(&p, &input, &t, &shipped())
                    .unwrap_or_else(|e| panic!("{:?} {rpm} rpm {n} N: {e}", p.kind));
                assert_eq!(tr.len(), t.len());
                let channels = tr.numeric_channels();
                assert!(channels.iter().all(|c| c.iter().all(|x| x.is_finite())), "{:?} {rpm} rpm {n} N", p.kind);
            }
        }
    }
}

/// A parameter set that makes the equations absurdly stiff (L/R = 1 ns) is an
/// error naming the time constant, returned after the step budget, not a hang.
#[test]
fn absurdly_stiff_parameters_fail_with_a_budget_error() {
    let mut p = rig_params();
    p.motor.inductance_h = 1e-9 * p.motor.resistance_ohm;
    let start = std::time::Instant::now();
    let err = simulate(&p, &RunInput::VoltageStep { voltage_v: 6.0 }, &grid(20.0, 10.0), &shipped()).unwrap_err();
    let rig_model::ModelError::IntegratorFailed { reason, .. } = err else { panic!("{err:?}") };
    assert!(reason.contains("L/R = 1.00e-9 s"), "{reason}");
    assert!(start.elapsed().as_secs() < 60);
}

/// A trajectory reused by `simulate_into` (a map's per-thread buffer) holds
/// exactly what a fresh `simulate` returns, whatever it held before: a long
/// 500 Hz stick-slip run, then a shorter run of the thesis model, then a
/// 100 Hz run of the rig model.
#[test]
fn a_reused_trajectory_holds_exactly_what_a_fresh_run_returns() {
    let mut out = rig_types::Trajectory::default();
    for (p, rate, t_end, rpm) in [
        (common::rig_params(), 500.0, 40.0, 20.0),
        (common::thesis_params(), 250.0, 12.0, 60.0),
        (common::rig_params(), 100.0, 20.0, 40.0),
    ] {
        let input = RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: 15.0, ramp_s: 2.0 };
        let t = common::grid(t_end, rate);
        let stats = rig_model::simulate_into(&p, &input, &t, &shipped(), &mut out).expect("reused");
        let (fresh, fresh_stats) = rig_model::simulate_with_stats(&p, &input, &t, &shipped()).expect("fresh");
        assert_eq!(out.len(), t.len());
        assert_eq!(out, fresh, "{rate} Hz, {t_end} s");
        assert_eq!(stats, fresh_stats);
    }
}

/// A sample grid spaced by exactly max_step_s (100 Hz at the default 10 ms)
/// is stepped along by exact steps: the run takes no more Dormand–Prince steps
/// than the same run sampled once at its end (the start-up before the motor
/// friction saturates, and the break-away). Stepping by t + max_step_s fell
/// an ulp short of each sample and added an ulp-long step to it: 863 steps
/// against 350.
#[test]
fn a_grid_at_the_maximum_step_takes_no_extra_dormand_prince_steps() {
    let p = rig_params();
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 40.0, normal_force_n: 15.0, ramp_s: 2.0 };
    let o = shipped();
    let (_, once) = simulate_with_stats(&p, &input, &[40.0], &o).expect("sampled once");
    for rate in [100.0, 50.0] {
        let (_, grid) = simulate_with_stats(&p, &input, &grid(40.0, rate), &o).expect("on the grid");
        assert!(
            grid.accepted_steps + grid.rejected_steps <= once.accepted_steps + once.rejected_steps + 2,
            "{rate} Hz: {grid:?} against {once:?} sampled once"
        );
    }
}
