//! Cross-check of the rig model against an independent integrator: scipy's
//! solve_ivp (DOP853, rtol 1e-10, terminal events) on the same equations,
//! tests/scipy/rig_model_scipy.py. Skipped, with a message, when python3 or
//! scipy is missing, so CI without python still passes the rest.

mod common;

use common::*;
use rig_model::{ANTI_WINDUP_TRACKING_S, MOTOR_FRICTION_SPEED_RAD_S, simulate};
use rig_types::{FrictionLaw, RigParams, RunInput};
use std::io::Write;
use std::process::{Command, Stdio};

const SCRIPT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scipy/rig_model_scipy.py");

fn scipy_available() -> bool {
    Command::new("python3")
        .args(["-c", "import scipy, numpy"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// Stick-slip-prone variant of the test rig: light shaft damping, μs 0.6 / μk 0.3.
fn crosscheck_params() -> RigParams {
    let mut p = rig_params();
    p.friction = FrictionLaw::Coulomb { mu_static: 0.6, mu_kinetic: 0.3 };
    p.shaft_damping_nm_s_rad = 0.005;
    p
}

struct Reference {
    rotor_speed_rad_s: Vec<f64>,
    release_times_s: Vec<f64>,
}

fn run_scipy(p: &RigParams, rpm: f64, n: f64, ramp: f64, t: &[f64]) -> Reference {
    let case = serde_json::json!({
        "params": p,
        "motor_rpm_setpoint": rpm,
        "normal_force_n": n,
        "ramp_s": ramp,
        "sample_times_s": t,
        "anti_windup_tracking_s": ANTI_WINDUP_TRACKING_S,
        "motor_friction_speed_rad_s": MOTOR_FRICTION_SPEED_RAD_S,
    });
    let mut child = Command::new("python3")
        .arg(SCRIPT)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 starts");
    child.stdin.take().unwrap().write_all(case.to_string().as_bytes()).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let floats = |key: &str| v[key].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect::<Vec<_>>();
    Reference { rotor_speed_rad_s: floats("rotor_speed_rad_s"), release_times_s: floats("release_times_s") }
}

fn max_of(x: &[f64]) -> f64 {
    x.iter().cloned().fold(f64::MIN, f64::max)
}

/// Mean spacing of break-aways in the second half of the run, s.
fn period(releases: &[f64], t_half: f64) -> f64 {
    let late: Vec<f64> = releases.iter().copied().filter(|&r| r >= t_half).collect();
    assert!(late.len() >= 3, "{releases:?}");
    (late[late.len() - 1] - late[0]) / (late.len() - 1) as f64
}

#[test]
fn rig_model_agrees_with_scipy_solve_ivp() {
    if !scipy_available() {
        eprintln!("SKIPPED rig_model_agrees_with_scipy_solve_ivp: python3 with scipy and numpy not found");
        return;
    }
    let p = crosscheck_params();
    let rate = 2_000.0;
    let t_end = 30.0;
    let t = grid(t_end, rate);
    let o = at_rtol(1e-10);
    for (rpm, n) in [(10.0, 5.0), (20.0, 15.0), (40.0, 25.0)] {
        let reference = run_scipy(&p, rpm, n, 2.0, &t);
        let tr =
            simulate(&p, &RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: n, ramp_s: 2.0 }, &t, &o)
                .unwrap();
        // Break-aways of the Rust run: at the first slipping sample k, Ω1 has
        // grown from 0 at the rate (μs − μk) N r / J1 (the shaft torque equals
        // μs N r at break-away), so the break-away was Ω1_k / rate earlier (error O(dt²)).
        let accel = (0.6 - 0.3) * n * p.brake_disc_radius_m / p.rotor_inertia_kgm2;
        let releases: Vec<f64> = (1..tr.len())
            .filter(|&k| tr.stuck[k - 1] && !tr.stuck[k])
            .map(|k| t[k] - tr.rotor_speed_rad_s[k] / accel)
            .collect();
        assert_eq!(releases.len(), reference.release_times_s.len(), "{rpm} rpm {n} N: number of break-aways");
        let release_diff =
            releases.iter().zip(&reference.release_times_s).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let half = tr.len() / 2;
        let (w, w_ref) = (&tr.rotor_speed_rad_s[half..], &reference.rotor_speed_rad_s[half..]);
        let diff = w.iter().zip(w_ref).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let max_diff = (max_of(w) - max_of(w_ref)).abs();
        let period_diff = (period(&releases, t_end / 2.0) - period(&reference.release_times_s, t_end / 2.0)).abs();
        eprintln!(
            "{rpm} rpm {n} N: {} break-aways, max |Δ release| {release_diff:.2e} s, max |ΔΩ1| {diff:.2e} rad/s, \
             |Δ max Ω1| {max_diff:.2e} rad/s, |Δ period| {period_diff:.2e} s",
            releases.len()
        );
        assert!(release_diff < 1e-6, "{rpm} rpm {n} N: {release_diff}");
        assert!(period_diff < 1e-6, "{rpm} rpm {n} N: {period_diff}");
        assert!(max_diff < 1e-6, "{rpm} rpm {n} N: {max_diff}");
        assert!(diff < 1e-5, "{rpm} rpm {n} N: {diff}");
    }
}

/// Stick-slip cycles of a run: break-away times (as in the scipy test, from the
/// first slipping sample) and the largest rotor speed between consecutive ones.
fn cycles(tr: &rig_types::Trajectory, t: &[f64], accel: f64) -> (Vec<f64>, Vec<f64>) {
    let starts: Vec<usize> = (1..tr.len()).filter(|&k| tr.stuck[k - 1] && !tr.stuck[k]).collect();
    let releases = starts.iter().map(|&k| t[k] - tr.rotor_speed_rad_s[k] / accel).collect();
    let peaks = starts.windows(2).map(|w| max_of(&tr.rotor_speed_rad_s[w[0]..w[1]])).collect();
    (releases, peaks)
}

/// Issue 12's accuracy bar for the default tolerance (which the exact steps of
/// the drive make cheap): on the three cross-check cases, every stick-slip
/// cycle's rotor-speed peak, every break-away time and the period agree with
/// a tight-tolerance run (rtol 1e-13, itself within 1e-6 of scipy's DOP853 by
/// the test above) to 0.1 % (peaks and period relative, break-aways relative
/// to the period).
#[test]
fn default_tolerance_is_within_a_tenth_of_a_percent_of_a_tight_reference() {
    let p = crosscheck_params();
    let (rate, t_end) = (2_000.0, 30.0);
    let t = grid(t_end, rate);
    let tight = at_rtol(1e-13);
    for (rpm, n) in [(10.0, 5.0), (20.0, 15.0), (40.0, 25.0)] {
        let input = RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: n, ramp_s: 2.0 };
        let accel = (0.6 - 0.3) * n * p.brake_disc_radius_m / p.rotor_inertia_kgm2;
        let (rel_ref, peaks_ref) = cycles(&simulate(&p, &input, &t, &tight).unwrap(), &t, accel);
        let (rel, peaks) = cycles(&simulate(&p, &input, &t, &shipped()).unwrap(), &t, accel);
        assert_eq!(rel.len(), rel_ref.len(), "{rpm} rpm {n} N: number of break-aways");
        assert!(rel.len() >= 6, "{rpm} rpm {n} N must stick-slip: {rel:?}");
        let period_ref = period(&rel_ref, t_end / 2.0);
        let period_err = (period(&rel, t_end / 2.0) - period_ref).abs() / period_ref;
        let release_err = rel.iter().zip(&rel_ref).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / period_ref;
        let peak_err = peaks.iter().zip(&peaks_ref).map(|(a, b)| ((a - b) / b).abs()).fold(0.0, f64::max);
        eprintln!(
            "{rpm} rpm {n} N, default tolerance against rtol 1e-13: {} cycles, peaks {peak_err:.1e}, \
             break-aways {release_err:.1e} of the period, period {period_err:.1e} (relative)",
            peaks.len()
        );
        assert!(peak_err < 1e-3, "{rpm} rpm {n} N: rotor-speed peaks off by {peak_err}");
        assert!(release_err < 1e-3, "{rpm} rpm {n} N: break-aways off by {release_err} of the period");
        assert!(period_err < 1e-3, "{rpm} rpm {n} N: period off by {period_err}");
    }
}
