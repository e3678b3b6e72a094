//! A friction threshold that varies along the track, the candidate
//! `track_threshold`: Coulomb whose static level depends on where the slider
//! is on the paper,
//!
//! μs(x) = μs0 + σ z(x/ℓ),  μk(x) = μs(x) − Δμ,
//!
//! z a smooth random profile of unit node deviation and correlation length
//! ℓ (value noise: independent standard normal values at nodes ℓ apart,
//! joined by smoothstep; one fixed seed, so a law is one track and a
//! simulation is deterministic), x the slider's travel since the start.
//!
//! Why (docs/findings.md, the slider's premises): the force at 1100 µm/s
//! wanders by about 0.02 F/(m g) at 0.1–0.4 Hz at both springs — equal in
//! force, 12 × apart in stretch, so the friction's along the track, not the
//! drive's — and k168-v4300 slides at a level of its own. A slider on a
//! pinning landscape is the classic picture of a heterogeneous interface
//! (Baumberger & Caroli, Adv. Phys. 55, 279 (2006), §2, the multicontact
//! interface as a population of pinned contacts; Prandtl–Tomlinson with a
//! random potential): quasi-statically the slider sits where the spring
//! force meets the threshold, k (V t − x) = m g μs(x), stable while
//! dμs/dx > −k/(m g); it follows the track (creep: the force rises at
//! L μs'/(μs' + k/(m g)), below L) where the threshold's slope is small
//! against k/(m g), and jumps where the threshold falls faster than the
//! spring unloads. A stiff spring (k/(m g) = 7.5 × 10⁻³ per µm at
//! 2254 N/m) follows a track that a soft one (5.6 × 10⁻⁴ per µm at
//! 168 N/m) stick-slips over: creep at the stiff spring and stick-slip at
//! the soft one at the same V, with no velocity dependence at all. The
//! static-to-kinetic drop Δμ keeps Coulomb's dynamic slip.
//!
//! The implicit step ([`Track::step`], Moreau, through `sim`'s
//! `one_dof::ImplicitFriction`): Coulomb's step
//! (`one_dof::implicit_coulomb_step`) at the levels of the slider's present
//! position, which the state carries (state[0], m, from 0) and advances by v h.

use crate::fit::ParamSpec;
use rig_model::one_dof::implicit_coulomb_step;

/// The law's id in slider-diagnosis.json.
pub const ID: &str = "track_threshold";

/// μs0, Δμ, σ, ℓ (m). Bounds: μs0 and Δμ as Coulomb's; σ from 10⁻³ (below
/// the force's resolution at the stiff spring) to 0.1 (a third of the
/// level); ℓ from 0.1 µm to 1 mm (from below a contact's size to a
/// seventeenth of the track a run covers).
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec { name: "mu_static0", lo: 0.2, hi: 0.8, log: false },
    ParamSpec { name: "mu_drop", lo: 0.001, hi: 0.3, log: true },
    ParamSpec { name: "track_sd", lo: 1e-3, hi: 0.1, log: true },
    ParamSpec { name: "track_length_m", lo: 1e-7, hi: 1e-3, log: true },
];

/// Correlation lengths of track a simulation covers at least (the events'
/// statistics, not one feature of the track): the simulated window is
/// lengthened to this travel at the drive speed ([`Track::min_window_s`]).
pub const TRACK_LENGTHS: f64 = 200.0;

/// The track's seed (one track per law: fits are deterministic).
const SEED: u64 = 0x005e_ed0f_7ac4;

/// The law of parameter vector `x` ([`PARAMS`]'s order).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Track {
    pub mu_static0: f64,
    pub mu_drop: f64,
    pub sd: f64,
    pub length_m: f64,
}

impl Track {
    pub fn of(x: &[f64]) -> Track {
        Track { mu_static0: x[0], mu_drop: x[1], sd: x[2], length_m: x[3] }
    }

    /// The static threshold at travel `x_m`.
    pub fn threshold(&self, x_m: f64) -> f64 {
        self.mu_static0 + self.sd * profile(x_m / self.length_m)
    }

    /// One implicit step of the contact under the normal load `weight_n`
    /// (N; speeds in m/s, forces in N), for `sim`'s `one_dof::ImplicitFriction`:
    /// Coulomb's step at the levels of the slider's travel `travel_m` (its
    /// state, from 0 at the start), which it advances by v h. Returns the
    /// new speed and the signed contact force.
    pub fn step(
        &self,
        travel_m: &mut f64,
        stuck: &mut bool,
        p: f64,
        h_over_mass: f64,
        h_s: f64,
        weight_n: f64,
    ) -> (f64, f64) {
        let mu_s = self.threshold(*travel_m);
        let kinetic = weight_n * (mu_s - self.mu_drop);
        let r = implicit_coulomb_step(p, h_over_mass, weight_n * mu_s, |_| kinetic, stuck);
        *travel_m += r.0 * h_s;
        r
    }

    /// The simulated window that covers [`TRACK_LENGTHS`] correlation lengths at `drive_m_s`, s.
    pub fn min_window_s(&self, drive_m_s: f64) -> f64 {
        TRACK_LENGTHS * self.length_m / drive_m_s.abs().max(1e-300)
    }

    /// Starting points: the threshold just above the runs' mean force,
    /// Coulomb-like drops, a track of 0.01–0.02 over 2–10 µm (where the
    /// slopes σ/ℓ straddle the two springs' k/(m g)); where the search
    /// starts, not a value it keeps.
    pub fn starts(mu: f64) -> Vec<Vec<f64>> {
        let mut v = Vec::new();
        for drop in [0.005, 0.02] {
            for (sd, len) in [(0.01, 2e-6), (0.02, 5e-6), (0.02, 1e-5)] {
                v.push(vec![mu + 0.01, drop, sd, len]);
            }
        }
        v
    }
}

/// Unit value noise at `u` (in correlation lengths): standard normal values
/// at the integers, joined by smoothstep.
fn profile(u: f64) -> f64 {
    let n = u.floor();
    let s = u - n;
    let s = s * s * (3.0 - 2.0 * s);
    let i = n as i64;
    let (a, b) = nodes(i);
    a * (1.0 - s) + b * s
}

thread_local! {
    /// The last node pair [`profile`] drew on each thread: a slider crosses a
    /// node in many steps, and a node costs a logarithm and a cosine (the
    /// track law's simulations spent about 40 % of the `slider` stage's CPU
    /// drawing the same two nodes again). Values, not a state: bit-identical.
    static LAST_NODES: std::cell::Cell<Option<(i64, f64, f64)>> = const { std::cell::Cell::new(None) };
}

/// (node(i), node(i + 1)), from the thread's last pair when it is the same.
fn nodes(i: i64) -> (f64, f64) {
    LAST_NODES.with(|c| match c.get() {
        Some((j, a, b)) if j == i => (a, b),
        _ => {
            let (a, b) = (node(i), node(i.wrapping_add(1)));
            c.set(Some((i, a, b)));
            (a, b)
        }
    })
}

/// A standard normal value for node `i` (Box–Muller on two splitmix64 draws).
fn node(i: i64) -> f64 {
    let mix = |mut z: u64| {
        z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let a = mix(SEED ^ (i as u64).wrapping_mul(2));
    let b = mix(SEED ^ (i as u64).wrapping_mul(2).wrapping_add(1));
    let unit = |z: u64| ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    (-2.0 * unit(a).ln()).sqrt() * (2.0 * std::f64::consts::PI * unit(b)).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_has_unit_nodes_and_is_continuous() {
        let nodes: Vec<f64> = (0..20000).map(node).collect();
        let mean = nodes.iter().sum::<f64>() / nodes.len() as f64;
        let sd = (nodes.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / nodes.len() as f64).sqrt();
        assert!(mean.abs() < 0.03 && (sd - 1.0).abs() < 0.03, "{mean} {sd}");
        for i in -3..3 {
            assert_eq!(profile(i as f64), node(i));
            let u = i as f64 + 1.0;
            assert!((profile(u - 1e-9) - profile(u)).abs() < 1e-6);
        }
    }

    #[test]
    fn the_step_holds_at_the_local_threshold_and_advances_the_travel() {
        let law = Track::of(&[0.35, 0.02, 0.02, 5e-6]);
        let (hm, h, w) = (1e-4 / 0.0307, 1e-4, 0.301);
        let (mut x, mut stuck) = (0.0, true);
        let here = law.threshold(0.0);
        let (v, _) = law.step(&mut x, &mut stuck, 0.99 * hm * w * here, hm, h, w);
        assert!(stuck && v == 0.0 && x == 0.0);
        let (v, f) = law.step(&mut x, &mut stuck, 1.2 * hm * w * here, hm, h, w);
        assert!(!stuck && v > 0.0 && (x - v * h).abs() < 1e-18);
        assert!((f - w * (here - law.mu_drop)).abs() < 1e-12);
    }
}
