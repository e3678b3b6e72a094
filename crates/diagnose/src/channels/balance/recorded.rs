//! Every operating point's channels read once per campaign, and the
//! balances built from them as recorded or through a transform.

use super::super::stuck_stretches;
use super::rows::{row_at, rows_lanes};
use super::{BalanceData, EVENT_ROWS, Row, RunRows};
use crate::DiagnoseOptions;
use crate::channels::ChannelOptions;
use crate::prepare::diff_noise;
use rig_calibrate::CampaignCalibration;
use rig_types::sensor::{ForceCal, force_n, nominal_window_samples, ticks_to_rad};
use rig_types::{Campaign, RunKind};
use std::borrow::Cow;

/// The stick↔slip transitions of a recorded rotor encoder from sample
/// `from` on, as (kind: 0 slip→stick, 1 stick→slip; sample): both ends of every stuck stretch (|Ω1| below
/// `slip_rad_s` on the documented differentiator, `rig_types::sensor`) that
/// lasts at least [`crate::extension::dwell::MIN_DWELL_S`] (shorter ones are
/// the speed's chatter around the threshold, not a stick).
fn transitions(time_s: &[f64], ticks: &[i64], per_rev: u32, slip_rad_s: f64, from: usize) -> Vec<(usize, usize)> {
    let w1 = rig_types::sensor::encoder_speed_rad_s(time_s, ticks, per_rev);
    stuck_stretches(&w1, slip_rad_s)
        .into_iter()
        .filter(|&(j, k)| time_s[k] - time_s[j] >= crate::extension::dwell::MIN_DWELL_S)
        .flat_map(|(j, k)| [(0, j), (1, k)])
        .filter(|&(_, e)| e >= from)
        .collect()
}

/// One operating point's channels in physical units (rotor and motor
/// angle, rad; force, N) and what no realignment or sensor model of them
/// changes: where its steady state starts and its stick↔slip transitions,
/// located on the rotor encoder as recorded (so every realignment of the
/// delay grid and every sensor model is scored on the same transitions).
#[derive(Debug, Clone)]
pub struct RecordedRun {
    pub id: String,
    pub rotor_rad: Vec<f64>,
    pub motor_rad: Vec<f64>,
    pub force_n: Vec<f64>,
    /// First sample of the steady state (after the ramp and `settle_s`).
    pub(super) from: usize,
    pub(super) transitions: Vec<(usize, usize)>,
    /// The recorded force's noise (first differences, [`diff_noise`]): the
    /// torque balance check's floor, which only the balance as recorded uses.
    pub(super) force_noise_n: f64,
}

impl RecordedRun {
    /// The run's stick→slip transitions in its steady state, each with the
    /// sample of the transition that follows it (the record's end when
    /// none): located on the rotor encoder as recorded, as the balance's
    /// event-locked rows are (the force sensor's ring after each
    /// break-away, [`crate::structure`]).
    pub fn breakaways(&self) -> Vec<(usize, usize)> {
        let end = self.rotor_rad.len();
        let t = &self.transitions;
        (0..t.len()).filter(|&i| t[i].0 == 1).map(|i| (t[i].1, t.get(i + 1).map_or(end, |x| x.1))).collect()
    }
}

/// Every operating point's channels, read once per campaign: the balance
/// as recorded ([`Recorded::balance`]) and through any realignment or
/// sensor model ([`Recorded::balance_with`]) are built from it, so the
/// structural candidates' grids ([`crate::structure`]) do not convert
/// ticks, locate transitions or measure noise once per grid point.
#[derive(Debug, Clone)]
pub struct Recorded {
    pub runs: Vec<RecordedRun>,
    /// The operating points' sample rate as their time columns measure it,
    /// Hz ([`Campaign::clock_rate_hz`]): the balance's derivatives divide by
    /// the time that elapsed, not by the declared rate's.
    pub(super) rate_hz: f64,
    /// The balance window, samples (`balance_window_s` at `rate_hz`).
    pub(super) w: usize,
    /// The sample step, s: 1 / `rate_hz`.
    pub(super) dt: f64,
    pub(super) r_m: f64,
    /// Σk²/(Σk)² of the triangle kernel: the variance gain of white noise.
    pub(super) kernel_gain: f64,
    pub(super) j1_kgm2: f64,
}

/// A run's three channels as a transform leaves them: rotor angle (rad),
/// motor angle (rad), force (N), borrowed where left as recorded.
pub type Channels<'a> = (Cow<'a, [f64]>, Cow<'a, [f64]>, Cow<'a, [f64]>);

impl Recorded {
    /// The operating points of `c` with their three channels.
    pub fn of(c: &Campaign, cal: &CampaignCalibration, opts: &DiagnoseOptions, o: &ChannelOptions) -> Self {
        let rate_hz = c.clock_rate_hz("operating_point");
        let w = nominal_window_samples(o.balance_window_s, rate_hz).max(2);
        let kernel_gain = {
            let ks: Vec<f64> = (0..=2 * w).map(|k| (w - k.abs_diff(w)) as f64).collect();
            ks.iter().map(|k| k * k).sum::<f64>() / ks.iter().sum::<f64>().powi(2)
        };
        let mut runs = Vec::new();
        for run in c.runs_of("operating_point") {
            let RunKind::OperatingPoint { ramp_s, .. } = run.kind else { continue };
            let d = &run.data;
            let (Some(t1), Some(t2), Some(mv)) = (&d.rotor_ticks, &d.motor_ticks, &d.brake_force_mv) else { continue };
            let f =
                force_n(mv, ForceCal { factor_mv_per_n: cal.force_factor_mv_per_n, offset_mv: cal.force_offset_mv });
            let from = d.time_s.partition_point(|&x| x < ramp_s + opts.settle_s);
            let per_rev = c.rig.encoder_ticks_per_rev;
            runs.push(RecordedRun {
                id: run.id.clone(),
                rotor_rad: ticks_to_rad(t1, per_rev),
                motor_rad: ticks_to_rad(t2, per_rev),
                force_noise_n: diff_noise(&f),
                force_n: f,
                from,
                transitions: transitions(&d.time_s, t1, per_rev, opts.slip_speed_rad_s, from.max(w)),
            });
        }
        Recorded {
            runs,
            rate_hz,
            w,
            dt: 1.0 / rate_hz,
            r_m: c.rig.brake_disc_radius_m,
            kernel_gain,
            j1_kgm2: cal.rotor_inertia_kgm2,
        }
    }

    /// The operating points' sample rate as their time columns measure it,
    /// Hz: what the structural grids count their delays and filters in.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// The brake disc's radius, m (the force's lever arm, Eq. 4-10's r).
    pub fn disc_radius_m(&self) -> f64 {
        self.r_m
    }

    /// The balance of the channels as recorded.
    pub fn balance(&self) -> BalanceData {
        self.balance_with(|_, r| {
            (r.rotor_rad.as_slice().into(), r.motor_rad.as_slice().into(), r.force_n.as_slice().into())
        })
    }

    /// The balance of the channels as `transform` gives them (the
    /// realignments and sensor models of [`crate::structure`]): it is handed
    /// each run with its index and returns the run's [`Channels`], whole
    /// records. The event-locked rows stay at the recorded transitions.
    pub fn balance_with<'a>(&'a self, transform: impl Fn(usize, &'a RecordedRun) -> Channels<'a>) -> BalanceData {
        let [data] = self.balance_lanes(|i, run| [transform(i, run)]);
        data
    }

    /// `L` balances at once, [`Recorded::balance_with`] of each of the `L`
    /// channel sets `transform` gives a run: one call per run (a sensor
    /// grid's points filter a run's channels together, `crate::structure`),
    /// each lane's rows and sums built exactly as `balance_with` builds
    /// them, so each lane is that balance to the bit.
    pub fn balance_lanes<'a, const L: usize>(
        &'a self,
        transform: impl Fn(usize, &'a RecordedRun) -> [Channels<'a>; L],
    ) -> [BalanceData; L] {
        let mut lanes: [Vec<RunRows>; L] = std::array::from_fn(|_| Vec::with_capacity(self.runs.len()));
        for (i, run) in self.runs.iter().enumerate() {
            let channels = transform(i, run);
            let grids = rows_lanes::<L>(
                std::array::from_fn(|l| (&*channels[l].0, &*channels[l].1, &*channels[l].2)),
                self.dt,
                self.w,
                self.r_m,
                run.from,
            );
            for ((lane, channels), grid) in lanes.iter_mut().zip(channels).zip(grids) {
                lane.push(self.run_rows(run, channels, grid));
            }
        }
        lanes.map(|runs| BalanceData { runs, j1_kgm2: self.j1_kgm2, window_s: self.w as f64 * self.dt })
    }

    /// One run's [`RunRows`] from its channels `(phi1, phi2, f)` and their
    /// grid rows (`rows` of the channels from `run.from`).
    fn run_rows(&self, run: &RecordedRun, (phi1, phi2, f): Channels<'_>, grid: Vec<Row>) -> RunRows {
        let (w, dt, r_m) = (self.w, self.dt, self.r_m);
        let angle_rad = (0..grid.len()).map(|j| phi1[run.from.max(w) + j * w]).collect();
        let events = run
            .transitions
            .iter()
            .filter_map(|&(kind, e)| {
                let rows: Option<Vec<Row>> =
                    (0..EVENT_ROWS).map(|j| row_at(&phi1, &phi2, &f, dt, w, r_m, e + j * w)).collect();
                rows.map(|r| (kind, r))
            })
            .collect();
        let (mut ata, mut atb, mut yty) = ([0.0; 25], [0.0; 5], 0.0);
        for (x, y) in &grid {
            let y = y + self.j1_kgm2 * x[0];
            yty += y * y;
            for i in 0..5 {
                atb[i] += x[i] * y;
                for j in 0..5 {
                    ata[5 * i + j] += x[i] * x[j];
                }
            }
        }
        RunRows {
            id: run.id.clone(),
            rows: grid,
            angle_rad,
            events,
            force_noise_n: run.force_noise_n,
            kernel_gain: self.kernel_gain,
            ata,
            atb,
            yty,
        }
    }
}

/// A test run's (id, rotor angle rad, motor angle rad, force N).
#[cfg(test)]
pub(crate) type TestRun = (String, Vec<f64>, Vec<f64>, Vec<f64>);

#[cfg(test)]
impl Recorded {
    /// Test records: each run's (id, rotor angle rad, motor angle rad, force
    /// N) at `rate_hz`, steady from its first sample, without transitions;
    /// the balance window `window_s`, J1 `j1_kgm2`, disc radius `r_m`.
    pub(crate) fn of_channels(runs: Vec<TestRun>, rate_hz: f64, window_s: f64, r_m: f64, j1_kgm2: f64) -> Self {
        let w = nominal_window_samples(window_s, rate_hz).max(2);
        let runs = runs
            .into_iter()
            .map(|(id, rotor_rad, motor_rad, force_n)| RecordedRun {
                id,
                rotor_rad,
                motor_rad,
                force_noise_n: diff_noise(&force_n),
                force_n,
                from: 0,
                transitions: Vec::new(),
            })
            .collect();
        Recorded { runs, rate_hz, w, dt: 1.0 / rate_hz, r_m, kernel_gain: 1.0, j1_kgm2 }
    }
}
