//! The 1-DOF core's tests: explicit and implicit runs, batches to the bit.

use super::*;

const FS: f64 = 1000.0;

fn shaft() -> Shaft {
    Shaft {
        inertia_kgm2: 0.05,
        stiffness_nm_rad: 2.0,
        twist_damping_nm_s_rad: 0.02,
        absolute_damping_nm_s_rad: 0.0,
        mid: None,
    }
}

const LAW: Coulomb = Coulomb { static_nm: 1.8, kinetic_nm: 1.0 };

#[test]
fn steady_slip_is_the_exact_fixed_point() {
    // Constant top speed 20 rad/s: the oscillation decays (ζ = 0.032, decay time
    // 2J/c = 5 s; 60 s leave e^{-12}); then Ω = 20 and k φ = T_k + c_a Ω.
    for ca in [0.0, 0.01] {
        let sh = Shaft { absolute_damping_nm_s_rad: ca, ..shaft() };
        // Started 0.01 rad off the fixed point: 0.01 e^{-12} is left.
        let start = OneDofState { bit_rad_s: 20.0, twist_rad: (1.0 + ca * 20.0) / 2.0 + 0.01, ..Default::default() };
        let r = simulate(&sh, &LAW, Drive::ConstantSpeed(20.0), None, start, FS, 60_000, 5).unwrap();
        let n = r.bit_rad_s.len() - 1;
        let om = r.bit_rad_s[n];
        // With c_a the bit lags: J·0 = kφ + c(20 − Ω) − c_a Ω − T_k and φ constant ⇒ Ω = 20.
        assert!((om - 20.0).abs() < 1e-6, "{om}");
        assert!((r.twist_rad[n] - (1.0 + ca * 20.0) / 2.0).abs() < 1e-6, "{}", r.twist_rad[n]);
        assert!((r.friction_nm[n] - 1.0).abs() < 1e-12);
    }
}

#[test]
fn slow_drive_sticks_and_slips_at_the_coulomb_period() {
    // Undamped Coulomb stick-slip driven at v: stuck until kφ = T_s, then a slip
    // half-cycle of the harmonic oscillator about φ_k = T_k/k with amplitude
    // (T_s − T_k)/k, ending (Ω = 0) at φ = (2T_k − T_s)/k; stuck again while the
    // drive winds 2(T_s − T_k)/k. Period: π√(J/k) + 2(T_s − T_k)/(k v) (v ≪ amplitude·ω_n).
    let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
    let v = 0.2;
    let start = OneDofState { stuck: true, ..Default::default() };
    let r = simulate(&sh, &LAW, Drive::ConstantSpeed(v), None, start, FS, 30_000, 10).unwrap();
    let onsets: Vec<usize> = (1..r.stuck.len()).filter(|&i| r.stuck[i - 1] && !r.stuck[i]).collect();
    assert!(onsets.len() >= 4, "{onsets:?}");
    let period = (onsets[onsets.len() - 1] - onsets[1]) as f64 / FS / (onsets.len() - 2) as f64;
    let slip = std::f64::consts::PI * (0.05f64 / 2.0).sqrt();
    // The slip starts with Ω = v ≠ 0 (the drive winds on): the half-cycle is slightly
    // longer than π√(J/k); bound the period between the two idealisations.
    let expect = slip + 2.0 * 0.8 / (2.0 * v);
    assert!((period / expect - 1.0).abs() < 0.03, "{period} vs {expect}");
    // The contact never holds more than its static level.
    assert!(r.friction_nm.iter().all(|t| t.abs() <= 1.8 + 1e-9));
}

#[test]
fn a_speed_series_and_a_constant_speed_agree() {
    let u = vec![3.0; 5000];
    let start = OneDofState { bit_rad_s: 3.0, twist_rad: 0.4, ..Default::default() };
    let a = simulate(&shaft(), &LAW, Drive::Speed(&u), None, start, FS, 5000, 5).unwrap();
    let b = simulate(&shaft(), &LAW, Drive::ConstantSpeed(3.0), None, start, FS, 5000, 5).unwrap();
    assert_eq!(a, b);
}

#[test]
fn the_extensions_run_and_bad_input_is_refused() {
    let sh = Shaft { mid: Some(MidInertia { inertia_kgm2: 0.02, split: 0.5 }), ..shaft() };
    let u = vec![3.0; 10_000];
    let g = vec![1.1; 10_000];
    let drive = Drive::SpeedLoop { inertia_kgm2: 0.1, kp_nm_s_rad: 2.0, ki_nm_rad: 5.0, reference_rad_s: &u };
    let start = OneDofState { top_rad_s: 3.0, ..Default::default() };
    let r = simulate(&sh, &LAW, drive, Some(&g), start, FS, 10_000, 5).unwrap();
    // The loop's integral makes the mean top speed follow its reference.
    let tail = &r.top_rad_s[5000..];
    assert!((tail.iter().sum::<f64>() / tail.len() as f64 - 3.0).abs() < 0.1);
    let bad = Shaft { inertia_kgm2: 0.0, ..shaft() };
    assert!(simulate(&bad, &LAW, Drive::ConstantSpeed(1.0), None, start, FS, 10, 1).is_err());
    assert!(simulate(&shaft(), &LAW, Drive::Speed(&u[..5]), None, start, FS, 10, 1).is_err());
}

/// A law with a static level, a falling slip level and a first-order lag
/// (every branch of the core's contact: the state stepped stuck, at
/// break-away and in slip).
struct Lagged;

impl Friction for Lagged {
    fn static_nm(&self, scale: f64, _: &[f64; MAX_FRICTION_STATES]) -> Option<f64> {
        Some(scale * 1.8)
    }
    fn slip_nm(&self, _: f64, _: f64, state: &[f64; MAX_FRICTION_STATES]) -> f64 {
        state[0]
    }
    fn step_state(&self, state: &mut [f64; MAX_FRICTION_STATES], speed: f64, scale: f64, held: Option<f64>, h: f64) {
        let target = held.unwrap_or_else(|| scale * (1.0 + 0.8 * (-speed / 0.5).exp()));
        state[0] += if held.is_some() { 1.0 } else { (h / 0.01).min(1.0) } * (target - state[0]);
    }
}

#[test]
fn a_batch_gives_each_run_its_single_runs_bits() {
    // Runs of every kind, of different lengths, one refused and one that diverges:
    // in one batch each is bit for bit the run `simulate` makes of it alone, whatever
    // its neighbours (the batch reversed as well).
    let n = 6_000;
    let wavy: Vec<f64> = (0..n).map(|i| 1.0 + 0.8 * (i as f64 * 0.003).sin()).collect();
    let g: Vec<f64> = (0..n).map(|i| 1.0 + 0.2 * (i as f64 * 0.001).cos()).collect();
    let mid = Shaft { mid: Some(MidInertia { inertia_kgm2: 0.02, split: 0.4 }), ..shaft() };
    let soft = Shaft { inertia_kgm2: 1e-9, ..shaft() };
    let stuck = OneDofState { stuck: true, friction_state: [1.8, 0.0], ..Default::default() };
    let moving = OneDofState { bit_rad_s: 0.7, twist_rad: 0.6, top_rad_s: 1.0, ..Default::default() };
    let job = |shaft: Shaft, drive: Drive<'static>, scale: Option<&'static [f64]>, start, samples| OneDofJob {
        shaft,
        law: &Lagged,
        drive,
        normal_scale: scale,
        start,
        samples,
    };
    let (wavy, g): (&'static [f64], &'static [f64]) = (wavy.leak(), g.leak());
    let loop_drive =
        Drive::SpeedLoop { inertia_kgm2: 0.1, kp_nm_s_rad: 2.0, ki_nm_rad: 5.0, reference_rad_s: &wavy[..4_000] };
    let jobs = [
        job(shaft(), Drive::Speed(wavy), None, stuck, n),
        job(shaft(), Drive::Speed(wavy), Some(g), moving, n),
        job(mid, loop_drive, Some(&g[..4_000]), moving, 4_000),
        job(shaft(), Drive::ConstantSpeed(0.3), None, stuck, 2_500),
        job(shaft(), Drive::Speed(&wavy[..10]), None, stuck, n),
        job(soft, Drive::ConstantSpeed(50.0), None, moving, n),
    ];
    let alone: Vec<Result<OneDofRun, ModelError>> =
        jobs.iter().map(|j| simulate(&j.shaft, j.law, j.drive, j.normal_scale, j.start, FS, j.samples, 5)).collect();
    assert!(alone[..4].iter().all(|r| r.is_ok()) && alone[4].is_err(), "four runs, one refusal");
    assert!(matches!(alone[5], Err(ModelError::IntegratorFailed { .. })), "{:?}", alone[5].as_ref().err());
    let stuck_samples = alone[0].as_ref().unwrap().stuck.iter().filter(|s| **s).count();
    assert!(stuck_samples > 100 && stuck_samples < n - 100, "stick-slip: {stuck_samples} stuck samples");
    let bits = |r: &Result<OneDofRun, ModelError>| match r {
        Ok(r) => {
            format!(
                "{:?}",
                [&r.bit_rad_s, &r.top_rad_s, &r.twist_rad, &r.friction_nm, &r.accel_rad_s2]
                    .map(|c| c.iter().map(|v| v.to_bits()).collect::<Vec<u64>>())
            ) + &format!("{:?}", r.stuck)
        }
        Err(e) => format!("{e:?}"),
    };
    let batch = simulate_batch(&jobs, FS, 5);
    let mut reversed = jobs;
    reversed.reverse();
    let mut back = simulate_batch(&reversed, FS, 5);
    back.reverse();
    for (i, r) in alone.iter().enumerate() {
        assert_eq!(bits(&batch[i]), bits(r), "job {i} in the batch");
        assert_eq!(bits(&back[i]), bits(r), "job {i} in the batch reversed");
    }
}

#[test]
fn rate_state_implicit_speed_solves_its_equation() {
    for &(p, hn, a, s) in &[(1e-3, 1e-3, 0.01, 1e-12), (-2e-4, 5e-4, 0.02, 1e-6), (5e-2, 1e-3, 0.005, 1e-3)] {
        for guess in [f64::INFINITY, 0.0, 3.0, 40.0] {
            let (v, _) = rate_state_implicit_speed(p, hn, a, f64::ln(s), guess);
            let r = v + hn * a * (v / s).asinh() - p;
            assert!(r.abs() < 1e-12 * p.abs().max(1e-9), "residual {r} from {guess}");
        }
    }
    // A long-aged contact: s = e^{-800} underflows; v stays finite and solves the equation.
    for guess in [0.0, 900.0] {
        let (v, u) = rate_state_implicit_speed(1e-3, 1e-3, 0.01, -800.0, guess);
        assert!(v.is_finite() && v > 0.0, "{v}");
        let r = v + 1e-3 * 0.01 * u - 1e-3;
        assert!(r.abs() < 1e-15 && (u - ((2.0 * v).ln() + 800.0)).abs() < 1e-9, "residual {r}, u {u}");
    }
}

#[test]
fn implicit_coulomb_sticks_and_slips_at_the_closed_form_levels() {
    // Undamped Coulomb stick-slip: the contact breaks away at the static level
    // T_s; the slip is an oscillation about T_k with amplitude
    // k √(D² + (v/ω)²), D = (T_s − T_k)/k (the drive keeps winding while the
    // bit starts from rest), so the torque peaks just above T_s and the slip
    // ends as far below T_k.
    let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
    let start = OneDofState { stuck: true, ..Default::default() };
    let r = simulate_implicit(&sh, &LAW, Drive::ConstantSpeed(0.2), start, FS, 30_000, 10).unwrap();
    let torque: Vec<f64> = r.twist_rad.iter().map(|p| sh.stiffness_nm_rad * p).collect();
    let max = torque.iter().cloned().fold(f64::MIN, f64::max);
    let min = torque[10_000..].iter().cloned().fold(f64::MAX, f64::min);
    let amplitude = sh.stiffness_nm_rad * (0.4f64.powi(2) + (0.2f64 / (2.0f64 / 0.05).sqrt()).powi(2)).sqrt();
    assert!((max - (1.0 + amplitude)).abs() < 1e-3, "peak {max} vs {}", 1.0 + amplitude);
    assert!((min - (1.0 - amplitude)).abs() < 1e-3, "end of slip {min} vs {}", 1.0 - amplitude);
    let bad = Shaft { mid: Some(MidInertia { inertia_kgm2: 0.02, split: 0.5 }), ..shaft() };
    assert!(simulate_implicit(&bad, &LAW, Drive::ConstantSpeed(0.2), start, FS, 10, 1).is_err());
}

#[test]
fn an_implicit_run_made_in_pieces_is_the_run_made_at_once() {
    // Stick-slip with rate and state (a friction state carried across the
    // pieces) and with Coulomb (the stuck flag): every channel bit for bit.
    let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
    let rs = RateStateAgeing { normal_nm: 1.0, mu0: 1.0, a: 0.01, b: 0.015, dc_rad: 1e-3, v_ref_rad_s: 0.1 };
    let drive = Drive::ConstantSpeed(0.2);
    let start =
        OneDofState { stuck: true, twist_rad: 0.5, friction_state: rs.initial_state(0.2), ..Default::default() };
    let whole = simulate_implicit(&sh, &rs, drive, start, FS, 9_000, 4).unwrap();
    let (mut run, mut state) = (OneDofRun::default(), start);
    for n in [2, 1_000, 1_001, 5_000, 9_000] {
        simulate_implicit_extend(&sh, &rs, drive, &mut state, FS, n, 4, &mut run).unwrap();
        assert_eq!(run.twist_rad.len(), n);
    }
    assert_eq!(run, whole);
    let (lo, hi) = whole.bit_rad_s.iter().fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    assert!(hi - lo > 0.1, "the bit's speed moves: {lo}..{hi}");
    let whole = simulate_implicit(&sh, &LAW, drive, start, FS, 6_000, 4).unwrap();
    let (mut run, mut state) = (OneDofRun::default(), start);
    for n in [3_000, 6_000] {
        simulate_implicit_extend(&sh, &LAW, drive, &mut state, FS, n, 4, &mut run).unwrap();
    }
    assert_eq!(run, whole);
}

#[test]
fn a_sink_that_keeps_the_twist_alone_gets_the_runs_twist() {
    // The steps do not depend on where the samples go: a sink keeping one
    // channel, filled in pieces, holds the full run's twist bit for bit.
    struct Twist(Vec<f64>);
    impl ImplicitSink for Twist {
        fn samples(&self) -> usize {
            self.0.len()
        }
        fn reserve(&mut self, more: usize) {
            self.0.reserve(more);
        }
        fn push(&mut self, s: &OneDofState, _: f64, _: f64) {
            self.0.push(s.twist_rad);
        }
    }
    let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
    let rs = RateStateAgeing { normal_nm: 1.0, mu0: 1.0, a: 0.01, b: 0.015, dc_rad: 1e-3, v_ref_rad_s: 0.1 };
    let drive = Drive::ConstantSpeed(0.2);
    let start =
        OneDofState { stuck: true, twist_rad: 0.5, friction_state: rs.initial_state(0.2), ..Default::default() };
    let whole = simulate_implicit(&sh, &rs, drive, start, FS, 9_000, 4).unwrap();
    let (mut twist, mut state) = (Twist(Vec::new()), start);
    for n in [2, 4_000, 9_000] {
        simulate_implicit_extend(&sh, &rs, drive, &mut state, FS, n, 4, &mut twist).unwrap();
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    assert_eq!(bits(&twist.0), bits(&whole.twist_rad));
    let (lo, hi) = whole.twist_rad.iter().fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    assert!(hi - lo > 0.01, "the twist moves: {lo}..{hi}");
}

#[test]
fn the_overflow_bound_is_exps() {
    use super::implicit::LN_S_OVERFLOW;
    assert_eq!(LN_S_OVERFLOW.to_bits(), 0x4086_2E42_FEFA_39EF);
    assert!(LN_S_OVERFLOW.exp().is_finite() && LN_S_OVERFLOW.next_up().exp() == f64::INFINITY);
    let mut x = LN_S_OVERFLOW;
    for _ in 0..1000 {
        x = x.next_down();
        assert!(x.exp().is_finite());
    }
    for x in [-1e300, -745.2, 0.0, 700.0, 709.0, 709.78, 710.0, 1e4, f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
        assert_eq!(x.exp() == f64::INFINITY, x > LN_S_OVERFLOW, "{x}");
    }
}
