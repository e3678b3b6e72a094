//! The fitting module's tests and the records they share with the crate's other tests.

use super::*;

/// The test records' shaft: J 0.01 kg m2, k 4 N m/rad, c 0.01 N m s/rad on the twist rate.
pub(crate) fn shaft() -> rig_model::one_dof::Shaft {
    rig_model::one_dof::Shaft {
        inertia_kgm2: 0.01,
        stiffness_nm_rad: 4.0,
        twist_damping_nm_s_rad: 0.01,
        absolute_damping_nm_s_rad: 0.0,
        mid: None,
    }
}

/// A record at 1 kHz of these channels (the raw ones equal to them, no dips, no repairs).
pub(crate) fn prepared(time_s: Vec<f64>, top_rpm: Vec<f64>, bit_rpm: Vec<f64>, torque_nm: Vec<f64>) -> Prepared {
    let n = time_s.len();
    Prepared {
        fs_hz: 1000.0,
        time_s,
        top_rpm,
        wob_n: vec![500.0; n],
        bit_raw_rpm: bit_rpm.clone(),
        torque_raw_nm: torque_nm.clone(),
        bit_rpm,
        torque_nm,
        glitches: rig_spectra::stickslip::GlitchReport { runs: 0, samples: 0, longest_run: 0 },
        top_noise_rad_s: 0.0,
        twist_excursion_rad: (0.0, 0.0),
        repairs: Vec::new(),
    }
}

/// 10 s at 1 kHz: bit speed 80 + 60 sin(2π 2 t) rpm, and a torque channel that
/// reads the single-valued law 3 − 0.01 Ω(t − 0.025 s) (late by 25 ms).
fn late_channel() -> (Prepared, WindowSpec) {
    let n = 10_000;
    let time_s: Vec<f64> = (0..n).map(|i| i as f64 / 1000.0).collect();
    let speed = |t: f64| 80.0 + 60.0 * (std::f64::consts::TAU * 2.0 * t).sin();
    let bit_rpm: Vec<f64> = time_s.iter().map(|t| speed(*t)).collect();
    let torque_nm: Vec<f64> = time_s.iter().map(|t| 3.0 - 0.01 * speed(t - 0.025)).collect();
    let d = prepared(time_s, vec![80.0; n], bit_rpm, torque_nm);
    let cal = WindowSpec {
        label: "3-7".into(),
        split: crate::data::Split::Train,
        start_s: 3.0,
        end_s: 7.0,
        span: 2000..7000,
        window: 1000..5000,
    };
    (d, cal)
}

/// The calibration-like window 4-8 s of a 12 s test record at 1 kHz (warm-up from 1 s).
pub(crate) fn window_4_8() -> WindowSpec {
    WindowSpec {
        label: "4-8".into(),
        split: crate::data::Split::Train,
        start_s: 4.0,
        end_s: 8.0,
        span: 1000..8000,
        window: 3000..7000,
    }
}

/// 12 s of stick-slip simulated by the one core (J 0.01 kg m2, k 4 N m/rad, c 0.01 N m s/rad, Coulomb
/// 2.5/1.5 N m, top 2 + sin(2π 0.5 t) rad/s), its contact torque recorded `late` samples late
/// plus `js` times the bit's acceleration; the calibration-like window 4-8 s.
fn simulated_record(late: usize, js: f64) -> (Prepared, WindowSpec, Model) {
    use rig_model::one_dof::{Coulomb, Drive, OneDofState, simulate};
    let (n, fs) = (12_000, 1000.0);
    let top: Vec<f64> = (0..n).map(|i| 2.0 + (std::f64::consts::TAU * 0.5 * i as f64 / fs).sin()).collect();
    let shaft = shaft();
    let law = Coulomb { static_nm: 2.5, kinetic_nm: 1.5 };
    let r = simulate(&shaft, &law, Drive::Speed(&top), None, OneDofState::default(), fs, n, 10).unwrap();
    let torque_nm: Vec<f64> =
        (0..n).map(|i| r.friction_nm[i.saturating_sub(late)] + js * r.accel_rad_s2[i.saturating_sub(late)]).collect();
    let rpm = |x: &[f64]| x.iter().map(|v| v / RPM_TO_RAD_S).collect::<Vec<f64>>();
    let (top_rpm, bit_rpm) = (rpm(&top), rpm(&r.bit_rad_s));
    let d = prepared((0..n).map(|i| i as f64 / fs).collect(), top_rpm, bit_rpm, torque_nm);
    let w = window_4_8();
    let law = FrictionLaw {
        static_nm: 2.5,
        kinetic_nm: 1.5,
        stribeck_speed_rad_s: 0.01,
        shape_exponent: 1.0,
        viscous_nm_s_rad: 0.0,
    };
    let m = Model {
        inertia_kgm2: 0.01,
        stiffness_nm_rad: 4.0,
        damping_nm_s_rad: 0.01,
        torque_delay_s: late as f64 / fs,
        friction: law,
        ..crate::sim::tests::base()
    };
    (d, w, m)
}

#[test]
fn the_balance_reads_a_late_channel_and_sees_what_lies_between() {
    // Read with its delay, the channel is the balance (differences across a stick/slip kink only).
    let (d, w, m) = simulated_record(30, 0.0);
    let on = channel_balance(&d, &w, &m);
    assert!(on.r_squared > 0.99, "{on:?}");
    // Read as recorded (no delay), the same channel is not.
    let off = channel_balance(&d, &w, &Model { torque_delay_s: 0.0, ..m });
    assert!(off.r_squared < on.r_squared - 0.05, "{off:?} {on:?}");
    // With the bit's J known, an inertia of a tenth of it between sensor and contact is left in the residual.
    let (d, w, m) = simulated_record(30, 0.001);
    let js = channel_balance(&d, &w, &m);
    assert!(js.residual_rms_nm > 2.0 * on.residual_rms_nm, "{js:?} {on:?}");
}

#[test]
fn a_late_channel_draws_a_loop_that_its_delay_closes() {
    let (d, cal) = late_channel();
    // As recorded, the torque at a given speed differs between acceleration and deceleration:
    // Ω(t − τ) − Ω(t) ≈ −τ Ω̇, up to 0.01 · 0.025 · 60 · 4π ≈ 0.19 N m apart.
    let raw = loop_spread(&d, &cal, 5.0, 20, 0.0);
    assert!(raw.max_bin_std_nm > 0.05, "{raw:?}");
    // Read 25 ms later it is the law again: the spread left is the law across a bin's width,
    // 0.01 N m/rpm over 140/20 = 7 rpm: a std of 0.07/√12 = 0.020 N m for evenly spread speeds,
    // never above half the bin's torque range, 0.035 N m.
    let aligned = loop_spread(&d, &cal, 5.0, 20, 0.025);
    assert!(aligned.max_bin_std_nm < 0.035 && aligned.rms_bin_std_nm < 0.2 * raw.rms_bin_std_nm, "{aligned:?} {raw:?}");
    let best = narrowest_loop(&d, &cal, 5.0, 20, MAX_DELAY_S);
    assert!((best.shift_s - 0.025).abs() < 1.5e-3, "{best:?}");
}
