//! CPU time (not wall time) per simulate call, read from /proc/self/stat (Linux):
//! criterion measures wall time, which other jobs on the two shared cores inflate.
#[path = "../tests/common/mod.rs"]
mod common;
use rig_model::{SimOptions, simulate_with_stats};
use rig_types::RunInput;
fn cpu_s() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap();
    let f: Vec<&str> = s.rsplit(')').next().unwrap().split_whitespace().collect();
    (f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap()) / 100.0
}
fn main() {
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 40.0, normal_force_n: 15.0, ramp_s: 2.0 };
    let t = common::grid(40.0, 500.0);
    for (name, p, samples) in [
        ("rig 500 Hz", common::rig_params(), t.clone()),
        ("rig 1 sample", common::rig_params(), vec![40.0]),
        ("thesis 500 Hz", common::thesis_params(), t.clone()),
    ] {
        let n = 500;
        let c0 = cpu_s();
        let w0 = std::time::Instant::now();
        let mut st = None;
        for _ in 0..n {
            st = Some(simulate_with_stats(&p, &input, &samples, &SimOptions::default()).unwrap().1);
        }
        println!(
            "{name}: cpu {:.3} ms, wall {:.3} ms per run, {:?}",
            (cpu_s() - c0) / n as f64 * 1e3,
            w0.elapsed().as_secs_f64() / n as f64 * 1e3,
            st.unwrap()
        );
    }
}
