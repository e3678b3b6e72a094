//! The slider's dynamics on the one 1-DOF simulator core,
//! `rig_model::one_dof::simulate_implicit`: m ẍ = k (V t − x) − m g μ, the
//! recorded signal being the spring force over weight k (V t − x)/(m g).
//!
//! With a set-up other than the README's ([`Structure`]) m becomes the mass
//! that oscillates, m_eff, and k the chain's stiffness, k_eff: m_eff ẍ =
//! k_eff (V t − x) − m g μ, recorded as k_eff (V t − x)/(m g).
//!
//! This is the equation of the chapter's rotor on its shaft with the brake
//! (Eq. 4-6 with one inertia, the shaft's stiffness and an imposed drive
//! angle) in translation, which is `one_dof`'s equation with J = m, k the
//! spring, the twist φ = V t − x the spring's extension (m), Ω the slider's
//! speed (m/s), no damping and the friction force N μ, N = m g. The laws are
//! [`Law`]'s; each maps onto one_dof's implicit contact
//! ([`one_dof::ImplicitFriction`]: Moreau's time stepping, friction implicit
//! in the new speed, symplectic Euler for the oscillator, period error
//! (ωh)²/24, 0.07 % at 50 steps per natural period; a stiff law, rate and
//! state at creep speeds with m g a/(m v) ≈ 10⁸ s⁻¹, stays stable).
//! - Coulomb: stick (v⁺ = 0) while the spring force stays within μs m g,
//!   slip at μk m g, sticking again when v⁺ would change sign
//!   (`one_dof::implicit_coulomb_step`).
//! - Static ageing: as Coulomb, but the threshold grows with the time stuck,
//!   μs(t) = μs0 + β ln(1 + t/τ) (Heslot et al. 1994's heuristic law of the
//!   static threshold; Baumberger & Caroli 2006, §2), and slip runs on a
//!   velocity-strengthening kinetic law μk(v) = μk0 + α ln(1 + v/v1).
//! - Rate and state (Dieterich–Ruina, ageing law; Baumberger & Caroli 2006):
//!   `one_dof::RateStateAgeing`, μ = μ0 + a ln(v/v*) + b ln(v* θ/Dc),
//!   dθ/dt = 1 − v θ/Dc, regularised at v = 0 (Rice, Lapusta & Ranjith 2001).
//! - Rate and state with Ruina's slip law ([`crate::slip`]): the same
//!   friction, dθ/dt = −(v θ/Dc) ln(v θ/Dc).

use rig_model::ModelError;
use rig_model::one_dof::{
    self, Drive, ImplicitFriction, ImplicitSink, MAX_FRICTION_STATES, OneDofState, RateStateAgeing, Shaft,
};
/// A friction law, parameters dimensionless (μ) or in the units of their names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// Static μs, kinetic μk (the baseline).
    Coulomb { mu_static: f64, mu_kinetic: f64 },
    /// μs(t_stuck) = μs0 + β ln(1 + t/τ); μk(v) = μk0 + α ln(1 + v/v1).
    StaticAgeing { mu_static0: f64, ageing_beta: f64, ageing_time_s: f64, mu_kinetic0: f64, alpha: f64, v1_m_s: f64 },
    /// Dieterich–Ruina with the ageing law; μ0 at the reference speed v*.
    RateState { mu0: f64, a: f64, b: f64, dc_m: f64, v_ref_m_s: f64 },
    /// Dieterich–Ruina with Ruina's slip law ([`crate::slip`]).
    RateStateSlip(crate::slip::Slip),
    /// Heslot et al. 1994's law, the velocity and the age cut off at small
    /// values ([`crate::heslot`]).
    Heslot(crate::heslot::Heslot),
    /// Coulomb with a threshold that varies along the track ([`crate::track`]).
    Track(crate::track::Track),
}

/// The set-up as the simulation sees it, beside the friction law: the mass
/// that oscillates and the spring the force is read through, from the
/// stated (README) mass m and stiffness k. The normal load stays the
/// slider's weight m g and the recorded force stays over m g in every case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Structure {
    /// The README's: the slider's mass m on the stated spring k.
    Stated,
    /// The mass that oscillates is m_eff = r m: more than m when part of the
    /// spring moves with the slider (a uniform spring adds a third of its own
    /// mass, Rayleigh's estimate), less than m only if part of the weighed
    /// mass does not move with the slider.
    /// A spring r times stiffer than stated, read through its extension and
    /// the stated k (the channel's reading), is this with m_eff = m/r and the
    /// law's coefficients over r (`fit::SetupCandidate`).
    EffectiveMass { mass_ratio: f64 },
    /// A compliance in series with the spring (the force sensor, the loading
    /// stage): the chain is 1/k_eff = 1/k + 1/k_s, the same k_s whichever
    /// spring is mounted; the force through the chain is k_eff (V t − x).
    SeriesCompliance { series_stiffness_n_m: f64 },
}

impl Structure {
    /// (the mass that oscillates, kg; the chain's stiffness, N/m) for the stated m and k.
    pub fn effective(&self, mass_kg: f64, stiffness_n_m: f64) -> (f64, f64) {
        match *self {
            Structure::Stated => (mass_kg, stiffness_n_m),
            Structure::EffectiveMass { mass_ratio } => (mass_ratio * mass_kg, stiffness_n_m),
            Structure::SeriesCompliance { series_stiffness_n_m: ks } => {
                (mass_kg, stiffness_n_m * ks / (stiffness_n_m + ks))
            }
        }
    }
}

/// What one run imposes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// The stated spring (the run's file name), N/m.
    pub stiffness_n_m: f64,
    pub drive_speed_m_s: f64,
    /// The stated slider mass (the README's), kg: the normal load is its weight.
    pub mass_kg: f64,
    pub gravity_m_s2: f64,
    /// How the set-up departs from the stated m and k.
    pub structure: Structure,
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
    /// Natural period of the set-up as modelled, 2π √(m_eff/k_eff), s.
    pub fn natural_period_s(&self) -> f64 {
        let (m, k) = self.structure.effective(self.mass_kg, self.stiffness_n_m);
        2.0 * std::f64::consts::PI * (m / k).sqrt()
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
            Law::RateStateSlip(l) => l.mu0,
            Law::Heslot(h) => h.mu0,
            Law::Track(t) => t.mu_static0 - t.mu_drop,
        }
    }
}

/// Spring force over weight at `sample_rate_hz` over `duration_s`, from rest
/// with the spring preloaded to `initial_force_over_weight` (the drive starts
/// at t = 0).
pub fn simulate(law: &Law, s: &Setup) -> Result<Vec<f64>, ModelError> {
    let mut out = Vec::new();
    simulate_into(law, s, &mut out)?;
    Ok(out)
}

/// [`simulate`] into a caller's buffer (a batch's per-thread scratch), overwritten.
/// An error is one_dof's refusal: a set-up out of range, or a law whose
/// simulation left the physical range.
pub fn simulate_into(law: &Law, s: &Setup, out: &mut Vec<f64>) -> Result<(), ModelError> {
    out.clear();
    simulate_more(law, s, &mut OneDofState::default(), out)
}

/// [`simulate_into`] continued: `out` (as a call of this with the same law
/// and set-up but a shorter `duration_s` left it, or empty: a run from the
/// start) grows to `s.duration_s` from `state` (the state at its last
/// sample, which this keeps). One_dof's run is not kept: each sample goes
/// straight to its force over weight ([`ForceOverWeight`]). The steps do not depend on the
/// duration (an integer number per sample, from the natural period and the
/// rate), so a stretch lengthened piece by piece is bit for bit the one
/// simulated at once (`one_dof::simulate_implicit_extend`): a caller that
/// lengthens a stretch pays for the added samples only.
pub fn simulate_more(law: &Law, s: &Setup, state: &mut OneDofState, out: &mut Vec<f64>) -> Result<(), ModelError> {
    let n_out = (s.duration_s * s.sample_rate_hz).floor() as usize;
    if n_out < 2 || out.len() < 2 {
        out.clear();
    }
    if n_out < 2 {
        out.extend(std::iter::repeat_n(s.initial_force_over_weight, n_out));
        return Ok(());
    }
    let dt_out = 1.0 / s.sample_rate_hz;
    // An integer number of steps per output sample, at least the requested density.
    let sub = ((dt_out / (s.natural_period_s() / s.steps_per_period)).ceil() as usize).max(1);
    let weight_n = s.mass_kg * s.gravity_m_s2;
    let (inertia_kg, chain_n_m) = s.structure.effective(s.mass_kg, s.stiffness_n_m);
    let shaft = Shaft {
        inertia_kgm2: inertia_kg,
        stiffness_nm_rad: chain_n_m,
        twist_damping_nm_s_rad: 0.0,
        absolute_damping_nm_s_rad: 0.0,
        mid: None,
    };
    let contact = Contact { law: *law, weight_n, track: Default::default() };
    if out.is_empty() {
        *state = OneDofState {
            twist_rad: s.initial_force_over_weight * weight_n / chain_n_m,
            stuck: true,
            friction_state: contact.initial_state(s.drive_speed_m_s),
            ..OneDofState::default()
        };
    }
    let drive = Drive::ConstantSpeed(s.drive_speed_m_s);
    let mut sink = ForceOverWeight { out, per_m: chain_n_m / weight_n };
    one_dof::simulate_implicit_extend(&shaft, &contact, drive, state, s.sample_rate_hz, n_out, sub, &mut sink)
}

/// The one channel the slider reads, as one_dof's samples come: the spring
/// force over weight k_eff φ/(m g), φ the spring's extension (one_dof's
/// twist, m); the other channels are not stored.
struct ForceOverWeight<'a> {
    out: &'a mut Vec<f64>,
    /// k_eff/(m g), 1/m.
    per_m: f64,
}

impl ImplicitSink for ForceOverWeight<'_> {
    fn samples(&self) -> usize {
        self.out.len()
    }
    fn reserve(&mut self, more: usize) {
        self.out.reserve(more);
    }
    fn push(&mut self, state: &OneDofState, _friction_nm: f64, _accel_m_s2: f64) {
        self.out.push(self.per_m * state.twist_rad);
    }
}

/// A [`Law`] as one_dof's implicit contact, forces in N (μ times the weight).
struct Contact {
    law: Law,
    weight_n: f64,
    /// A track law's last threshold ([`crate::track::Memo`]; values, not a state).
    track: std::cell::Cell<crate::track::Memo>,
}

impl Contact {
    fn rate_state(&self) -> Option<RateStateAgeing> {
        match self.law {
            Law::RateState { mu0, a, b, dc_m, v_ref_m_s } => {
                Some(RateStateAgeing { normal_nm: self.weight_n, mu0, a, b, dc_rad: dc_m, v_ref_rad_s: v_ref_m_s })
            }
            _ => None,
        }
    }
}

impl ImplicitFriction for Contact {
    /// Coulomb: none; static ageing: the time stuck (0); rate and state: θ = Dc/V (the slip law: its
    /// logarithm); a track: the travel (0).
    fn initial_state(&self, drive_m_s: f64) -> [f64; MAX_FRICTION_STATES] {
        if let Law::RateStateSlip(law) = self.law {
            return crate::slip::Contact { law, weight_n: self.weight_n }.initial_state(drive_m_s);
        }
        if let Law::Heslot(law) = self.law {
            return crate::heslot::Contact { law, weight_n: self.weight_n }.initial_state(drive_m_s);
        }
        self.rate_state().map_or([0.0; MAX_FRICTION_STATES], |r| r.initial_state(drive_m_s))
    }
    fn implicit_step(
        &self,
        state: &mut [f64; MAX_FRICTION_STATES],
        stuck: &mut bool,
        p: f64,
        h_over_mass: f64,
        h_s: f64,
    ) -> (f64, f64) {
        let w = self.weight_n;
        match self.law {
            Law::Coulomb { mu_static, mu_kinetic } => {
                one_dof::implicit_coulomb_step(p, h_over_mass, w * mu_static, |_| w * mu_kinetic, stuck)
            }
            Law::StaticAgeing { mu_static0, ageing_beta, ageing_time_s, mu_kinetic0, alpha, v1_m_s } => {
                let mu_s = mu_static0 + ageing_beta * (1.0 + state[0] / ageing_time_s).ln();
                let r = one_dof::implicit_coulomb_step(
                    p,
                    h_over_mass,
                    w * mu_s,
                    |v| w * (mu_kinetic0 + alpha * (1.0 + v / v1_m_s).ln()),
                    stuck,
                );
                state[0] = if *stuck { state[0] + h_s } else { 0.0 };
                r
            }
            Law::RateState { .. } => {
                self.rate_state().expect("a rate-and-state law").implicit_step(state, stuck, p, h_over_mass, h_s)
            }
            Law::RateStateSlip(law) => {
                crate::slip::Contact { law, weight_n: w }.implicit_step(state, stuck, p, h_over_mass, h_s)
            }
            Law::Heslot(law) => {
                crate::heslot::Contact { law, weight_n: w }.implicit_step(state, stuck, p, h_over_mass, h_s)
            }
            Law::Track(law) => {
                let mut memo = self.track.get();
                let r = law.step(&mut state[0], stuck, p, h_over_mass, h_s, w, &mut memo);
                self.track.set(memo);
                r
            }
        }
    }
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
            structure: Structure::Stated,
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
        let f = simulate(&Law::Coulomb { mu_static: 0.4, mu_kinetic: 0.35 }, &s).unwrap();
        let max = f.iter().cloned().fold(f64::MIN, f64::max);
        assert!((max - 0.4).abs() < 2e-3, "peak {max}");
        let after_first = f.iter().position(|&y| y > 0.399).unwrap() + 200;
        let min = f[after_first..].iter().cloned().fold(f64::MAX, f64::min);
        assert!((min - 0.30).abs() < 3e-3, "trough {min}");
    }

    #[test]
    fn a_set_up_sets_the_inertial_period_as_its_closed_form() {
        // Coulomb with a small drop, r = ω Δμ m g/(k V) ≈ 0.1: one cycle lasts
        // T (1 − atan(r)/π + r/π) (a slip from rest, then a stick of 2r/ω),
        // T = 2π √(m_eff/k_eff): 0.8 T0 for m_eff = 0.64 m,
        // √2 T0 for a series spring k_s = k. The slip is a harmonic arc of
        // amplitude Δμ √(1 + 1/r²) about μk, so the force spans twice that.
        let law = Law::Coulomb { mu_static: 0.36, mu_kinetic: 0.35 };
        for (structure, ratio) in [
            (Structure::EffectiveMass { mass_ratio: 0.64 }, 0.8),
            (Structure::SeriesCompliance { series_stiffness_n_m: 2254.0 }, 2f64.sqrt()),
        ] {
            let mut s = setup(2254.0, 4300.0, 1.0);
            s.structure = structure;
            s.initial_force_over_weight = 0.36;
            let f = simulate(&law, &s).unwrap();
            let (m, k) = structure.effective(s.mass_kg, s.stiffness_n_m);
            let (w, weight) = ((k / m).sqrt(), s.mass_kg * s.gravity_m_s2);
            let r = w * 0.01 * weight / (k * s.drive_speed_m_s);
            let pi = std::f64::consts::PI;
            let expected = 2.0 * pi / w * (1.0 - r.atan() / pi + r / pi);
            assert!((2.0 * pi / w / s_natural(&s) - ratio).abs() < 1e-9);
            // Maxima after the first cycle: the period is the mean spacing.
            let peaks: Vec<usize> =
                (1..f.len() - 1).filter(|&i| f[i] > 0.37 && f[i] >= f[i - 1] && f[i] > f[i + 1]).collect();
            let period = (peaks[peaks.len() - 1] - peaks[1]) as f64 / (peaks.len() - 2) as f64 / s.sample_rate_hz;
            assert!((period / expected - 1.0).abs() < 0.01, "{structure:?}: period {period} vs {expected}");
            let (max, min) = f[peaks[1]..].iter().fold((f64::MIN, f64::MAX), |(a, b), &x| (a.max(x), b.min(x)));
            let range = 2.0 * 0.01 * (1.0 + 1.0 / (r * r)).sqrt();
            assert!(((max - min) / range - 1.0).abs() < 0.02, "{structure:?}: range {} vs {range}", max - min);
        }
    }

    /// The README's natural period 2π √(m/k) of a set-up.
    fn s_natural(s: &Setup) -> f64 {
        2.0 * std::f64::consts::PI * (s.mass_kg / s.stiffness_n_m).sqrt()
    }
}
