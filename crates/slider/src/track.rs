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
    /// new speed and the signed contact force. `memo` is the run's last
    /// (travel's bits, threshold) ([`Memo`]): a stuck slider does not move,
    /// so its threshold is read from there instead of drawn again.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &self,
        travel_m: &mut f64,
        stuck: &mut bool,
        p: f64,
        h_over_mass: f64,
        h_s: f64,
        weight_n: f64,
        memo: &mut Memo,
    ) -> (f64, f64) {
        let mu_s = memo.threshold(self, *travel_m);
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

/// A run's last threshold: (the travel's bits, [`Track::threshold`] there),
/// the travel's bits NaN's before the first step. The threshold is a
/// function of the travel alone, so reading it back where the travel has
/// the same bits is the same number (a stuck slider's steps, most of a
/// stick-slip run's: each drew it again, a division, a floor and the node
/// cache, ≈ 15 % of the slider study's CPU at the shipped budget); and
/// the run's last node pair, as the thread's [`LAST_NODES`] (values: the
/// same numbers without the thread-local's access per sliding step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Memo {
    travel_bits: u64,
    threshold: f64,
    nodes: Option<(i64, f64, f64)>,
}

impl Default for Memo {
    fn default() -> Memo {
        Memo { travel_bits: f64::NAN.to_bits(), threshold: f64::NAN, nodes: None }
    }
}

impl Memo {
    /// `law`'s threshold at `travel_m`, from the memo when the travel is the last one.
    pub fn threshold(&mut self, law: &Track, travel_m: f64) -> f64 {
        if travel_m.to_bits() != self.travel_bits {
            let z = profile_with(travel_m / law.length_m, &mut self.nodes);
            (self.travel_bits, self.threshold) = (travel_m.to_bits(), law.mu_static0 + law.sd * z);
        }
        self.threshold
    }
}

/// `u.floor()` without libm's call (the dev profile's target has no SSE4.1
/// `roundsd`, so `f64::floor` is a function call: 2.5 % of the slider
/// study's CPU): the truncation toward zero, one less where it rounded a
/// negative number up. Exact wherever |u| < 2⁵² (there every float is an
/// integer and is returned as it is); NaN and the rest go to `f64::floor`.
fn floor(u: f64) -> f64 {
    if u.abs() < 4_503_599_627_370_496.0 {
        let t = (u as i64) as f64;
        // copysign: −0.0 stays −0.0, as libm gives it.
        if t > u { t - 1.0 } else { t.copysign(u) }
    } else {
        u.floor()
    }
}

/// Unit value noise at `u` (in correlation lengths): standard normal values
/// at the integers, joined by smoothstep.
fn profile(u: f64) -> f64 {
    LAST_NODES.with(|c| {
        let mut last = c.get();
        let z = profile_with(u, &mut last);
        c.set(last);
        z
    })
}

/// [`profile`] with the last node pair drawn, `last` ((i, node(i),
/// node(i + 1))), kept by the caller: a slider crosses a node in many steps.
fn profile_with(u: f64, last: &mut Option<(i64, f64, f64)>) -> f64 {
    let n = floor(u);
    let s = u - n;
    let s = s * s * (3.0 - 2.0 * s);
    let i = n as i64;
    let (a, b) = match *last {
        Some((j, a, b)) if j == i => (a, b),
        _ => {
            let (a, b) = (node(i), node(i.wrapping_add(1)));
            *last = Some((i, a, b));
            (a, b)
        }
    };
    a * (1.0 - s) + b * s
}

thread_local! {
    /// The last node pair [`profile`] drew on each thread: a slider crosses a
    /// node in many steps, and a node costs a logarithm and a cosine (the
    /// track law's simulations spent about 40 % of the `slider` stage's CPU
    /// drawing the same two nodes again). Values, not a state: bit-identical.
    static LAST_NODES: std::cell::Cell<Option<(i64, f64, f64)>> = const { std::cell::Cell::new(None) };
}

/// A standard normal value for node `i` (Box–Muller on two splitmix64
/// draws): the track's nodes, and the fixed moves of
/// [`crate::study::local_misfit`] (at negative indices the travel never reaches).
pub(crate) fn node(i: i64) -> f64 {
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
    fn the_floor_is_libms_and_the_memo_the_threshold() {
        let cases = [0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.0 - f64::EPSILON, -1e-300, 4.5e15, -4.5e15, 1e300, -1e300];
        for &x in cases.iter().chain(&[f64::INFINITY, f64::NEG_INFINITY, f64::MAX, f64::MIN_POSITIVE]) {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x}");
        }
        assert!(floor(f64::NAN).is_nan());
        // Every binade from 2^-30 to 2^54, both signs, at integers and their neighbours.
        for e in -30..55 {
            for m in [1.0, 1.37, 1.5, 1.999] {
                let u = m * 2f64.powi(e);
                for x in
                    [u, -u, u.round(), -u.round(), u.round().next_up(), u.round().next_down(), -u.round().next_up()]
                {
                    assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x}");
                }
            }
        }
        let law = Track::of(&[0.35, 0.02, 0.02, 5e-6]);
        let mut memo = Memo::default();
        for x in [0.0, 0.0, 1.3e-6, 1.3e-6, 7.7e-5, 0.0, -2e-6, -2e-6] {
            assert_eq!(memo.threshold(&law, x).to_bits(), law.threshold(x).to_bits());
        }
    }

    #[test]
    fn the_step_holds_at_the_local_threshold_and_advances_the_travel() {
        let law = Track::of(&[0.35, 0.02, 0.02, 5e-6]);
        let (hm, h, w) = (1e-4 / 0.0307, 1e-4, 0.301);
        let (mut x, mut stuck) = (0.0, true);
        let here = law.threshold(0.0);
        let mut memo = Memo::default();
        let (v, _) = law.step(&mut x, &mut stuck, 0.99 * hm * w * here, hm, h, w, &mut memo);
        assert!(stuck && v == 0.0 && x == 0.0);
        let (v, f) = law.step(&mut x, &mut stuck, 1.2 * hm * w * here, hm, h, w, &mut memo);
        assert!(!stuck && v > 0.0 && (x - v * h).abs() < 1e-18);
        assert!((f - w * (here - law.mu_drop)).abs() < 1e-12);
    }
}
