//! Stick-slip of a truth model at a protocol's operating points, read from the
//! simulator's own stick phase (the truth knows when rotor 1 is held), and the
//! draw of effect-free rigs whose campaigns stick-slip ([`draw_stick_slip_rig`]).

use crate::{Protocol, Truth, VirtualRigError, draw_rig, times};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rig_types::{FrictionLaw, RunInput};

/// Stick phases of one operating point over the second half of its run
/// (after the ramp's transient).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StickSlip {
    /// Stick phases that begin in the window (transitions slip → stick).
    pub episodes: usize,
    /// Fraction of the window's samples in the stick phase.
    pub stick_fraction: f64,
}

impl StickSlip {
    /// A steady stick-slip: at least 3 stick phases in the window and at least
    /// 5 % of it stuck. A stuck rotor reads Ω1 = 0, which meets the
    /// classifier's stick-slip minimum (max(0.3 rad/s, 10 % of the mean),
    /// `rig_sweep::Regime::stick_slip`) whenever a phase outlasts the ±20 ms
    /// of the encoder differentiator; 5 % of a stick-slip cycle of ≤ 2 Hz is ≥ 25 ms.
    pub fn is_stick_slip(&self) -> bool {
        self.episodes >= 3 && self.stick_fraction >= 0.05
    }
}

/// Simulates every operating point of `protocol` with the truth model (no
/// sensor chain, no per-run phases) and reports its stick phases.
pub fn stick_slip_runs(truth: &Truth, protocol: &Protocol) -> Result<Vec<StickSlip>, VirtualRigError> {
    let t = times(protocol.op_duration_s, protocol.sample_rate_hz);
    let opts = crate::TRUTH_SIM_OPTIONS; // the truth model's one integrator setting
    protocol
        .op_points
        .par_iter()
        .enumerate()
        // One trajectory per worker, reused from run to run (`simulate_into`,
        // what `simulate` calls: the same samples): a fresh one per run was a
        // fresh mapping of its pages, and the battery's construction draws
        // these rigs hundreds of times (≈ 1 s of page faults per process).
        .map_init(rig_types::Trajectory::default, |tr, (j, &(rpm, n0))| {
            let input =
                RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: n0, ramp_s: protocol.ramp_s };
            rig_model::simulate_into(&truth.params, &input, &t, &opts, tr)
                .map_err(|source| VirtualRigError::Model { run: format!("op-{:02}", j + 1), source })?;
            let half = tr.stuck.len() / 2;
            let w = &tr.stuck[half..];
            let episodes = w.windows(2).filter(|p| !p[0] && p[1]).count();
            let stick_fraction = w.iter().filter(|&&s| s).count() as f64 / w.len().max(1) as f64;
            Ok(StickSlip { episodes, stick_fraction })
        })
        .collect()
}

/// Operating points of a campaign that must stick-slip for
/// [`draw_stick_slip_rig`] to accept a draw.
pub const MIN_STICK_SLIP_RUNS: usize = 3;

/// Draws tried by [`draw_stick_slip_rig`] before it gives up.
const STICK_SLIP_ATTEMPTS: u64 = 32;

/// An effect-free rig whose campaign under `protocol` stick-slips in at least
/// [`MIN_STICK_SLIP_RUNS`] operating points (checked by simulating the truth,
/// [`stick_slip_runs`]). The rig is [`draw_rig`]'s draw with the two
/// parameters that decide stick-slip redrawn in a range where it is common:
/// the shaft's damping ratio ξ 0.01–0.05 (a lightly damped steel string;
/// `draw_rig` 0.06–0.12) and μs/μk 1.3–1.8 (`draw_rig` 1.2–1.5). The classic
/// 1-DOF argument: after a break-away the rotor overshoots with a speed
/// amplitude ≈ (μs − μk) N r / √(J1 K), and it sticks again where that
/// exceeds the slip speed, less what the damping takes per cycle. Draws are
/// seeded by `seed` and the attempt; the first accepted is returned, or
/// `None` after 32 attempts (a protocol without slow, heavily loaded points).
pub fn draw_stick_slip_rig(seed: u64, protocol: &Protocol) -> Option<Truth> {
    for attempt in 0..STICK_SLIP_ATTEMPTS {
        let mut truth = draw_rig(seed);
        let mut r = ChaCha8Rng::seed_from_u64(seed ^ 0x571c_c5e1_0000 ^ attempt);
        let xi = r.random_range(0.01..0.05);
        let p = &mut truth.params;
        p.shaft_damping_nm_s_rad = 2.0 * xi * (p.rotor_inertia_kgm2 * p.shaft_stiffness_nm_rad).sqrt();
        if let FrictionLaw::Coulomb { mu_static, mu_kinetic } = &mut p.friction {
            *mu_static = *mu_kinetic * r.random_range(1.3..1.8);
        }
        let runs = stick_slip_runs(&truth, protocol).ok()?;
        if runs.iter().filter(|s| s.is_stick_slip()).count() >= MIN_STICK_SLIP_RUNS {
            return Some(truth);
        }
    }
    None
}
