//! CPU time (not wall time) per simulate call, read from /proc/self/stat (Linux):
//! criterion measures wall time, which other jobs on the two shared cores inflate.
//!
//! `--peer-case` instead prints, as JSON, the criterion bench's problem in the
//! form tests/scipy/rig_model_scipy.py reads (parameters, 40 rpm, 15 N, ramp,
//! 500 Hz samples over 40 s, the two model constants) with this crate's CPU
//! and wall time and results on it: scripts/peer_scipy.py times scipy on it.
#[path = "../tests/common/mod.rs"]
mod common;
use rig_model::{ANTI_WINDUP_TRACKING_S, MOTOR_FRICTION_SPEED_RAD_S, simulate_into, simulate_with_stats};
use rig_types::{FrictionLaw, RunInput};
/// CPU time (user + system) of this process so far, s (`rig_types::cpu`).
fn cpu_s() -> f64 {
    rig_types::cpu::process_cpu_s().expect("/proc/self/stat")
}
/// Minor page faults of this process so far (/proc/self/stat field 10).
fn minor_faults() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap();
    s.rsplit(')').next().unwrap().split_whitespace().nth(7).unwrap().parse().unwrap()
}
fn main() {
    // Read once, first (on a thread of its own: `common::shipped`).
    let o = common::shipped();
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 40.0, normal_force_n: 15.0, ramp_s: 2.0 };
    let t = common::grid(40.0, 500.0);
    if std::env::args().any(|a| a == "--peer-case") {
        return peer_case(&input, &t, &o);
    }
    for (name, p, samples) in [
        ("rig 500 Hz", common::rig_params(), t.clone()),
        ("rig 1 sample", common::rig_params(), vec![40.0]),
        ("thesis 500 Hz", common::thesis_params(), t.clone()),
    ] {
        let n = 500;
        let (c0, f0) = (cpu_s(), minor_faults());
        let w0 = std::time::Instant::now();
        let mut st = None;
        for _ in 0..n {
            st = Some(simulate_with_stats(&p, &input, &samples, &o).unwrap().1);
        }
        let (cpu_fresh, wall_fresh) = ((cpu_s() - c0) / n as f64 * 1e3, w0.elapsed().as_secs_f64() / n as f64 * 1e3);
        let faults_fresh = (minor_faults() - f0) / n as f64;
        let mut out = rig_types::Trajectory::default();
        let (c0, w0, f0) = (cpu_s(), std::time::Instant::now(), minor_faults());
        for _ in 0..n {
            simulate_into(&p, &input, &samples, &o, &mut out).unwrap();
        }
        println!(
            "{name}: cpu {cpu_fresh:.3} ms, wall {wall_fresh:.3} ms, {faults_fresh:.0} page faults per run; into a \
             reused trajectory cpu {:.3} ms, wall {:.3} ms, {:.0} page faults; {:?}",
            (cpu_s() - c0) / n as f64 * 1e3,
            w0.elapsed().as_secs_f64() / n as f64 * 1e3,
            (minor_faults() - f0) / n as f64,
            st.unwrap()
        );
    }
}

fn peer_case(input: &RunInput, t: &[f64], o: &rig_model::SimOptions) {
    let p = common::rig_params();
    let RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = *input else { unreachable!() };
    let FrictionLaw::Coulomb { mu_static, mu_kinetic } = p.friction else { unreachable!("the bench brake is Coulomb") };
    let (n, c0, w0) = (500, cpu_s(), std::time::Instant::now());
    let mut tr = None;
    for _ in 0..n {
        tr = Some(simulate_with_stats(&p, input, t, o).unwrap().0);
    }
    let (cpu_ms, wall_ms) = ((cpu_s() - c0) / n as f64 * 1e3, w0.elapsed().as_secs_f64() / n as f64 * 1e3);
    let tr = tr.unwrap();
    // The same runs into one reused trajectory (simulate_into, a batch's per-thread buffer).
    let mut out = rig_types::Trajectory::default();
    let (c0, w0) = (cpu_s(), std::time::Instant::now());
    for _ in 0..n {
        simulate_into(&p, input, t, o, &mut out).unwrap();
    }
    let (cpu_reused_ms, wall_reused_ms) =
        ((cpu_s() - c0) / n as f64 * 1e3, w0.elapsed().as_secs_f64() / n as f64 * 1e3);
    assert_eq!(out, tr, "a reused trajectory holds what a fresh run returns");
    // Break-aways as in tests/scipy_crosscheck.rs: Ω1 grew from 0 at (μs − μk) N r / J1.
    let accel = (mu_static - mu_kinetic) * normal_force_n * p.brake_disc_radius_m / p.rotor_inertia_kgm2;
    let releases: Vec<f64> = (1..tr.len())
        .filter(|&k| tr.stuck[k - 1] && !tr.stuck[k])
        .map(|k| t[k] - tr.rotor_speed_rad_s[k] / accel)
        .collect();
    let case = serde_json::json!({
        "params": p,
        "motor_rpm_setpoint": motor_rpm_setpoint,
        "normal_force_n": normal_force_n,
        "ramp_s": ramp_s,
        "sample_times_s": t,
        "anti_windup_tracking_s": ANTI_WINDUP_TRACKING_S,
        "motor_friction_speed_rad_s": MOTOR_FRICTION_SPEED_RAD_S,
        "rust": {
            "options": format!(
                "pipeline.toml [shared.integrator] (rtol {:e}, atol {:e}, max_step {} s)",
                o.rtol, o.atol, o.max_step_s
            ),
            "cpu_ms_per_run": cpu_ms,
            "wall_ms_per_run": wall_ms,
            "cpu_ms_per_run_reused": cpu_reused_ms,
            "wall_ms_per_run_reused": wall_reused_ms,
            "rotor_speed_rad_s": tr.rotor_speed_rad_s,
            "release_times_s": releases,
        },
    });
    println!("{case}");
}
