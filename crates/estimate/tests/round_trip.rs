//! Round trip in faer's manner: simulate a campaign with known parameters
//! (rig_model + noise + encoder quantisation), estimate blind, compare.

mod common;

use rig_estimate::{EstimateOptions, InitialValues, estimate_rig};
use std::time::Instant;

/// Table 4.4 as printed (data/thesis/table-4-4.csv).
fn table_4_4() -> InitialValues {
    InitialValues {
        motor_inertia_kgm2: 0.37e-3,
        inductance_h: 1.10e-3,
        resistance_ohm: 0.33,
        torque_constant_nm_a: 0.12,
        voltage_constant_v_s_rad: 6.02e-2,
        friction_torque_nm: 0.1,
        speed_regulation_nm_s_rad: 1.91e-4,
        rotor_inertia_kgm2: 0.0283,
        shaft_stiffness_nm_rad: 0.268,
    }
}

#[test]
fn explore() {
    let truth = common::truth();
    let t0 = Instant::now();
    let c =
        common::campaign(&truth, &[6.0, 8.0, 10.0, 12.0], 10.0, &[(20.0, 10.0), (45.0, 4.0), (85.0, 25.0)], 15.0, 1);
    eprintln!("generate {:?}", t0.elapsed());
    let cal = rig_calibrate::calibrate_campaign(&c).unwrap();
    eprintln!("cal K {} J1 {} xi {}", cal.stiffness_nm_rad, cal.rotor_inertia_kgm2, cal.damping_ratio);
    let t0 = Instant::now();
    let est = estimate_rig(&c, &cal, &EstimateOptions::new(table_4_4())).unwrap();
    eprintln!("estimate {:?}", t0.elapsed());
    for p in &est.report.params {
        eprintln!(
            "{:6} init {:10.4e} est {:10.4e} se {:?} {:?}",
            p.name, p.initial, p.estimate, p.stderr, p.identifiable
        );
    }
    eprintln!("conv {} it {} {}", est.report.converged, est.report.iterations, est.report.stop_reason);
    eprintln!("{:?}", est.report.runs);
    eprintln!("pi {:?}", est.pi);
    eprintln!("fr {:?}", est.friction);
    eprintln!("modes {:?}", est.modes);
    eprintln!("white {:?}", est.report.whiteness.ljung_box_q);
}

#[test]
fn explore_pi() {
    let truth = common::truth();
    for ticks in [1000u32, 1_000_000] {
        common::TICKS_OVERRIDE.with(|c| c.set(ticks));
        let c = common::campaign(&truth, &[], 10.0, &[(20.0, 10.0), (45.0, 4.0), (85.0, 25.0)], 15.0, 1);
        for w in [5usize, 25, 100] {
            let o = rig_estimate::PiOptions { window_samples: w, ..Default::default() };
            let pi = rig_estimate::estimate_pi(&c, 24.0, &o).unwrap();
            eprintln!(
                "ticks {ticks} w {w}: kp {:.4} ± {:.4} ki {:.4} ± {:.4}",
                pi.kp_v_s_rad, pi.kp_stderr, pi.ki_v_rad, pi.ki_stderr
            );
        }
    }
}
