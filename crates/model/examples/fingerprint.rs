//! Two tools for changes to the integrator that claim to keep or to speed up
//! its results.
//!
//! `cargo run --release -p rig-model --example fingerprint` prints the step
//! counters of 30 runs (both model kinds, five operating points of which six
//! runs stick-slip, sampled at 100, 500 and 1000 Hz) and one hash of every bit of
//! every channel: a change that claims byte-identical trajectories must print
//! the same hash.
//!
//! `... --example fingerprint -- dump <rpm> <N> <rig|thesis>` prints every
//! channel of one 40 s run at 500 Hz, to compare two builds' trajectories.
//!
//! `... --example fingerprint -- best [rig|rig100|one|at:<s>|thesis] [runs]` times the
//! criterion bench's problem into a reused trajectory and prints the best
//! batch of 100 runs: on a shared machine the minimum is what an A/B
//! comparison of two builds can trust (criterion's mean moves with the load).
#[path = "../tests/common/mod.rs"]
mod common;
use rig_model::{simulate_into, simulate_with_stats};
use rig_types::RunInput;
use std::hash::{Hash, Hasher};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("dump") {
        // dump <rpm> <N> <rig|thesis>: every sample of that run at 500 Hz as text.
        let num = |i: usize| args[i].parse::<f64>().expect("a number");
        let input = RunInput::OperatingPoint { motor_rpm_setpoint: num(1), normal_force_n: num(2), ramp_s: 2.0 };
        let p = if args[3] == "thesis" { common::thesis_params() } else { common::rig_params() };
        // RTOL=<x> in the environment: that rtol (atol 10⁻² of it) instead of the shipped one.
        let o =
            std::env::var("RTOL").map_or(common::shipped(), |r| common::at_rtol(r.parse().expect("RTOL: a number")));
        let (tr, _) = simulate_with_stats(&p, &input, &common::grid(40.0, 500.0), &o).unwrap();
        for k in 0..tr.len() {
            println!(
                "{:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e}",
                tr.rotor_angle_rad[k],
                tr.rotor_speed_rad_s[k],
                tr.motor_angle_rad[k],
                tr.motor_speed_rad_s[k],
                tr.current_a[k],
                tr.voltage_v[k],
                tr.friction_torque_nm[k],
                f64::from(u8::from(tr.stuck[k]))
            );
        }
        return;
    }
    if args.first().map(String::as_str) == Some("best") {
        let which = args.get(1).map_or("rig", String::as_str);
        let runs: usize = args.get(2).map_or(1500, |s| s.parse().expect("runs: an integer"));
        return best(which, runs);
    }
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let o = common::shipped();
    for (rpm, n) in [(40.0, 15.0), (10.0, 15.0), (5.0, 25.0), (60.0, 5.0), (20.0, 20.0)] {
        let input = RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: n, ramp_s: 2.0 };
        for p in [common::rig_params(), common::thesis_params()] {
            for rate in [500.0, 100.0, 1000.0] {
                let (tr, st) = simulate_with_stats(&p, &input, &common::grid(40.0, rate), &o).unwrap();
                for c in tr.numeric_channels() {
                    c.iter().for_each(|v| v.to_bits().hash(&mut h));
                }
                tr.stuck.hash(&mut h);
                println!("{rpm} rpm {n} N {:?} {rate} Hz: {st:?}", p.kind);
            }
        }
    }
    println!("hash {:016x}", h.finish());
}

fn best(which: &str, runs: usize) {
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 40.0, normal_force_n: 15.0, ramp_s: 2.0 };
    // "one": sampled once, at 40 s; "at:<T>": once, at T s (the start-up alone, say).
    let t = match which {
        "one" => vec![40.0],
        w if w.starts_with("at:") => vec![w[3..].parse().expect("at:<seconds>")],
        "rig100" => common::grid(40.0, 100.0),
        _ => common::grid(40.0, 500.0),
    };
    let p = if which == "thesis" { common::thesis_params() } else { common::rig_params() };
    let (mut out, o) = (rig_types::Trajectory::default(), common::shipped());
    let mut best_ms = f64::INFINITY;
    for _ in 0..runs.div_ceil(100) {
        let w = std::time::Instant::now();
        for _ in 0..100 {
            simulate_into(&p, &input, &t, &o, &mut out).unwrap();
        }
        best_ms = best_ms.min(w.elapsed().as_secs_f64() * 10.0);
    }
    println!("{which} best {best_ms:.4} ms/run");
}
