//! The slider's dynamics, one file behind a small interface ([`Law`],
//! [`Setup`], [`simulate`]): m ẍ = k (V t − x) − m g μ, the recorded signal
//! being the spring force over weight k (V t − x)/(m g).
//!
//! This is the equation of the chapter's rotor on its shaft with the brake
//! (Eq. 4-6 with one inertia, the shaft's stiffness and an imposed drive
//! angle) in translation. It is written here, not on `rig_model::one_dof`,
//! because that core is being made the one 1-DOF simulator of every
//! imposed-drive rig by another engineer while this crate is written: the
//! plan is to move [`simulate`] onto it, keeping this interface, once it can
//! carry a state variable (θ below) and a set-valued stick phase.
//!
//! Scheme: symplectic Euler with the friction implicit in the new velocity
//! (Moreau's time stepping): v⁺ + h g μ(v⁺, θ) = v + h k (V t − x)/m,
//! x⁺ = x + h v⁺. The linear oscillator keeps its energy on average (no
//! numerical damping of the inertial oscillation; period error (ωh)²/24,
//! 0.2 % at 100 steps per natural period), and a stiff friction law (the
//! rate-and-state law at creep speeds, m g a/(m v) ≈ 10⁸ s⁻¹) is stable.
//! - Coulomb: stick (v⁺ = 0) while the spring force stays within μs m g,
//!   slip at μk m g, sticking again when v⁺ would change sign.
//! - Static ageing: as Coulomb, but the threshold grows with the time stuck,
//!   μs(t) = μs0 + β ln(1 + t/τ) (Heslot et al. 1994's heuristic law of the
//!   static threshold; Baumberger & Caroli 2006, §2), and slip runs on a
//!   velocity-strengthening kinetic law μk(v) = μk0 + α ln(1 + v/v1).
//! - Rate and state (Dieterich–Ruina, ageing law; Baumberger & Caroli 2006,
//!   Eqs. 3–4 as we read them): μ = μ0 + a ln(v/v*) + b ln(v* θ/Dc),
//!   dθ/dt = 1 − v θ/Dc, in the regularised form μ = a asinh(v/(2v*)
//!   e^{(μ0 + b ln(v*θ/Dc))/a}) (Rice, Lapusta & Ranjith 2001) that is finite
//!   at v = 0; θ advances exactly for the step's constant v⁺.

/// A friction law, parameters dimensionless (μ) or in the units of their names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// Static μs, kinetic μk (the baseline).
    Coulomb { mu_static: f64, mu_kinetic: f64 },
    /// μs(t_stuck) = μs0 + β ln(1 + t/τ); μk(v) = μk0 + α ln(1 + v/v1).
    StaticAgeing { mu_static0: f64, ageing_beta: f64, ageing_time_s: f64, mu_kinetic0: f64, alpha: f64, v1_m_s: f64 },
    /// Dieterich–Ruina with the ageing law; μ0 at the reference speed v*.
    RateState { mu0: f64, a: f64, b: f64, dc_m: f64, v_ref_m_s: f64 },
}

/// What one run imposes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    pub stiffness_n_m: f64,
    pub drive_speed_m_s: f64,
    pub mass_kg: f64,
    pub gravity_m_s2: f64,
    /// Simulated time, s (from rest, spring relaxed).
    pub duration_s: f64,
    /// Output rate, Hz (the recording's, so one feature function serves both).
    pub sample_rate_hz: f64,
    /// Integration steps per natural period 2π √(m/k).
    pub steps_per_period: f64,
    /// Spring force over weight at t = 0, slider at rest (a preloaded spring
    /// skips the first loading from zero, which carries no information).
    pub initial_force_over_weight: f64,
}

impl Setup {
    /// Natural period 2π √(m/k), s.
    pub fn natural_period_s(&self) -> f64 {
        2.0 * std::f64::consts::PI * (self.mass_kg / self.stiffness_n_m).sqrt()
    }
}

impl Law {
    /// The law's friction level while sliding (μk, μk0 or μ0): where a
    /// simulation starts its spring.
    pub fn sliding_level(&self) -> f64 {
        match *self {
            Law::Coulomb { mu_kinetic, .. } => mu_kinetic,
            Law::StaticAgeing { mu_kinetic0, .. } => mu_kinetic0,
            Law::RateState { mu0, .. } => mu0,
        }
    }
}

/// Spring force over weight at `sample_rate_hz` over `duration_s`, from rest
/// with the spring preloaded to `initial_force_over_weight` (the drive starts
/// at t = 0).
pub fn simulate(law: &Law, s: &Setup) -> Vec<f64> {
    let n_out = (s.duration_s * s.sample_rate_hz).floor() as usize;
    let dt_out = 1.0 / s.sample_rate_hz;
    // An integer number of steps per output sample, at least the requested density.
    let sub = ((dt_out / (s.natural_period_s() / s.steps_per_period)).ceil() as usize).max(1);
    let h = dt_out / sub as f64;
    let (k_m, g) = (s.stiffness_n_m / s.mass_kg, s.gravity_m_s2);
    let to_fw = s.stiffness_n_m / (s.mass_kg * g);
    let (mut x, mut v) = (-s.initial_force_over_weight / to_fw, 0.0f64);
    let mut stuck = true;
    let mut stuck_s = 0.0f64;
    // θ at rest from a long hold: start at the steady state of the drive speed.
    let mut theta = match law {
        Law::RateState { dc_m, .. } => dc_m / s.drive_speed_m_s,
        _ => 0.0,
    };
    let mut out = Vec::with_capacity(n_out);
    let mut t = 0.0f64;
    for i in 0..n_out {
        if i > 0 {
            for _ in 0..sub {
                let p = v + h * k_m * (s.drive_speed_m_s * t - x);
                v = match *law {
                    Law::Coulomb { mu_static, mu_kinetic } => {
                        coulomb_step(p, h * g, mu_static, |_| mu_kinetic, &mut stuck)
                    }
                    Law::StaticAgeing { mu_static0, ageing_beta, ageing_time_s, mu_kinetic0, alpha, v1_m_s } => {
                        let mu_s = mu_static0 + ageing_beta * (1.0 + stuck_s / ageing_time_s).ln();
                        let v =
                            coulomb_step(p, h * g, mu_s, |v| mu_kinetic0 + alpha * (1.0 + v / v1_m_s).ln(), &mut stuck);
                        stuck_s = if stuck { stuck_s + h } else { 0.0 };
                        v
                    }
                    Law::RateState { mu0, a, b, dc_m, v_ref_m_s } => {
                        let psi = mu0 + b * (v_ref_m_s * theta / dc_m).ln();
                        let v = rate_state_velocity(p, h * g, a, 2.0 * v_ref_m_s * (-psi / a).exp());
                        theta = age(theta, v.abs(), h, dc_m);
                        v
                    }
                };
                x += h * v;
                t += h;
            }
        }
        out.push(to_fw * (s.drive_speed_m_s * t - x));
    }
    out
}

/// One implicit Coulomb step: `p` the velocity the spring alone would give,
/// `hg` = h g. Sticks when friction within the static (stuck) or kinetic
/// (sliding) bound can hold v⁺ = 0; else slides at the kinetic law, solved
/// for v⁺ by a few fixed-point passes (the law varies slowly with v).
fn coulomb_step(p: f64, hg: f64, mu_static: f64, mu_kinetic: impl Fn(f64) -> f64, stuck: &mut bool) -> f64 {
    let bound = if *stuck { mu_static } else { mu_kinetic(0.0) };
    if p.abs() <= hg * bound {
        *stuck = true;
        return 0.0;
    }
    *stuck = false;
    let mut v = p - hg * mu_kinetic(0.0) * p.signum();
    for _ in 0..3 {
        let next = p - hg * mu_kinetic(v.abs()) * p.signum();
        if next.signum() != p.signum() {
            *stuck = true;
            return 0.0;
        }
        v = next;
    }
    v
}

/// Solves v + hg a asinh(v/s) = p for v (s = 2 v* e^{−ψ/a}) through
/// u = asinh(v/s): f(u) = s sinh u + hg a u − p is increasing and convex for
/// u > 0, so Newton from above converges monotonically.
fn rate_state_velocity(p: f64, hg: f64, a: f64, s: f64) -> f64 {
    let (sign, p) = (p.signum(), p.abs());
    if p == 0.0 {
        return 0.0;
    }
    let c = hg * a;
    let mut u = (p / c).min((p / s).asinh());
    for _ in 0..60 {
        let f = s * u.sinh() + c * u - p;
        let step = f / (s * u.cosh() + c);
        u -= step;
        if step.abs() <= 1e-12 * u.abs().max(1e-300) {
            break;
        }
    }
    sign * s * u.sinh()
}

/// The ageing law dθ/dt = 1 − v θ/Dc advanced exactly over `h` at constant v.
fn age(theta: f64, v: f64, h: f64, dc: f64) -> f64 {
    let r = v * h / dc;
    if r < 1e-9 {
        return theta + h * (1.0 - v * theta / dc);
    }
    let ss = dc / v;
    ss + (theta - ss) * (-r).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup(k: f64, v_um_s: f64, dur: f64) -> Setup {
        Setup {
            stiffness_n_m: k,
            drive_speed_m_s: v_um_s * 1e-6,
            mass_kg: 0.0307,
            gravity_m_s2: 9.81,
            duration_s: dur,
            sample_rate_hz: 2000.0,
            steps_per_period: 100.0,
            initial_force_over_weight: 0.0,
        }
    }

    #[test]
    fn coulomb_stick_slip_matches_the_closed_form() {
        // Undamped Coulomb stick-slip: slip at μs, drop 2(μs − μk) when V ≪ ω Δx,
        // period = stick time 2(μs − μk) m g/(k V) + slip time ≈ T0/2.
        let s = setup(168.0, 42.0, 20.0);
        let f = simulate(&Law::Coulomb { mu_static: 0.4, mu_kinetic: 0.35 }, &s);
        let max = f.iter().cloned().fold(f64::MIN, f64::max);
        assert!((max - 0.4).abs() < 2e-3, "peak {max}");
        let after_first = f.iter().position(|&y| y > 0.399).unwrap() + 200;
        let min = f[after_first..].iter().cloned().fold(f64::MAX, f64::min);
        assert!((min - 0.30).abs() < 3e-3, "trough {min}");
    }

    #[test]
    fn rate_state_velocity_solves_its_equation() {
        for &(p, hg, a, s) in &[(1e-3, 1e-3, 0.01, 1e-12), (-2e-4, 5e-4, 0.02, 1e-6), (5e-2, 1e-3, 0.005, 1e-3)] {
            let v = rate_state_velocity(p, hg, a, s);
            let r = v + hg * a * (v / s).asinh() - p;
            assert!(r.abs() < 1e-12 * p.abs().max(1e-9), "residual {r}");
        }
    }
}
