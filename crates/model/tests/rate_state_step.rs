//! The rate-and-state implicit step (`one_dof::rate_state_implicit_speed`,
//! `RateStateAgeing`) at the point of the slider's parameter box that made it
//! panic (fifteenth session, docs/findings.md): its Newton search ran out of
//! iterations at the first step and returned a speed that is no root
//! (1.75 m/s from p = 1.3 mm/s), the state θ = Dc/|v| of that speed made s
//! overflow, s sinh u became ∞ − ∞ = NaN and `clamp` with that NaN bound
//! panicked. Every step now solves its equation, and a NaN given to the step
//! comes back as a NaN (the integrator's error), never a panic.

use rig_model::one_dof::{
    Drive, ImplicitFriction, OneDofState, RateStateAgeing, Shaft, rate_state_implicit_speed, simulate_implicit,
};

const MASS_KG: f64 = 0.0307;
const WEIGHT_N: f64 = MASS_KG * 9.81;
const STIFFNESS_N_M: f64 = 2254.0;
const DRIVE_M_S: f64 = 4300e-6;
const FS_HZ: f64 = 2000.0;

/// rate_state_ageing at the ninth point of the Halton design over the
/// slider's box (μ0 0.5375, a 1.186e-3, b − a 0.0331, Dc 0.829 µm), v* = 1e-4 m/s.
fn law() -> RateStateAgeing {
    let a = 1e-3 * 100f64.powf(1.0 / 27.0);
    RateStateAgeing {
        normal_nm: WEIGHT_N,
        mu0: 0.2 + 0.6 * 9.0 / 16.0,
        a,
        b: a + 1e-4 * 1000f64.powf(21.0 / 25.0),
        dc_rad: 1e-7 * 1000f64.powf(15.0 / 49.0),
        v_ref_rad_s: 1e-4,
    }
}

/// The slider's set-up at k2254-v4300 (rig_slider::sim::simulate_more): the
/// stated mass on the spring, undamped, from rest with the spring at μ0, at
/// least 50 steps per natural period in whole steps per sample (2).
fn run(samples: usize) -> Result<rig_model::one_dof::OneDofRun, rig_model::ModelError> {
    let law = law();
    let shaft = Shaft {
        inertia_kgm2: MASS_KG,
        stiffness_nm_rad: STIFFNESS_N_M,
        twist_damping_nm_s_rad: 0.0,
        absolute_damping_nm_s_rad: 0.0,
        mid: None,
    };
    let period_s = 2.0 * std::f64::consts::PI * (MASS_KG / STIFFNESS_N_M).sqrt();
    let substeps = ((1.0 / FS_HZ / (period_s / 50.0)).ceil() as usize).max(1);
    assert_eq!(substeps, 2);
    let start = OneDofState {
        twist_rad: law.mu0 * WEIGHT_N / STIFFNESS_N_M,
        stuck: true,
        friction_state: law.initial_state(DRIVE_M_S),
        ..OneDofState::default()
    };
    simulate_implicit(&shaft, &law, Drive::ConstantSpeed(DRIVE_M_S), start, FS_HZ, samples, substeps)
}

#[test]
fn the_slider_point_that_panicked_runs_a_physical_stick_slip() {
    // Before the fix: a panic at sample 11 (one_dof.rs, `clamp` with a NaN bound).
    let run = run(4000).expect("a law inside the slider's bounds runs");
    let (v_max, f) = (
        run.bit_rad_s.iter().fold(0f64, |m, v| m.max(v.abs())),
        run.twist_rad.iter().map(|t| t * STIFFNESS_N_M / WEIGHT_N).collect::<Vec<_>>(),
    );
    // The slider released from μ0 moves at most V + ω φ0 ≈ 24 mm/s (it ran at 1.75 m/s).
    assert!(v_max < 0.03, "max speed {v_max} m/s");
    let (lo, hi) = f.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
    assert!(lo > 0.0 && hi < 1.0, "force over weight in [{lo}, {hi}]");
}

/// The first step of that run: from u = 0 the first Newton step lands at
/// p/(hn a) ≈ 453, a hundred above the root, and the descent from there
/// took more than the 100 iterations.
#[test]
fn the_first_step_from_rest_solves_its_equation() {
    let law = law();
    let hn = 2.5e-4 / MASS_KG * WEIGHT_N;
    let theta = law.dc_rad / DRIVE_M_S;
    let psi = law.mu0 + law.b * (law.v_ref_rad_s * theta / law.dc_rad).ln();
    let ln_s = (2.0 * law.v_ref_rad_s).ln() - psi / law.a;
    let p = 1.3182187500000002e-3;
    let (v, u) = rate_state_implicit_speed(p, hn, law.a, ln_s, 0.0);
    assert!(v > 0.0 && v < p, "v {v} for p {p}");
    let r = v + hn * law.a * u - p;
    assert!(r.abs() < 1e-12 * p, "residual {r}");
    assert!((u - ((v.ln() - ln_s).exp()).asinh()).abs() < 1e-9 * u, "u {u}");
}

#[test]
fn a_nan_or_an_overflowing_s_is_no_panic() {
    // A NaN momentum or state (a substep after one that left the physical
    // range): a NaN speed, which the integrator's check refuses.
    assert!(rate_state_implicit_speed(f64::NAN, 1e-3, 0.01, -10.0, 1.0).0.is_nan());
    assert!(rate_state_implicit_speed(1e-3, 1e-3, 0.01, f64::NAN, 1.0).0.is_nan());
    // s = e^1028 (a contact as young as θ = 3.5e-25 s): no friction left,
    // v = p to the last digit, where ½(e^{u + ln s} − e^{ln s − u}) was ∞ − ∞.
    for (p, guess) in [(2.35e18, 0.0), (-1e-3, 5.0)] {
        let (v, u) = rate_state_implicit_speed(p, 2.45e-3, 1.186e-3, 1028.0, guess);
        assert_eq!(v, p);
        assert!(u.is_finite() && u >= 0.0, "u {u}");
    }
}
