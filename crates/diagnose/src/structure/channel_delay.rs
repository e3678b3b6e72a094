//! Structural candidate `channel_delay`: one recorded channel of the
//! operating points lags the others by a transport delay (a FIFO or filter
//! latency of the acquisition chain), x_rec[k] = x[k − d]. The rig is the
//! rig model (damping on the twist rate); only the record is late, so the
//! candidate changes no simulated motion.
//!
//! # What the delay does to the rotor balance
//!
//! Eq. 4-7's first row with the measured r·F (J1 Ω̇1 = K tw + C tẇ − r·F,
//! [`crate::channels::BalanceData`]) over 0.1 s windows: a rotor encoder
//! late by d reads the twist φ2 − φ1(t − d) ≈ tw + Ω1·d, so in every steady
//! slip the balance is off by K·Ω1·d, a torque that grows with the slip speed
//! like a drag C_r = K·d (at K ≈ 0.27 N·m/rad, 6 ms reads as 1.6e-3
//! N·m·s/rad); a late force channel reads r·F(t − d) ≈ r·F − r·Ḟ·d, which in a
//! stick (r·F ≈ K·tw) is −K·tẇ·d, a twist-rate damping lowered by K·d.
//!
//! # Fit
//!
//! Over a grid of whole-sample delays of each channel (1 sample to
//! [`MAX_DELAY_S`], counted at the campaign's sample rate), the channel is
//! advanced by the delay ([`crate::channels::advanced`]) and the
//! balance refitted with the rig model's structure (C on the twist rate, no
//! drag); the fit is the delay with the smallest sum over training runs of
//! each run's squared RMS residual, or no delay when the records as recorded
//! fit best. The two parameters are the delays of the rotor encoder and of
//! the force channel, one of them 0; the fold-jackknife rule of the
//! selection ([`super`]) then asks every fold to pick the same channel and
//! a delay consistent across folds. A rotor-encoder delay must also be
//! supported by its own footprint in the records as recorded
//! ([`StructureCandidate::support`]): the Ω1 term above, the delay
//! C_r/K that a drag fitted on the as-recorded balance implies, at least
//! `min_t` fold-jackknife errors above 0. A whole-sample realignment also
//! moves the balance's dominant noise, the rotor encoder's quantisation in
//! the Ω̇1 term (J1 times a second difference of the angle over the window),
//! and can lower it by chance: the full battery's
//! `ladder-angle_periodic_friction-1-10` (no delay; a steady slide under a
//! 4 Hz angle-periodic ripple) gains 6.6 % on the balance at one sample of
//! advance and 5.6 % at one sample of delay, the direction no recording
//! chain makes, while the same runs re-simulated without quantisation or
//! noise lose 13× their misfit at either; as recorded its balance wants no
//! Ω1 term (C_r = −8.6e-6 N·m·s/rad, the one-sample delay's footprint
//! K·dt being 5.4e-4). When the tick-loss check flags the
//! records ([`crate::channels::tick_loss_check_of`]: the twist grows with
//! the angle travelled, a lost tick is never given back) the rotor encoder's
//! delays are not tried: its count falls behind, it is not late.

use super::{Aligned, Fitted, ParamSpec, StructureCandidate, StructureData};
use crate::channels::{BalanceData, Channels, Recorded, RecordedRun, advanced};
use rig_types::RigParams;

pub struct ChannelDelay;

/// The finding's id.
pub const ID: &str = "channel_delay";

/// The longest delay tried, s: 10 samples at 500 Hz, beyond the latency of a
/// FIFO or an anti-alias filter of an acquisition chain at these rates.
pub const MAX_DELAY_S: f64 = 0.02;

/// A recorded channel that may lag the others.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DelayedChannel {
    RotorEncoder,
    Force,
}

impl DelayedChannel {
    pub fn name(self) -> &'static str {
        match self {
            DelayedChannel::RotorEncoder => "rotor encoder",
            DelayedChannel::Force => "force sensor",
        }
    }
}

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "rotor_encoder_delay_s",
        unit: "s",
        lower: 0.0,
        meaning: "how late the rotor encoder's angle is recorded against the other channels",
    },
    ParamSpec {
        name: "force_delay_s",
        unit: "s",
        lower: 0.0,
        meaning: "how late the brake force is recorded against the other channels",
    },
];

/// A rotor-encoder delay's footprint in the records as recorded (module
/// docs): the rotor encoder late by d reads the twist as tw + Ω1·d, so the
/// balance fitted with a drag on Ω1 reads C_r = K·d; the baseline is d = 0.
const FOOTPRINT: ParamSpec = ParamSpec {
    name: "rotor_encoder_delay_implied_s",
    unit: "s",
    lower: 0.0,
    meaning: "the rotor encoder's delay that the as-recorded balance's Ω1 term implies, C_r/K",
};

/// The delay C_r/K (s) that the as-recorded balance of the runs `include`
/// accepts implies, its twist-rate damping and drag fitted together
/// (Eq. 4-7's first row with the measured r·F; module docs); `None` when
/// singular or K ≤ 0.
fn implied_rotor_delay_s(data: &BalanceData, include: &dyn Fn(&str) -> bool) -> Option<f64> {
    let f = data.fit(include, true, true)?;
    (f.stiffness_nm_rad > 0.0).then(|| f.rotor_drag_nm_s_rad / f.stiffness_nm_rad)
}

/// Delays of one channel whose balances are built together
/// ([`Recorded::balance_lanes`]: each lane the balance [`Recorded::balance_with`]
/// builds, to the bit; a force delay's lanes share the recorded angles and
/// so the twist's sums). 5 divides the grid at 500 Hz and 1 kHz (10 and 20
/// delays); a remainder is built one by one.
const LANES: usize = 5;

/// The channels of run `r` with `channel` advanced by `samples`.
fn delayed(channel: DelayedChannel, samples: usize, r: &RecordedRun) -> Channels<'_> {
    match channel {
        DelayedChannel::RotorEncoder => {
            (advanced(&r.rotor_rad, samples).into(), r.motor_rad.as_slice().into(), r.force_n.as_slice().into())
        }
        DelayedChannel::Force => {
            (r.rotor_rad.as_slice().into(), r.motor_rad.as_slice().into(), advanced(&r.force_n, samples).into())
        }
    }
}

/// The balance of `c` with each channel advanced by 1 … [`MAX_DELAY_S`] samples.
pub(super) fn grid(rec: &Recorded, rate_hz: f64) -> Vec<Aligned> {
    let n = (MAX_DELAY_S * rate_hz).round() as usize;
    let delays: Vec<usize> = (1..=n).collect();
    let mut out = Vec::with_capacity(2 * n);
    for channel in [DelayedChannel::RotorEncoder, DelayedChannel::Force] {
        for chunk in delays.chunks(LANES) {
            let data: Vec<BalanceData> = match <[usize; LANES]>::try_from(chunk) {
                Ok(lanes) => rec.balance_lanes(|_, r| lanes.map(|samples| delayed(channel, samples, r))).into(),
                Err(_) => chunk.iter().map(|&samples| rec.balance_with(|_, r| delayed(channel, samples, r))).collect(),
            };
            out.extend(chunk.iter().zip(data).map(|(&samples, data)| Aligned {
                channel,
                samples,
                delay_s: samples as f64 / rate_hz,
                data,
            }));
        }
    }
    out
}

/// Sum over the runs `include` accepts of each run's squared RMS residual of
/// the twist-rate balance fitted on them and of its squared event-locked
/// misfit ([`BalanceData::run_event_rms`]: where a sensor's lag shows);
/// `None` when singular.
pub(super) fn training_cost(
    data: &BalanceData,
    include: &dyn Fn(&str) -> bool,
) -> Option<(f64, crate::channels::BalanceFit)> {
    let fit = data.fit(include, true, false)?;
    let sq = |v: Vec<(String, f64)>| v.iter().map(|(_, r)| r * r).sum::<f64>();
    Some((sq(data.run_rms(&fit, include)) + sq(data.run_event_rms(&fit, include)), fit))
}

/// The edge of `channel`'s delay grid when `fitted` is there: its delay
/// within half a sample of [`MAX_DELAY_S`] (the grid's last whole sample).
fn at_longest_delay(channel: DelayedChannel, fitted: &Fitted) -> Option<super::GridEdge> {
    let i = usize::from(channel == DelayedChannel::Force);
    let d = fitted.values[i];
    // The grid's whole samples: its last is MAX_DELAY_S rounded at the rate, so
    // a delay within 0.5 ms of it (a sample at up to 1 kHz) is that last point.
    (d > 0.0 && (d - MAX_DELAY_S).abs() < 5e-4).then(|| super::GridEdge {
        param: &PARAMS[i],
        edge: d,
        what: format!("the {} {:.1} ms late, the longest delay tried", channel.name(), 1e3 * d),
    })
}

impl StructureCandidate for ChannelDelay {
    fn id(&self) -> &'static str {
        ID
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn fit(&self, _model: &RigParams, data: &StructureData, include: &dyn Fn(&str) -> bool) -> Option<Fitted> {
        let (mut best_cost, mut best_fit) = training_cost(&data.balance, include)?;
        let mut best: Option<usize> = None;
        // A rotor encoder that loses ticks falls behind for good; a delay of it
        // would be fitted to the lost ticks' growing twist (the tick-loss
        // check, `crate::channels::tick_loss_check_of`, names that fault).
        let tried = data
            .aligned
            .iter()
            .enumerate()
            .filter(|(_, a)| !(data.tick_loss && a.channel == DelayedChannel::RotorEncoder));
        for (i, a) in tried {
            if let Some((cost, fit)) = training_cost(&a.data, include)
                && cost < best_cost
            {
                (best_cost, best_fit, best) = (cost, fit, Some(i));
            }
        }
        let mut values = vec![0.0; 2];
        let mut footprint = None;
        if let Some(a) = best.map(|i| &data.aligned[i]) {
            values[usize::from(a.channel == DelayedChannel::Force)] = a.delay_s;
            if a.channel == DelayedChannel::RotorEncoder {
                footprint = implied_rotor_delay_s(&data.balance, include);
            }
        }
        Some(Fitted { values, balance: best_fit, aligned: best, sensor: None, footprint })
    }
    /// A rotor-encoder delay is supported by its footprint as recorded, the
    /// delay the balance's Ω1 term implies ([`implied_rotor_delay_s`]; module
    /// docs), not by the realignment's fit alone; a force delay by its value.
    fn support(&self, fitted: &Fitted) -> Vec<(&'static str, f64, &'static ParamSpec)> {
        let rotor = match fitted.footprint {
            Some(d) if fitted.values[0] > 0.0 => (FOOTPRINT.name, d, &FOOTPRINT),
            _ => (PARAMS[0].name, fitted.values[0], &PARAMS[0]),
        };
        vec![rotor, (PARAMS[1].name, fitted.values[1], &PARAMS[1])]
    }
    /// The rig is the model's: only the record is late.
    fn apply(&self, model: &RigParams, _fitted: &Fitted) -> RigParams {
        model.clone()
    }
    /// At [`MAX_DELAY_S`], the grid's longest delay (module docs of
    /// [`super`], "A fit at its grid's edge").
    fn at_grid_edge(&self, fitted: &Fitted) -> Option<super::GridEdge> {
        let longest = |c: DelayedChannel| at_longest_delay(c, fitted);
        longest(DelayedChannel::RotorEncoder).or_else(|| longest(DelayedChannel::Force))
    }
    fn describe(&self, fitted: &Fitted) -> String {
        let (r, f) = (fitted.values[0], fitted.values[1]);
        let b = &fitted.balance;
        let (channel, d) = if f > 0.0 { (DelayedChannel::Force, f) } else { (DelayedChannel::RotorEncoder, r) };
        if d > 0.0 {
            format!(
                "the {} recorded {:.1} ms late (the rig model's damping on the twist rate, C = {:.2e} N·m·s/rad in \
                 the realigned balance)",
                channel.name(),
                1e3 * d,
                b.twist_damping_nm_s_rad
            )
        } else {
            "no channel delay (the records as recorded fit the balance best)".into()
        }
    }
    fn damping(&self) -> &'static str {
        super::twist_rate::ID
    }
    fn moves(&self) -> bool {
        false
    }
    fn finding_id(&self) -> Option<&'static str> {
        Some(ID)
    }
}

#[cfg(test)]
mod tests {
    use super::{DelayedChannel, FOOTPRINT, PARAMS, delayed, grid, implied_rotor_delay_s};
    use crate::channels::Recorded;
    use crate::structure::{Fitted, StructureCandidate};

    /// Steady slides at five speeds under a 4 Hz ripple of the rotor, the
    /// force from Eq. 4-7's first row (K, C on the twist rate, no drag), the
    /// angles quantised by a 1000-tick encoder; the rotor encoder recorded
    /// `late` samples late.
    fn records(late: usize) -> Recorded {
        let (rate, n, j1, k, c, r_m) = (500.0, 15_000usize, 0.03, 0.27, 0.015, 0.09);
        let tick = 2.0 * std::f64::consts::PI / 1000.0;
        let q = |x: f64| (x / tick).floor() * tick;
        let w_rip = 2.0 * std::f64::consts::PI * 4.0;
        let runs = [2.0, 4.0, 7.0, 11.0, 15.0]
            .iter()
            .enumerate()
            .map(|(i, &omega)| {
                let t = |j: usize| j as f64 / rate;
                // φ1 = Ωt + A sin(ω t); φ2 = Ωt + tw0 (the drive holds its speed);
                // the mean twist (the normal force's friction) not a line in Ω.
                let (a, tw0) = (0.004, [0.6, 0.3, 0.9, 0.45, 0.75][i]);
                let phi1 = |x: f64| omega * x + a * (w_rip * x).sin();
                let force: Vec<f64> = (0..n)
                    .map(|j| {
                        let x = t(j);
                        let tw = tw0 - a * (w_rip * x).sin();
                        let twd = -a * w_rip * (w_rip * x).cos();
                        let acc = -a * w_rip * w_rip * (w_rip * x).sin();
                        (k * tw + c * twd - j1 * acc) / r_m
                    })
                    .collect();
                let rotor = (0..n).map(|j| q(phi1(t(j) - late as f64 / rate))).collect();
                let motor = (0..n).map(|j| q(omega * t(j) + tw0)).collect();
                (format!("op-{i}"), rotor, motor, force)
            })
            .collect();
        Recorded::of_channels(runs, rate, 0.1, r_m, j1)
    }

    /// The footprint of a late rotor encoder in the balance as recorded: a
    /// drag C_r = K·d on Ω1 (module docs), so C_r/K gives the delay back;
    /// without a delay it is ≈ 0 (well below one sample), whatever the
    /// quantisation does to the realigned balances.
    #[test]
    fn a_late_rotor_encoder_shows_as_its_delay_in_the_as_recorded_drag() {
        let dt = 1.0 / 500.0;
        for late in [0usize, 2, 4] {
            let rec = records(late);
            let d = implied_rotor_delay_s(&rec.balance(), &|_| true).expect("a fit");
            assert!((d - late as f64 * dt).abs() < 0.25 * dt, "{late} samples late: implied {d:.2e} s");
        }
    }

    /// The grid's balances, built five delays at a time, are each delay's
    /// balance built alone ([`Recorded::balance_with`]) to the bit: their
    /// fits with every damping term and each run's residual RMS, on all runs
    /// and on a subset; at 500 Hz (10 delays a channel: two batches) and at
    /// 400 Hz (8: a batch and three alone).
    #[test]
    fn the_delay_grid_is_each_delays_own_balance_to_the_bit() {
        let rec = records(3);
        let (all, subset) = (|_: &str| true, |id: &str| id != "op-1" && id != "op-3");
        let includes: [&dyn Fn(&str) -> bool; 2] = [&all, &subset];
        let bits = |data: &crate::channels::BalanceData, include: &dyn Fn(&str) -> bool| {
            let f = data.fit(include, true, true).expect("a fit");
            let rms: Vec<u64> = data.run_rms(&f, include).iter().map(|x| x.1.to_bits()).collect();
            let fit = [f.stiffness_nm_rad, f.twist_damping_nm_s_rad, f.rotor_drag_nm_s_rad, f.offset_nm];
            (fit.map(f64::to_bits), rms)
        };
        for (rate_hz, n) in [(500.0, 10), (400.0, 8)] {
            let g = grid(&rec, rate_hz);
            assert_eq!(g.len(), 2 * n);
            for (i, a) in g.iter().enumerate() {
                let channel = if i < n { DelayedChannel::RotorEncoder } else { DelayedChannel::Force };
                assert_eq!((a.channel, a.samples), (channel, i % n + 1));
                let alone = rec.balance_with(|_, r| delayed(channel, a.samples, r));
                for include in includes {
                    assert_eq!(bits(&a.data, include), bits(&alone, include), "{channel:?} {} samples", a.samples);
                }
            }
        }
    }

    /// The rotor delay is supported by that footprint, the force delay by its value.
    #[test]
    fn the_rotor_delay_is_supported_by_its_footprint() {
        let balance = crate::channels::BalanceFit {
            stiffness_nm_rad: 0.27,
            twist_damping_nm_s_rad: 0.0,
            rotor_drag_nm_s_rad: 0.0,
            offset_nm: 0.0,
        };
        let f = |values: Vec<f64>, footprint| Fitted { values, balance, aligned: None, sensor: None, footprint };
        let rotor = super::ChannelDelay.support(&f(vec![0.002, 0.0], Some(1e-5)));
        assert_eq!((rotor[0].0, rotor[0].1), (FOOTPRINT.name, 1e-5));
        let force = super::ChannelDelay.support(&f(vec![0.0, 0.006], None));
        assert_eq!((force[0].0, force[0].1, force[1].1), (PARAMS[0].name, 0.0, 0.006));
    }
}
