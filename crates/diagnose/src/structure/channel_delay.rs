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
//! a delay consistent across folds. When the tick-loss check flags the
//! records ([`crate::channels::tick_loss_check_of`]: the twist grows with
//! the angle travelled, a lost tick is never given back) the rotor encoder's
//! delays are not tried: its count falls behind, it is not late.

use super::{Aligned, Fitted, ParamSpec, StructureCandidate, StructureData};
use crate::channels::{BalanceData, Recorded, advanced};
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

/// The balance of `c` with each channel advanced by 1 … [`MAX_DELAY_S`] samples.
pub(super) fn grid(rec: &Recorded, rate_hz: f64) -> Vec<Aligned> {
    let n = (MAX_DELAY_S * rate_hz).round() as usize;
    let mut out = Vec::new();
    for channel in [DelayedChannel::RotorEncoder, DelayedChannel::Force] {
        for samples in 1..=n {
            let data = rec.balance_with(|_, r| match channel {
                DelayedChannel::RotorEncoder => {
                    (advanced(&r.rotor_rad, samples).into(), r.motor_rad.as_slice().into(), r.force_n.as_slice().into())
                }
                DelayedChannel::Force => {
                    (r.rotor_rad.as_slice().into(), r.motor_rad.as_slice().into(), advanced(&r.force_n, samples).into())
                }
            });
            out.push(Aligned { channel, samples, delay_s: samples as f64 / rate_hz, data });
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
        if let Some(a) = best.map(|i| &data.aligned[i]) {
            values[usize::from(a.channel == DelayedChannel::Force)] = a.delay_s;
        }
        Some(Fitted { values, balance: best_fit, aligned: best, sensor: None })
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
