//! Structural candidates `force_sensor_dynamics` and
//! `encoder_coupling_compliance`: a sensor with its own resonance between
//! the rig and the record. Like a delay, it changes no simulated motion
//! (the rig is the rig model); unlike a delay it rings, and its footprint
//! is at the stick↔slip transitions, where the force and the rotor's
//! acceleration jump (the event-locked rows of the balance,
//! [`crate::channels::BalanceData::run_event_rms`]).
//!
//! # The two sensors
//!
//! - **Force sensor as a second-order system** (a load cell and caliper arm,
//!   mass–spring–damper, pulled by the pad force): the record is
//!   F_m = H[F], H(s) = ω²/(s² + 2ζωs + ω²), ω = 2π f_n. At low frequency
//!   H ≈ 1 − (2ζ/ω)s: a lag of 2ζ/ω (a delay's alias), and a step of the
//!   force (break-away, arrest) rings at f_n.
//! - **Rotor encoder on a compliant coupling** (the disc's inertia on a
//!   coupling of stiffness k_c and damping c_c, ω² = k_c/J_e, 2ζω = c_c/J_e):
//!   the recorded angle is φe = G[φ1], G(s) = (ω² + 2ζωs)/(s² + 2ζωs + ω²).
//!   At low frequency G ≈ 1 − s²/ω²: the disc lags by Ω̇1/ω², which the
//!   balance reads as an inertia K/ω² too small — only where Ω1 accelerates,
//!   at the transitions.
//!
//! # Fit
//!
//! Both filters are linear and time-invariant, so the balance of the true
//! channels can be written with the recorded ones.
//!
//! - **Force sensor: the recorded force through the sensor's inverse.**
//!   r·F = −J1 Ω̇1 + K tw + C tẇ (Eq. 4-7's first row) holds for the force the load cell was
//!   pulled by, F = H⁻¹[F_m] = F_m + (2ζ/ω)Ḟ_m + F̈_m/ω²: H's inverse is a
//!   polynomial in s, exact, with no recursion and no start-up. The
//!   derivatives are central differences at the record's rate, and the
//!   balance's rows take their triangle-weighted means, in which they
//!   telescope to differences of the force's box means and samples a window
//!   apart. The angles stay as recorded, so their quantisation, the
//!   balance's dominant noise, is untouched; the force's noise is amplified
//!   by the derivatives, so on a record without a sensor every grid point
//!   can only lose. Measured (probe, fit on every run, twist-rate balance):
//!   `structural-force_sensor_dynamics-2` (11.5 Hz, ζ 0.09) through its
//!   true sensor, the balance RMS 1.2012e-2 N·m as recorded, 1.2003e-2
//!   through the inverse (event-locked 4.53e-3 → 3.70e-3), 1.2543e-2 with
//!   the former correction (below; 2 runs of 30 better than as recorded),
//!   which is why the right sensor was refuted by its held-out balance
//!   (−5.5 %, t −11.1); `-0` (7.2 Hz, ζ 0.29) 1.3146e-2 → 1.2588e-2
//!   (former: 1.3144e-2), `-1` (8.1 Hz, ζ 0.25) 1.4044e-2 → 1.3916e-2
//!   (1.4036e-2); the stick-slipping null `null_stick_slip-00` through
//!   12 Hz ζ 0.1, 12 Hz ζ 0.4, 20 Hz ζ 0.4, 15 Hz ζ 0.05: 1.1779e-2 as
//!   recorded, 1.1819e-2, 1.2100e-2, 1.1887e-2, 1.1790e-2 through the
//!   inverse (never better), where filtering the angles through H gave
//!   1.1620e-2, 1.1058e-2, 1.0979e-2 (−6.8 %, 26 runs of 30 better: the
//!   low-passed quantisation's false gain) and 1.6941e-2.
//! - **Encoder coupling: the other channels through the coupling's
//!   filter**: G applied to both sides of the balance (Eq. 4-7's first
//!   row), every term linear in (φ1, φ2, F), gives rows built from the
//!   recorded φe = G[φ1], G[φ2] and G[F]; no recorded channel is
//!   differentiated or inverted. The filter is applied as a correction, x + (G − 1)[x̃],
//!   with x̃ the channel smoothed over ±[`SMOOTH_HALF_S`] (a centred moving
//!   average, zero phase): the recorded sample noise stays in the rows as
//!   it is. (The force sensor was corrected the same way on the angles,
//!   φ + (H − 1)[φ̃], until the measurement above: the ±10 ms box passes
//!   0.90 at 11.5 Hz and its transition band mixes filtered and unfiltered
//!   quantisation, and a lightly damped sensor's right point lost on the
//!   balance.)
//!
//! The filters are discretised by the bilinear transform at the record's
//! rate (warping below 0.4 % at 20 Hz and 500 Hz), started at rest on the
//! first sample. The fit is the grid point (f_n on [`FREQUENCIES_HZ`], ζ on
//! [`DAMPING_RATIOS`]) with the smallest sum over training runs of each run's
//! squared RMS residual of the twist-rate balance, or none when the records
//! as recorded fit best (as `channel_delay`'s grid). The force sensor is
//! fitted on its ring instead wherever the records have one (below).
//!
//! # The ring after a break-away (what a delay does not have)
//!
//! The balance's rows, the event-locked ones included, are 0.1 s
//! triangle-weighted means whose gain at f is sinc²(π f · 0.1 s) (0.05 at
//! 8 Hz): a ringing force sensor reaches them only as its low-frequency
//! lag 2ζ/ω, a force delay's footprint (docs/findings.md). The force
//! channel at its full rate still has what separates them: at a break-away
//! the friction drops from the static level to the kinetic one within a few
//! milliseconds (the Stribeck decay as the rotor speeds up), and a
//! second-order sensor answers that drop with its step response, an
//! overshoot and a ring at f_n√(1 − ζ²) decaying as e^{−ζωt}
//! (H(s) = ω²/(s² + 2ζωs + ω²), the model above); a late channel shows the
//! same drop, later, and does not ring. So per run ([`Ring`]): every
//! stick→slip transition of the rotor encoder (the balance's), the recorded
//! force aligned on its steepest change within ±[`RING_SEARCH_S`](ring::RING_SEARCH_S) (the force
//! smoothed over ±[`RING_LOCATE_HALF_S`](ring::RING_LOCATE_HALF_S) to locate it), averaged over the
//! run's transitions from −[`RING_PRE_S`](ring::RING_PRE_S) to +[`RING_POST_S`](ring::RING_POST_S) (transitions
//! whose next stick comes earlier are left out; at least
//! [`crate::channels::MIN_EVENTS`]): an event-triggered average at full
//! rate, in which what every break-away shares stays and the force noise
//! falls by √transitions. The average is fitted by least squares with the
//! true force's shape through the hypothesis: a line before the drop, a
//! step (a raised-cosine ramp of width 0, 10 or 30 ms, at a time τ from −60
//! to +10 ms) and a quadratic after it (the slip's slow change of the
//! friction), five amplitudes, all through H of the grid point (or as
//! recorded); τ, the width and the amplitudes are each run's own, so a
//! delay, a shift of the whole drop, is absorbed and fits as well as the
//! records as recorded; only the shape after the drop tells. The run's
//! ring misfit is that fit's RMS residual times the disc radius, N·m (a
//! torque at the disc, like the balance's), at the best τ and width. The
//! force sensor's grid point is the one with the smallest training cost of
//! the balance (above) plus the sum over the training runs of the squared
//! ring misfits, if it beats the records as recorded: where the ring is
//! plain it decides (full battery `structural-force_sensor_dynamics-0`:
//! 7 Hz, ζ 0.30 against the truth's 7.2 Hz, 0.29; the balance alone chose
//! 10 Hz, ζ 0.40), where a slow Stribeck drop hardly excites the sensor the
//! balance does (`structural-velocity_weakening_friction+force_sensor_dynamics-0`:
//! the ring alone chose 5 Hz, ζ 0.05, a balance 4× worse). The selection
//! scores the fit on the held-out runs' ring misfits like every other
//! comparison ([`super`]).

use super::{Fitted, ParamSpec, StructureCandidate, StructureData};
use crate::channels::{BalanceData, Recorded};
use rayon::prelude::*;
use rig_types::RigParams;
use rig_types::sensor::{centred_moving_average, nominal_window_samples};
use std::borrow::Cow;

mod ring;
pub use ring::Ring;
pub(super) use ring::ring;

/// The force sensor's finding id.
pub const FORCE_SENSOR_ID: &str = "force_sensor_dynamics";
/// The encoder coupling's finding id.
pub const ENCODER_COUPLING_ID: &str = "encoder_coupling_compliance";

/// Half-width of the smoothing the sensor's correction is computed from, s
/// (module docs: ±10 ms, a zero-phase box whose first zero, 48 Hz at 500 Hz,
/// is far above every resonance tried).
pub const SMOOTH_HALF_S: f64 = 0.01;

/// Natural frequencies tried, Hz: from 2 Hz (a soft elastomer coupling, a
/// few times the stick-slip fundamental) to 20 Hz, above which neither
/// sensor is resolved by this rig (an encoder lag Ω̇1/ω² below a tick at
/// the transitions' 20–50 rad/s²; a force lag 2ζ/ω below a sample).
/// 7 Hz and ζ 0.3 were added when the full battery's 7.2 Hz, ζ 0.29 force
/// sensor fell between points (fitted 10 Hz, ζ 0.40).
pub const FREQUENCIES_HZ: [f64; 12] = [2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 15.0, 20.0];
/// Damping ratios tried (light to near-critical).
pub const DAMPING_RATIOS: [f64; 5] = [0.05, 0.1, 0.2, 0.3, 0.4];

/// Which sensor rings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sensor {
    Force,
    EncoderCoupling,
}

/// One point of the grid: the sensor's f_n and ζ and the balance it gives.
#[derive(Debug, Clone)]
pub struct SensorPoint {
    pub sensor: Sensor,
    pub natural_frequency_hz: f64,
    pub damping_ratio: f64,
    pub data: BalanceData,
}

/// The bilinear-transform coefficients of F(s) = (b1 s + ω²)/(s² + 2ζωs +
/// ω²), b1 = 2ζω when `rate_term` (the coupling's damper) else 0 (the load
/// cell), at `rate_hz`, divided through by the leading denominator
/// coefficient: y[k] = c0 u[k] + c1 u[k−1] + c2 u[k−2] − e1 y[k−1] − e2 y[k−2].
#[derive(Debug, Clone, Copy)]
struct Biquad {
    c: [f64; 3],
    e: [f64; 2],
}

impl Biquad {
    fn new(rate_hz: f64, f_n_hz: f64, zeta: f64, rate_term: bool) -> Self {
        let w = 2.0 * std::f64::consts::PI * f_n_hz;
        let a = 2.0 * rate_hz;
        let b1 = if rate_term { 2.0 * zeta * w } else { 0.0 };
        let (w2, a2, zwa) = (w * w, a * a, 2.0 * zeta * w * a);
        let (d0, d1, d2) = (a2 + zwa + w2, 2.0 * (w2 - a2), a2 - zwa + w2);
        let (n0, n1, n2) = (b1 * a + w2, 2.0 * w2, w2 - b1 * a);
        Biquad { c: [n0 / d0, n1 / d0, n2 / d0], e: [d1 / d0, d2 / d0] }
    }
}

/// Two channels through `L` filters as corrections, x + (F − 1)[x̃] with x̃
/// the smoothed channel (module docs), each recursion from rest at x̃[0]
/// (unit DC gain): one pass over the channels, the 2·L recursions
/// interleaved. Each recursion is latency-bound (its last output enters
/// its next), and they are independent, so the processor overlaps them: one
/// campaign's grid runs 120 points × 2 channels × every run through it, and
/// a lane is its own filter's result to the bit (the same operations in the
/// same order as one recursion alone).
fn corrected_pairs<const L: usize>(
    a: (&[f64], &[f64]),
    b: (&[f64], &[f64]),
    q: [Biquad; L],
) -> [(Vec<f64>, Vec<f64>); L] {
    let n = a.0.len().min(a.1.len()).min(b.0.len()).min(b.1.len());
    let (Some(&sa), Some(&sb)) = (a.1.first(), b.1.first()) else {
        return std::array::from_fn(|_| (Vec::new(), Vec::new()));
    };
    let mut out: [(Vec<f64>, Vec<f64>); L] = std::array::from_fn(|_| (vec![0.0; n], vec![0.0; n]));
    let (mut ua, mut ub) = ([[sa; 2]; L], [[sb; 2]; L]);
    let (mut ya, mut yb) = ([[sa; 2]; L], [[sb; 2]; L]);
    for k in 0..n {
        let (ra, xa, rb, xb) = (a.0[k], a.1[k], b.0[k], b.1[k]);
        for l in 0..L {
            let Biquad { c: [c0, c1, c2], e: [e1, e2] } = q[l];
            // The last sample's output enters last: one product and one
            // subtraction on the recursion's critical path.
            let na = (c0 * xa + c1 * ua[l][0] + c2 * ua[l][1] - e2 * ya[l][1]) - e1 * ya[l][0];
            let nb = (c0 * xb + c1 * ub[l][0] + c2 * ub[l][1] - e2 * yb[l][1]) - e1 * yb[l][0];
            out[l].0[k] = ra + (na - xa);
            out[l].1[k] = rb + (nb - xb);
            (ua[l], ub[l], ya[l], yb[l]) = ([xa, ua[l][0]], [xb, ub[l][0]], [na, ya[l][0]], [nb, yb[l][0]]);
        }
    }
    out
}

/// The force the load cell was pulled by, from its record (module docs):
/// H⁻¹[F_m] = F_m + (2ζ/ω)·Ḟ_m + F̈_m/ω², the exact inverse of H(s) =
/// ω²/(s² + 2ζωs + ω²) (a polynomial in s, no recursion), the derivatives
/// central differences at `rate_hz` (error ω²Δt²/12: 0.2 % at 11.5 Hz and
/// 500 Hz), the first and last sample as recorded: F_m + a1·D1F_m +
/// a2·D2F_m with D1F[k] = F[k+1] − F[k−1], D2F[k] = F[k+1] − 2F[k] + F[k−1]
/// (0 at both ends, [`force_differences`]) and (a1, a2) =
/// ([`inverse_coefficients`]). The grid builds its balance from the three
/// channels' balances ([`BalanceData::force_combination`]); this, sample by
/// sample, is what that equals to rounding (tests).
#[cfg(test)]
fn force_through_inverse(force_n: &[f64], rate_hz: f64, f_n_hz: f64, zeta: f64) -> Vec<f64> {
    let (a1, a2) = inverse_coefficients(rate_hz, f_n_hz, zeta);
    let n = force_n.len();
    (0..n)
        .map(|k| match (k.checked_sub(1), force_n.get(k + 1)) {
            (Some(j), Some(&next)) => {
                let (prev, f) = (force_n[j], force_n[k]);
                f + a1 * (next - prev) + a2 * (next - 2.0 * f + prev)
            }
            _ => force_n[k],
        })
        .collect()
}

/// The weights of the force's central differences in H⁻¹ at `rate_hz`
/// ([`force_through_inverse`]): a1 = (2ζ/ω)·rate/2 on F[k+1] − F[k−1],
/// a2 = rate²/ω² on F[k+1] − 2F[k] + F[k−1].
fn inverse_coefficients(rate_hz: f64, f_n_hz: f64, zeta: f64) -> (f64, f64) {
    let w = 2.0 * std::f64::consts::PI * f_n_hz;
    (2.0 * zeta / w * rate_hz / 2.0, rate_hz * rate_hz / (w * w))
}

/// The recorded force's central first and second differences
/// ([`force_through_inverse`]'s D1F and D2F), 0 at the first and last sample.
fn force_differences(force_n: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = force_n.len();
    let (mut d1, mut d2) = (vec![0.0; n], vec![0.0; n]);
    for k in 1..n.saturating_sub(1) {
        let (prev, f, next) = (force_n[k - 1], force_n[k], force_n[k + 1]);
        d1[k] = next - prev;
        d2[k] = next - 2.0 * f + prev;
    }
    (d1, d2)
}

/// The balance of the records at every point of the grid, for both
/// sensors: the force sensor's from the force through its inverse
/// ([`force_through_inverse`], the angles as recorded), linear in the
/// force, so every force point's balance is the recorded force's plus a1
/// and a2 times its differences' ([`force_differences`],
/// [`BalanceData::force_combination`]: three balances built once); the
/// coupling's from the channels it touches, smoothed once per run
/// ([`SMOOTH_HALF_S`]), through its filter as a correction, the points of
/// one natural frequency (every damping ratio) built together
/// ([`corrected_pairs`], [`Recorded::balance_lanes`]).
pub(super) fn grid(rec: &Recorded, rate_hz: f64) -> Vec<SensorPoint> {
    let half = nominal_window_samples(SMOOTH_HALF_S, rate_hz);
    let smooth: Vec<[Vec<f64>; 2]> =
        rec.runs.iter().map(|r| [&r.motor_rad, &r.force_n].map(|x| centred_moving_average(x, half))).collect();
    let [recorded, d1, d2] = rec.balance_lanes(|_, r| {
        let (d1, d2) = force_differences(&r.force_n);
        [Cow::Borrowed(r.force_n.as_slice()), Cow::Owned(d1), Cow::Owned(d2)]
            .map(|f| (Cow::Borrowed(r.rotor_rad.as_slice()), Cow::Borrowed(r.motor_rad.as_slice()), f))
    });
    let force = FREQUENCIES_HZ.iter().flat_map(|&f_n| {
        DAMPING_RATIOS.map(|zeta| {
            let (a1, a2) = inverse_coefficients(rate_hz, f_n, zeta);
            let data = recorded.force_combination(&[(a1, &d1), (a2, &d2)]);
            SensorPoint { sensor: Sensor::Force, natural_frequency_hz: f_n, damping_ratio: zeta, data }
        })
    });
    // Every f_n's coupling balances are independent: built in parallel, in grid order.
    let coupling: Vec<Vec<SensorPoint>> = FREQUENCIES_HZ
        .par_iter()
        .map(|&f_n| {
            let data = rec.balance_lanes(|i, r| {
                let [s2, sf] = &smooth[i];
                let q = DAMPING_RATIOS.map(|zeta| Biquad::new(rate_hz, f_n, zeta, true));
                corrected_pairs((&r.motor_rad, s2), (&r.force_n, sf), q)
                    .map(|(phi2, f)| (r.rotor_rad.as_slice().into(), phi2.into(), f.into()))
            });
            DAMPING_RATIOS
                .iter()
                .zip(data)
                .map(|(&zeta, data)| SensorPoint {
                    sensor: Sensor::EncoderCoupling,
                    natural_frequency_hz: f_n,
                    damping_ratio: zeta,
                    data,
                })
                .collect()
        })
        .collect();
    force.chain(coupling.into_iter().flatten()).collect()
}

/// The encoder coupling's placebo (module docs of [`super`], "A placebo at
/// the transitions"): the balance with the coupling's correction at f_n, ζ
/// run backwards in time, x + (G̃ − 1)[x̃] with G̃(s) = G(−s), on the motor
/// angle and the force (the channels reversed, corrected, reversed back).
/// G̃ has G's even part — to first order the same −s²/ω², the apparent
/// inertia K/ω² a coupling puts in the balance — and the opposite odd part:
/// its transient after a transition runs before it, which no sensor does.
/// A disc on a real coupling rings after the rotor's jumps, so the causal
/// filter fits the transitions and the reversed one does not; an error of
/// the rows that is even in time (the encoder's rounding where Ω1 turns)
/// fits both alike.
fn coupling_placebo(rec: &Recorded, rate_hz: f64, f_n_hz: f64, zeta: f64) -> BalanceData {
    let half = nominal_window_samples(SMOOTH_HALF_S, rate_hz);
    let q = [Biquad::new(rate_hz, f_n_hz, zeta, true)];
    let rev = |x: &[f64]| x.iter().rev().copied().collect::<Vec<f64>>();
    let [data] = rec.balance_lanes(|_, r| {
        let (m, f) = (rev(&r.motor_rad), rev(&r.force_n));
        let (sm, sf) = (centred_moving_average(&m, half), centred_moving_average(&f, half));
        let [(phi2, force)] = corrected_pairs((&m, &sm), (&f, &sf), q);
        [(r.rotor_rad.as_slice().into(), rev(&phi2).into(), rev(&force).into())]
    });
    data
}

const FORCE_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "force_sensor_natural_frequency_hz",
        unit: "Hz",
        lower: 0.0,
        meaning: "the force sensor's natural frequency (load cell and caliper arm)",
    },
    ParamSpec {
        name: "force_sensor_damping_ratio",
        unit: "1",
        lower: 0.0,
        meaning: "the force sensor's damping ratio",
    },
];

const COUPLING_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "encoder_coupling_natural_frequency_hz",
        unit: "Hz",
        lower: 0.0,
        meaning: "the rotor encoder disc's natural frequency on its coupling",
    },
    ParamSpec {
        name: "encoder_coupling_damping_ratio",
        unit: "1",
        lower: 0.0,
        meaning: "the rotor encoder coupling's damping ratio",
    },
];

/// The force sensor's low-frequency lag 2ζ/ω, s (H ≈ 1 − (2ζ/ω)s): the
/// term the records must support (0 without a resonance).
const FORCE_LAG: ParamSpec =
    ParamSpec { name: "force_sensor_lag_s", unit: "s", lower: 0.0, meaning: "the force sensor's lag 2ζ/ω" };
/// The encoder disc's lag per unit acceleration 1/ω², s² (G ≈ 1 − s²/ω²).
const COUPLING_LAG: ParamSpec = ParamSpec {
    name: "encoder_coupling_lag_s2",
    unit: "s²",
    lower: 0.0,
    meaning: "the encoder disc's lag per unit of the rotor's acceleration, 1/ω²",
};

/// A sensor candidate: which sensor, its id, parameters, the lag the
/// records must support, and its name in a sentence.
pub struct SensorCandidate {
    sensor: Sensor,
    id: &'static str,
    params: &'static [ParamSpec],
    lag: &'static ParamSpec,
    what: &'static str,
}

/// `force_sensor_dynamics`.
pub static FORCE_SENSOR: SensorCandidate = SensorCandidate {
    sensor: Sensor::Force,
    id: FORCE_SENSOR_ID,
    params: FORCE_PARAMS,
    lag: &FORCE_LAG,
    what: "the force sensor as a second-order system",
};

/// `encoder_coupling_compliance`.
pub static ENCODER_COUPLING: SensorCandidate = SensorCandidate {
    sensor: Sensor::EncoderCoupling,
    id: ENCODER_COUPLING_ID,
    params: COUPLING_PARAMS,
    lag: &COUPLING_LAG,
    what: "the rotor encoder on a compliant coupling",
};

/// The grid point of `sensor` with the smallest training cost, if it beats
/// the records as recorded.
fn fit_sensor(sensor: Sensor, data: &StructureData, include: &dyn Fn(&str) -> bool) -> Option<Fitted> {
    // The force sensor's ring after the break-aways joins the balance's
    // cost (module docs): the sum over training runs of its squared
    // misfits, a torque at the disc like the balance's.
    let ring = |point: Option<usize>| match sensor {
        Sensor::Force => data.ring.run_rms(point, include).iter().map(|x| x.1 * x.1).sum::<f64>(),
        Sensor::EncoderCoupling => 0.0,
    };
    let (mut best_cost, mut best_fit) = super::channel_delay::training_cost(&data.balance, include)?;
    best_cost += ring(None);
    let mut best: Option<usize> = None;
    for (i, p) in data.sensors.iter().enumerate().filter(|(_, p)| p.sensor == sensor) {
        if let Some((cost, fit)) = super::channel_delay::training_cost(&p.data, include)
            && cost + ring(Some(i)) < best_cost
        {
            (best_cost, best_fit, best) = (cost + ring(Some(i)), fit, Some(i));
        }
    }
    let values =
        best.map_or(vec![0.0, 0.0], |i| vec![data.sensors[i].natural_frequency_hz, data.sensors[i].damping_ratio]);
    Some(Fitted { values, balance: best_fit, aligned: None, sensor: best, footprint: None })
}

/// `u` through `q` from rest at u[0] (unit DC gain).
fn filtered(u: &[f64], q: Biquad) -> Vec<f64> {
    let Biquad { c: [c0, c1, c2], e: [e1, e2] } = q;
    let Some(&s) = u.first() else { return Vec::new() };
    let (mut uu, mut yy) = ([s; 2], [s; 2]);
    u.iter()
        .map(|&x| {
            let y = (c0 * x + c1 * uu[0] + c2 * uu[1] - e2 * yy[1]) - e1 * yy[0];
            (uu, yy) = ([x, uu[0]], [y, yy[0]]);
            y
        })
        .collect()
}

impl StructureCandidate for SensorCandidate {
    fn id(&self) -> &'static str {
        self.id
    }
    fn params(&self) -> &'static [ParamSpec] {
        self.params
    }
    fn fit(&self, _model: &RigParams, data: &StructureData, include: &dyn Fn(&str) -> bool) -> Option<Fitted> {
        fit_sensor(self.sensor, data, include)
    }
    /// The rig is the model's: only the record rings.
    fn apply(&self, model: &RigParams, _fitted: &Fitted) -> RigParams {
        model.clone()
    }
    fn describe(&self, fitted: &Fitted) -> String {
        let (f_n, zeta) = (fitted.values[0], fitted.values[1]);
        if f_n > 0.0 {
            format!(
                "{} with a resonance at {f_n:.1} Hz, ζ = {zeta:.2} (the rig model's damping on the twist rate, C = \
                 {:.2e} N·m·s/rad in the balance through it)",
                self.what, fitted.balance.twist_damping_nm_s_rad
            )
        } else {
            format!("{}: no resonance fits the balance better than the records as recorded", self.what)
        }
    }
    fn damping(&self) -> &'static str {
        super::twist_rate::ID
    }
    fn moves(&self) -> bool {
        false
    }
    fn finding_id(&self) -> Option<&'static str> {
        Some(self.id)
    }
    /// The force sensor's ring through its fitted point; the encoder's
    /// coupling leaves the force as recorded.
    fn ring_rms(&self, data: &StructureData, fitted: &Fitted, include: &dyn Fn(&str) -> bool) -> Vec<(String, f64)> {
        data.ring.run_rms(if self.sensor == Sensor::Force { fitted.sensor } else { None }, include)
    }
    /// At the grid's largest lag (module docs of [`super`], "A fit at its
    /// grid's edge"): the lowest f_n with the highest ζ for the force
    /// sensor (2ζ/ω), the lowest f_n for the coupling (1/ω², whatever ζ).
    fn at_grid_edge(&self, fitted: &Fitted) -> Option<super::GridEdge> {
        let (f_n, zeta) = (fitted.values[0], fitted.values[1]);
        let (f_lo, z_hi) = (FREQUENCIES_HZ[0], DAMPING_RATIOS[DAMPING_RATIOS.len() - 1]);
        let lag = self.support(fitted)[0].1;
        let what = match self.sensor {
            Sensor::Force if f_n == f_lo && zeta == z_hi => format!(
                "f_n = {f_lo} Hz, the lowest tried, with ζ = {z_hi:.2}, the highest: the largest lag 2ζ/ω it holds, \
                 {:.0} ms",
                1e3 * lag
            ),
            Sensor::EncoderCoupling if f_n == f_lo => format!(
                "f_n = {f_lo} Hz, the lowest tried: the largest lag per unit acceleration 1/ω² it holds, {:.1e} s²",
                lag
            ),
            _ => return None,
        };
        Some(super::GridEdge { param: &self.params[0], edge: f_lo, what })
    }
    /// The coupling's placebo ([`coupling_placebo`]) at the fitted point;
    /// the force sensor has none (its ring is its own footprint).
    fn placebo(&self, rec: &Recorded, rate_hz: f64, fitted: &Fitted) -> Option<BalanceData> {
        let (f_n, zeta) = (fitted.values[0], fitted.values[1]);
        (self.sensor == Sensor::EncoderCoupling && f_n > 0.0).then(|| coupling_placebo(rec, rate_hz, f_n, zeta))
    }
    /// The lag (0 without a resonance): 2ζ/ω for the force sensor, 1/ω²
    /// for the encoder's coupling.
    fn support(&self, fitted: &Fitted) -> Vec<(&'static str, f64, &'static ParamSpec)> {
        let w = 2.0 * std::f64::consts::PI * fitted.values[0];
        let lag = match (w > 0.0, self.sensor) {
            (false, _) => 0.0,
            (true, Sensor::Force) => 2.0 * fitted.values[1] / w,
            (true, Sensor::EncoderCoupling) => 1.0 / (w * w),
        };
        vec![(self.lag.name, lag, self.lag)]
    }
}

#[cfg(test)]
mod tests {
    use super::{Biquad, corrected_pairs, filtered, force_through_inverse};
    use std::f64::consts::PI;

    /// A force of the stick-slip's band (1 and 4 Hz) recorded through a
    /// lightly damped sensor (11.5 Hz, ζ 0.09: |H| = 1.13 at 4 Hz, a ring of
    /// 5.6× at resonance) is given back by the inverse, after the bilinear
    /// filter's start-up ring has decayed (e^{−ζωt}: 1e-14 at 5 s). The
    /// two discretisations differ by O(ω²Δt²) at the signal's frequencies
    /// (central differences ω²Δt²/12 = 8.4e-5 relative at 4 Hz, 500 Hz): 2e-3 N of an 8 N
    /// swing bounds both; as recorded it is off by ≈ 0.15 N (|H| = 1.13 at 4 Hz).
    #[test]
    fn the_inverse_gives_back_the_force_the_sensor_saw() {
        let (rate, f_n, zeta) = (500.0, 11.5, 0.09);
        let u: Vec<f64> = (0..5000)
            .map(|k| {
                let t = k as f64 / rate;
                30.0 + 3.0 * (2.0 * PI * t).sin() + 1.0 * (2.0 * PI * 4.0 * t).cos()
            })
            .collect();
        let recorded = filtered(&u, Biquad::new(rate, f_n, zeta, false));
        let back = force_through_inverse(&recorded, rate, f_n, zeta);
        let err = |x: &[f64]| x[2500..4999].iter().zip(&u[2500..4999]).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(err(&back) < 2e-3, "{}", err(&back));
        assert!(err(&recorded) > 0.1, "{}", err(&recorded));
    }

    /// u through F: the correction of u by itself, u + (F − 1)[u] = F[u].
    fn second_order(u: &[f64], rate: f64, f_n: f64, zeta: f64, rate_term: bool) -> Vec<f64> {
        let [(y, _)] = corrected_pairs((u, u), (u, u), [Biquad::new(rate, f_n, zeta, rate_term)]);
        y
    }

    /// Filters run side by side are each the filter run alone, to the bit
    /// (the grid's lanes, [`super::grid`]): two different records and
    /// corrections through five filters at once and one at a time.
    #[test]
    fn lanes_are_each_filter_alone() {
        let rate = 500.0;
        let x = |k: usize, f: f64| (2.0 * PI * f * k as f64 / rate).sin() + 0.01 * (k % 7) as f64;
        let (r1, s1): (Vec<f64>, Vec<f64>) = (0..900).map(|k| (x(k, 1.3), x(k, 1.31))).unzip();
        let (r2, s2): (Vec<f64>, Vec<f64>) = (0..900).map(|k| (x(k, 0.7) + 3.0, x(k, 0.69) + 3.0)).unzip();
        let q: [Biquad; 5] =
            std::array::from_fn(|l| Biquad::new(rate, 2.0 + 3.0 * l as f64, 0.05 + 0.08 * l as f64, l % 2 == 1));
        let lanes = corrected_pairs((&r1, &s1), (&r2, &s2), q);
        for (l, (a, b)) in lanes.iter().enumerate() {
            let [(a1, b1)] = corrected_pairs((&r1, &s1), (&r2, &s2), [q[l]]);
            assert_eq!((a.len(), b.len()), (900, 900));
            assert!(a.iter().zip(&a1).chain(b.iter().zip(&b1)).all(|(u, v)| u.to_bits() == v.to_bits()), "lane {l}");
        }
        // The lanes are different filters, not one copied.
        assert!(lanes[0].0 != lanes[1].0 && lanes[0].1 != lanes[4].1);
    }

    /// A sine through the filter, after its transient: the amplitude of the
    /// frequency response |F(iΩ)| (an independent, analytic reference).
    #[test]
    fn sine_amplitude_is_the_frequency_response() {
        let (rate, f_n, zeta) = (500.0, 6.0, 0.15);
        let w = 2.0 * PI * f_n;
        for f_in in [1.0, 5.0, 12.0] {
            let wi = 2.0 * PI * f_in;
            let u: Vec<f64> = (0..10_000).map(|k| (wi * k as f64 / rate).sin()).collect();
            let den = ((w * w - wi * wi).powi(2) + (2.0 * zeta * w * wi).powi(2)).sqrt();
            for (rate_term, num) in [(false, w * w), (true, (w.powi(4) + (2.0 * zeta * w * wi).powi(2)).sqrt())] {
                let y = second_order(&u, rate, f_n, zeta, rate_term);
                let amp = y[8000..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let expect = num / den;
                assert!((amp - expect).abs() < 5e-3 * expect, "{f_in} Hz {rate_term}: {amp} vs {expect}");
            }
        }
    }

    /// The coupling's placebo (the filter run backwards in time,
    /// [`super::coupling_placebo`]) shares the coupling's slow part and not
    /// its transient. A disc on a 6 Hz, ζ 0.2 coupling records a rotor that
    /// starts to accelerate at 1 s (20 rad/s², a stick→slip); the causal
    /// filter is the record, the backward one is off by more than half the
    /// disc's lag Ω̇1/ω² (1.4e-2 rad) before the start, where the rotor
    /// has not moved yet. On a slow swing (0.3 Hz, 0.2 rad) the two agree
    /// within 5 % of the coupling's correction (|G − 1| = 2.5e-3 of the
    /// swing, the apparent inertia both carry; the odd part, the phase of
    /// G − 1, is 0.02 rad there: 2 sin 0.02 = 4 %).
    #[test]
    fn the_placebo_rings_before_the_jump_and_keeps_the_slow_part() {
        let (rate, f_n, zeta) = (500.0, 6.0, 0.2);
        let backwards = |u: &[f64]| {
            let r: Vec<f64> = u.iter().rev().copied().collect();
            let mut y = second_order(&r, rate, f_n, zeta, true);
            y.reverse();
            y
        };
        let t = |k: usize| k as f64 / rate;
        let jump: Vec<f64> = (0..1500).map(|k| if t(k) < 1.0 { 0.0 } else { 10.0 * (t(k) - 1.0).powi(2) }).collect();
        let disc = second_order(&jump, rate, f_n, zeta, true);
        let placebo = backwards(&jump);
        let before = |x: &[f64]| x[400..500].iter().zip(&disc[400..500]).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let lag = 20.0 / (2.0 * PI * f_n).powi(2);
        assert!(before(&placebo) > 0.5 * lag, "{} vs {lag}", before(&placebo));
        assert!(before(&jump) < 1e-12, "the rotor is at rest before the start");
        let swing: Vec<f64> = (0..5000).map(|k| 0.2 * (2.0 * PI * 0.3 * t(k)).sin()).collect();
        let (ahead, behind) = (second_order(&swing, rate, f_n, zeta, true), backwards(&swing));
        let window = 1500..3500;
        let diff = window.clone().fold(0.0f64, |m, k| m.max((ahead[k] - behind[k]).abs()));
        let correction = window.fold(0.0f64, |m, k| m.max((ahead[k] - swing[k]).abs()));
        assert!(correction > 1e-4 && diff < 0.05 * correction, "{diff} vs {correction}");
    }

    /// A constant input stays where it is (unit DC gain, started at rest).
    #[test]
    fn rest_stays_at_rest() {
        for rate_term in [false, true] {
            assert!(second_order(&[3.5; 200], 500.0, 4.0, 0.1, rate_term).iter().all(|y| (y - 3.5).abs() < 1e-12));
        }
    }
}
