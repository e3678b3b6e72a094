//! Torque balance of rotor 1 in the measured channels of the operating
//! points: encoders and force sensor must satisfy the rotor equation.

use super::{ChannelCheck, ChannelOptions, rms, stuck_stretches};
use crate::DiagnoseOptions;
use crate::prepare::diff_noise;
use rig_calibrate::CampaignCalibration;
use rig_types::sensor::{ForceCal, force_n, nominal_window_samples, tick_rad, ticks_to_rad};
use rig_types::{Campaign, RigParams, RunKind};
use std::borrow::Cow;

/// Regressors of one window boundary: [⟨Ω̇1⟩, ⟨φ2−φ1⟩, ⟨Ω2−Ω1⟩, ⟨Ω1⟩, 1] and r⟨F⟩.
type Row = ([f64; 5], f64);

/// Triangle-weighted means around the boundary b (weights w − |k − b|),
/// the kernel for which (mean speed of the next window − of the previous) / T
/// is exactly the weighted mean of the acceleration, so no derivative of a
/// quantised angle is taken. `None` when the kernel leaves the record.
fn row_at(phi1: &[f64], phi2: &[f64], force_n: &[f64], dt: f64, w: usize, r_m: f64, b: usize) -> Option<Row> {
    let n = phi1.len().min(phi2.len()).min(force_n.len());
    if b < w || b + w >= n {
        return None;
    }
    let tw = |k: usize| phi2[k] - phi1[k];
    let big_t = w as f64 * dt;
    let (mut s_tw, mut s_f, mut s_k) = (0.0, 0.0, 0.0);
    for (k, &f) in force_n.iter().enumerate().take(b + w + 1).skip(b - w) {
        let wt = (w - k.abs_diff(b)) as f64;
        s_tw += wt * tw(k);
        s_f += wt * f;
        s_k += wt;
    }
    let w1_prev = (phi1[b] - phi1[b - w]) / big_t;
    let w1_next = (phi1[b + w] - phi1[b]) / big_t;
    let tw_prev = (tw(b) - tw(b - w)) / big_t;
    let tw_next = (tw(b + w) - tw(b)) / big_t;
    Some((
        [(w1_next - w1_prev) / big_t, s_tw / s_k, 0.5 * (tw_prev + tw_next), 0.5 * (w1_prev + w1_next), 1.0],
        r_m * s_f / s_k,
    ))
}

/// [`row_at`] every `w` samples from `from` on (the steady state's grid),
/// for `L` channel sets of one run at once (a sensor grid's points,
/// [`Recorded::balance_lanes`]; one set is `L = 1`). The triangle-weighted
/// means come from running box sums: the triangle w − |k − b| (|k − b| < w)
/// is a box of w samples convolved with itself, so its weighted sum at b is
/// the sum of the w box sums B(s) = Σ x[s..s+w] for s = b − w + 1 … b, and B
/// is updated by one sample in and one out (the same rows as [`row_at`]'s
/// to rounding, without its 2w + 1 products per boundary; a campaign's
/// structural grids build ≈ 100 balances of every run). The running sums
/// are additions each waiting for its last (latency-bound) and the lanes'
/// are independent, so one pass with the lanes interleaved lets the
/// processor overlap them; each lane performs the same operations in the
/// same order as it would alone (`L = 1`), so it is its own rows to the
/// bit. Lanes of unequal length are built one after the other. Lanes that
/// read the same angles (the same slices: a force sensor's points, which
/// change the force alone) share their twist's running sums, computed once
/// by the same operations in the same order, so each lane's rows are still
/// its own to the bit.
fn rows_lanes<const L: usize>(
    lanes: [(&[f64], &[f64], &[f64]); L],
    dt: f64,
    w: usize,
    r_m: f64,
    from: usize,
) -> [Vec<Row>; L] {
    let len = |(phi1, phi2, force_n): (&[f64], &[f64], &[f64])| phi1.len().min(phi2.len()).min(force_n.len());
    let n = len(lanes[0]);
    if L > 1 && lanes.iter().any(|&c| len(c) != n) {
        return lanes.map(|c| {
            let [out] = rows_lanes([c], dt, w, r_m, from);
            out
        });
    }
    let same = |a: &[f64], b: &[f64]| std::ptr::eq(a, b);
    if L > 1 && lanes.iter().all(|c| same(c.0, lanes[0].0) && same(c.1, lanes[0].1)) {
        rows_lanes_of::<L, true>(lanes, n, dt, w, r_m, from)
    } else {
        rows_lanes_of::<L, false>(lanes, n, dt, w, r_m, from)
    }
}

/// [`rows_lanes`] of `L` lanes of `n` samples each; with `SHARED_ANGLES`
/// every lane reads lane 0's angles and the twist's sums are lane 0's.
fn rows_lanes_of<const L: usize, const SHARED_ANGLES: bool>(
    lanes: [(&[f64], &[f64], &[f64]); L],
    n: usize,
    dt: f64,
    w: usize,
    r_m: f64,
    from: usize,
) -> [Vec<Row>; L] {
    let tw_lanes = if SHARED_ANGLES { 1 } else { L };
    let first = from.max(w);
    if first + w >= n {
        return std::array::from_fn(|_| Vec::new());
    }
    let tw = |l: usize, k: usize| lanes[l].1[k] - lanes[l].0[k];
    let big_t = w as f64 * dt;
    let s_k = (w * w) as f64;
    // Box sums starting at s = first − w + 1, advanced along the boundaries.
    let mut s = first + 1 - w;
    let mut b_tw: [f64; L] =
        std::array::from_fn(|l| if l < tw_lanes { (s..s + w).map(|k| tw(l, k)).sum::<f64>() } else { 0.0 });
    let mut b_f: [f64; L] = std::array::from_fn(|l| lanes[l].2[s..s + w].iter().sum::<f64>());
    let mut out: [Vec<Row>; L] = std::array::from_fn(|_| Vec::with_capacity((n - first) / w + 1));
    let mut b = first;
    while b + w < n {
        let (mut t_tw, mut t_f) = ([0.0; L], [0.0; L]);
        // Σ over s = b − w + 1 … b of B(s); on leaving, s = b + 1.
        while s <= b {
            for l in 0..tw_lanes {
                t_tw[l] += b_tw[l];
                b_tw[l] += tw(l, s + w) - tw(l, s);
            }
            for l in 0..L {
                t_f[l] += b_f[l];
                b_f[l] += lanes[l].2[s + w] - lanes[l].2[s];
            }
            s += 1;
        }
        for l in 0..L {
            let t_tw_l = t_tw[if SHARED_ANGLES { 0 } else { l }];
            let phi1 = lanes[l].0;
            let w1_prev = (phi1[b] - phi1[b - w]) / big_t;
            let w1_next = (phi1[b + w] - phi1[b]) / big_t;
            let tw_prev = (tw(l, b) - tw(l, b - w)) / big_t;
            let tw_next = (tw(l, b + w) - tw(l, b)) / big_t;
            out[l].push((
                [(w1_next - w1_prev) / big_t, t_tw_l / s_k, 0.5 * (tw_prev + tw_next), 0.5 * (w1_prev + w1_next), 1.0],
                r_m * t_f[l] / s_k,
            ));
        }
        b += w;
    }
    out
}

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

/// One operating point's balance rows and what its noise floor needs.
#[derive(Debug, Clone)]
struct RunRows {
    id: String,
    rows: Vec<Row>,
    /// The recorded rotor angle at each row's boundary, rad (the tick-loss
    /// check's regressor, [`tick_loss_check_of`]).
    angle_rad: Vec<f64>,
    /// Event-locked rows, per transition: its kind (0 slip→stick, 1
    /// stick→slip) and [`EVENT_ROWS`] rows, one centred on it and one a
    /// window after it.
    events: Vec<(usize, Vec<Row>)>,
    force_noise_n: f64,
    kernel_gain: f64,
    /// The steady rows' normal equations in (Ω̇1, tw, tẇ, Ω1, 1) against
    /// r·F + J1 Ω̇1, row-major 5 × 5, and their right-hand side: summed
    /// once, so a fit on any subset of runs ([`BalanceData::fit`]) is a sum
    /// of 5 × 5 blocks (the structural candidates fit every grid point on
    /// every fold).
    ata: [f64; 25],
    atb: [f64; 5],
    /// Σ (r·F + J1 Ω̇1)² over the steady rows: with `ata` and `atb`, a
    /// fit's sum of squared residuals on the run without its rows
    /// ([`BalanceData::run_rms`]).
    yty: f64,
}

/// The rotor torque balance's data: every operating point's window rows over
/// its steady state, with J1 from the calibration. Built once; fitted on any
/// subset of runs with any of the damping terms ([`BalanceData::fit`]), which
/// is how the structural candidates ([`crate::structure`]) are fitted
/// teacher-forced on training folds.
#[derive(Debug, Clone)]
pub struct BalanceData {
    runs: Vec<RunRows>,
    /// Rotor inertia held at the calibration's (Eqs. 4-4/4-5), kg·m².
    pub j1_kgm2: f64,
}

/// A fitted rotor balance r·F = −J1 Ω̇1 + K tw + C tẇ − C_r Ω1 + c0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalanceFit {
    pub stiffness_nm_rad: f64,
    /// C on the twist rate Ω2 − Ω1 (0 when not fitted).
    pub twist_damping_nm_s_rad: f64,
    /// C_r, a drag on the absolute rotor speed Ω1 (0 when not fitted).
    pub rotor_drag_nm_s_rad: f64,
    pub offset_nm: f64,
}

impl BalanceFit {
    fn beta(&self, j1: f64) -> [f64; 5] {
        [-j1, self.stiffness_nm_rad, self.twist_damping_nm_s_rad, -self.rotor_drag_nm_s_rad, self.offset_nm]
    }
}

/// Event-locked rows per transition: the balance window centred on the
/// transition and the next one (the transition, then what rings after it).
pub const EVENT_ROWS: usize = 2;

/// Transitions of one kind a run needs for its event-triggered average.
pub const MIN_EVENTS: usize = 3;

/// The rows of every operating point of `c` ([`rows`], steady state only).
pub fn balance_data(
    c: &Campaign,
    cal: &CampaignCalibration,
    opts: &DiagnoseOptions,
    o: &ChannelOptions,
) -> BalanceData {
    Recorded::of(c, cal, opts, o).balance()
}

/// `x` advanced by `lead` samples, x'[k] = x[k + lead] (the last sample held):
/// a channel recorded `lead` samples late, put back in time.
pub fn advanced(x: &[f64], lead: usize) -> Vec<f64> {
    let n = x.len();
    (0..n).map(|k| x[(k + lead).min(n - 1)]).collect()
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
    from: usize,
    transitions: Vec<(usize, usize)>,
    /// The recorded force's noise (first differences, [`diff_noise`]): the
    /// torque balance check's floor, which only the balance as recorded uses.
    force_noise_n: f64,
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
    /// The balance window, samples.
    w: usize,
    dt: f64,
    r_m: f64,
    /// Σk²/(Σk)² of the triangle kernel: the variance gain of white noise.
    kernel_gain: f64,
    j1_kgm2: f64,
}

/// A run's three channels as a transform leaves them: rotor angle (rad),
/// motor angle (rad), force (N), borrowed where left as recorded.
pub type Channels<'a> = (Cow<'a, [f64]>, Cow<'a, [f64]>, Cow<'a, [f64]>);

impl Recorded {
    /// The operating points of `c` with their three channels.
    pub fn of(c: &Campaign, cal: &CampaignCalibration, opts: &DiagnoseOptions, o: &ChannelOptions) -> Self {
        let w = nominal_window_samples(o.balance_window_s, c.rig.sample_rate_hz).max(2);
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
            w,
            dt: 1.0 / c.rig.sample_rate_hz,
            r_m: c.rig.brake_disc_radius_m,
            kernel_gain,
            j1_kgm2: cal.rotor_inertia_kgm2,
        }
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
        lanes.map(|runs| BalanceData { runs, j1_kgm2: self.j1_kgm2 })
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

impl BalanceData {
    /// The balance of the force F + Σ a_j G_j on the same angles, from the
    /// balance of F (`self`) and of each G_j (`terms`: (a_j, balance of
    /// G_j), lanes of one [`Recorded::balance_lanes`] call on the same
    /// angles, so the same runs, rows and events). A row's regressors are
    /// the angles' alone and its r⟨F⟩ is a triangle-weighted mean of the
    /// force, linear in it (Eq. 4-7's first row, [`row_at`]): each row,
    /// event-locked rows included, is F's with r⟨F⟩ + Σ a_j r⟨G_j⟩. The
    /// force sensor's inverse H⁻¹[F] = F + a1·D1F + a2·D2F
    /// ([`crate::structure`]) is so built at every grid point from three
    /// balances instead of one pass over every sample per point; it equals
    /// the balance of the combined force built sample by sample up to
    /// rounding (the sums combined, not the samples).
    pub fn force_combination(&self, terms: &[(f64, &BalanceData)]) -> BalanceData {
        let combine = |rows: &[Row], of: &dyn Fn(&BalanceData) -> &[Row]| -> Vec<Row> {
            let mut out = rows.to_vec();
            for &(a, t) in terms {
                let t_rows = of(t);
                debug_assert_eq!(t_rows.len(), out.len(), "a force combination's lanes share their rows");
                for ((_, y), (_, ty)) in out.iter_mut().zip(t_rows) {
                    *y += a * ty;
                }
            }
            out
        };
        let runs = self
            .runs
            .iter()
            .enumerate()
            .map(|(i, r)| {
                debug_assert!(
                    terms.iter().all(|(_, t)| t.runs[i].id == r.id && t.runs[i].events.len() == r.events.len())
                );
                let rows = combine(&r.rows, &|t| &t.runs[i].rows);
                let events = (r.events.iter().enumerate())
                    .map(|(e, (kind, e_rows))| (*kind, combine(e_rows, &|t| &t.runs[i].events[e].1)))
                    .collect();
                // The regressors are `self`'s, so XᵀX is too; Xᵀy and yᵀy of
                // the new y, summed as [`Recorded::balance_lanes`] sums them.
                let (mut atb, mut yty) = ([0.0; 5], 0.0);
                for (x, y) in &rows {
                    let y = y + self.j1_kgm2 * x[0];
                    yty += y * y;
                    for k in 0..5 {
                        atb[k] += x[k] * y;
                    }
                }
                RunRows {
                    id: r.id.clone(),
                    rows,
                    angle_rad: r.angle_rad.clone(),
                    events,
                    force_noise_n: r.force_noise_n,
                    kernel_gain: r.kernel_gain,
                    ata: r.ata,
                    atb,
                    yty,
                }
            })
            .collect();
        BalanceData { runs, j1_kgm2: self.j1_kgm2 }
    }

    /// Least squares of the balance over the runs `include` accepts, J1
    /// held; C (twist rate) and C_r (absolute rotor speed) are fitted only
    /// when asked, else held at 0. `None` when the regression is singular.
    pub fn fit(&self, include: impl Fn(&str) -> bool, twist_damping: bool, rotor_drag: bool) -> Option<BalanceFit> {
        let free = [false, true, twist_damping, rotor_drag, true];
        // The runs' normal equations summed over the free columns; a held
        // coefficient gets a unit diagonal and no data (one unit row pins it at 0).
        let (mut ata, mut atb) = ([0.0; 25], [0.0; 5]);
        for r in self.runs.iter().filter(|r| include(&r.id)) {
            for i in (0..5).filter(|&i| free[i]) {
                atb[i] += r.atb[i];
                for j in (0..5).filter(|&j| free[j]) {
                    ata[5 * i + j] += r.ata[5 * i + j];
                }
            }
        }
        for i in (0..5).filter(|&i| !free[i]) {
            ata[5 * i + i] = 1.0;
        }
        let b = rig_estimate::linear::Normal::from_row_major(5, &ata, atb.to_vec()).solve()?;
        Some(BalanceFit {
            stiffness_nm_rad: b[1],
            twist_damping_nm_s_rad: b[2],
            rotor_drag_nm_s_rad: -b[3],
            offset_nm: b[4],
        })
    }

    /// Each run's RMS residual of `fit`, N·m, over the runs `include`
    /// accepts (runs without rows left out): the teacher-forced misfit a
    /// structural candidate is compared on.
    pub fn run_rms(&self, fit: &BalanceFit, include: impl Fn(&str) -> bool) -> Vec<(String, f64)> {
        // r = y' − γ·x with y' = r·F + J1 Ω̇1 and γ the fit without its J1:
        // Σr² = y'ᵀy' − 2γᵀXᵀy' + γᵀXᵀXγ from the run's sums (no pass over its rows).
        let mut g = fit.beta(self.j1_kgm2);
        g[0] = 0.0;
        self.runs
            .iter()
            .filter(|r| include(&r.id) && !r.rows.is_empty())
            .map(|r| {
                let quad: f64 = (0..5).map(|i| g[i] * (0..5).map(|j| r.ata[5 * i + j] * g[j]).sum::<f64>()).sum();
                let lin: f64 = (0..5).map(|i| g[i] * r.atb[i]).sum();
                let ssr = (r.yty - 2.0 * lin + quad).max(0.0);
                (r.id.clone(), (ssr / r.rows.len() as f64).sqrt())
            })
            .collect()
    }

    /// Each run's event-locked misfit of `fit`, N·m, over the runs `include`
    /// accepts that have one: the residual averaged over the run's
    /// transitions of one kind (slip→stick, stick→slip) at one row of the
    /// event-locked window ([`EVENT_ROWS`]), an event-triggered average, and
    /// the RMS of those averages over the (kind, row) cells with at least
    /// [`MIN_EVENTS`] transitions. Averaging over a run's transitions keeps
    /// what every transition shares (a late or ringing sensor) and divides
    /// the sensor noise by √(transitions): the structural candidates'
    /// event-locked statistic ([`crate::structure`]).
    pub fn run_event_rms(&self, fit: &BalanceFit, include: impl Fn(&str) -> bool) -> Vec<(String, f64)> {
        let beta = fit.beta(self.j1_kgm2);
        let mut out = Vec::new();
        for r in self.runs.iter().filter(|r| include(&r.id)) {
            let mut cells = Vec::new();
            for kind in 0..2 {
                let of_kind: Vec<Vec<f64>> =
                    r.events.iter().filter(|e| e.0 == kind).map(|e| residuals(&e.1, &beta)).collect();
                if of_kind.len() < MIN_EVENTS {
                    continue;
                }
                for j in 0..EVENT_ROWS {
                    cells.push(of_kind.iter().map(|e| e[j]).sum::<f64>() / of_kind.len() as f64);
                }
            }
            if !cells.is_empty() {
                out.push((r.id.clone(), rms(&cells)));
            }
        }
        out
    }
}

/// The residuals r·F − (−J1 Ω̇1 + K tw + C tẇ − C_r Ω1 + c0) of `rows`, N·m.
fn residuals(rows: &[Row], beta: &[f64; 5]) -> Vec<f64> {
    rows.iter().map(|(x, y)| y - x.iter().zip(beta).map(|(a, b)| a * b).sum::<f64>()).collect()
}

/// Rotor-1 torque balance over the steady state of every operating point.
///
/// Eq. 4-7, first row, in the rig model's reading (rig-model docs: the
/// damping C acts on the twist rate): J1 Ω̇1 = K(φ2 − φ1) + C(Ω2 − Ω1) − T1,
/// with T1 = r·F measured by the force sensor (Eq. 4-10's r). It departs from
/// the thesis by adding an absolute drag d·Ω1 and a constant (force-sensor
/// offset drift), and by fitting K, C, d and the constant to the records
/// themselves (one least squares over all runs): a bearing drag or a slightly
/// wrong calibration is then no finding, and what is left is what no linear
/// rotor equation explains (a torque that follows angle, time or stick/slip).
/// Terms are triangle-weighted window means (window `balance_window_s`).
/// Statistic: per run the RMS residual, over runs their RMS, N·m. Floor: the
/// same expression under sensor noise alone: force noise (measured per run by
/// first differences) and one-tick quantisation of both encoders propagated
/// through the fitted coefficients.
pub fn torque_balance_check(
    c: &Campaign,
    cal: &CampaignCalibration,
    baseline: &RigParams,
    opts: &DiagnoseOptions,
    o: &ChannelOptions,
) -> ChannelCheck {
    torque_balance_check_of(c, &balance_data(c, cal, opts, o), baseline, o)
}

/// [`torque_balance_check`] of balance data already built.
pub fn torque_balance_check_of(
    c: &Campaign,
    data: &BalanceData,
    baseline: &RigParams,
    o: &ChannelOptions,
) -> ChannelCheck {
    let name = "operating_point.torque_balance";
    let w = nominal_window_samples(o.balance_window_s, c.rig.sample_rate_hz).max(2);
    let dt = 1.0 / c.rig.sample_rate_hz;
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    let r_m = c.rig.brake_disc_radius_m;
    let per_run = &data.runs;
    let ids: Vec<String> = per_run.iter().map(|r| r.id.clone()).collect();
    // J1 is the calibration's (Eqs. 4-4/4-5): fitted here it would be
    // attenuated towards 0 by the quantisation noise of Ω̇1 (errors in variables).
    let j1 = data.j1_kgm2;
    let Some(fit) = data.fit(|_| true, true, true) else {
        return ChannelCheck::not_testable(name, ids, "the rotor balance regression is singular".into());
    };
    let beta = fit.beta(j1);
    // r·F = −J1 Ω̇1 + K tw + C tẇ − d Ω1 + c0.
    let (k, cc, drag) = (beta[1], beta[2], -beta[3]);
    let run_rms: Vec<f64> = per_run
        .iter()
        .filter(|r| !r.rows.is_empty())
        .map(|r| {
            let e: Vec<f64> =
                r.rows.iter().map(|(x, y)| y - x.iter().zip(&beta).map(|(a, b)| a * b).sum::<f64>()).collect();
            rms(&e)
        })
        .collect();
    let big_t = w as f64 * dt;
    // Quantisation: uniform error tick²/12 per angle sample. Ω̇1 = second
    // difference of three boundary angles / T² (variance 6·tick²/12 / T⁴);
    // the twist (two encoders) under the kernel; the rates, difference of
    // two-boundary twists / 2T (variance 2·2·tick²/12 / 4T²).
    let q2 = rad * rad / 12.0;
    let floors: Vec<f64> = per_run
        .iter()
        .filter(|r| !r.rows.is_empty())
        .map(|r| {
            let var = (r_m * r.force_noise_n).powi(2) * r.kernel_gain
                + j1.powi(2) * 6.0 * q2 / big_t.powi(4)
                + k.powi(2) * 2.0 * q2 * r.kernel_gain
                + cc.powi(2) * q2 / big_t.powi(2)
                + drag.powi(2) * 0.5 * q2 / big_t.powi(2);
            var.sqrt()
        })
        .collect();
    let stat = rms(&run_rms);
    let floor = rms(&floors);
    let worst = ids
        .iter()
        .zip(&run_rms)
        .zip(&floors)
        .max_by(|a, b| (a.0.1 / a.1).total_cmp(&(b.0.1 / b.1)))
        .map(|((id, e), f)| format!("{id} {:.1}×", e / f))
        .unwrap_or_default();
    ChannelCheck::new(
        name,
        ids,
        stat,
        floor,
        o.torque_balance_ratio,
        format!(
            "rotor balance fitted on the records (J1 held): J1 {j1:.4} kg·m² (calibration; baseline {:.4}), K {k:.4} N·m/rad ({:.4}), C {cc:.2e} N·m·s/rad ({:.2e}), drag d {drag:.2e} N·m·s/rad, offset {:.2e} N·m; RMS residual {stat:.2e} N·m; worst run {worst}",
            baseline.rotor_inertia_kgm2, baseline.shaft_stiffness_nm_rad, baseline.shaft_damping_nm_s_rad, beta[4]
        ),
    )
}

/// The tick-loss check's name (run kind `operating_point`).
pub const TICK_LOSS_CHECK: &str = "operating_point.tick_loss";

/// The floor of the tick-loss fraction: a drift of the twist below 2·10⁻⁴
/// rad per rad travelled (0.2 ticks in 1000 of a 1000-tick encoder) is
/// within what the balance's slow wander gives (stated in
/// [`tick_loss_check_of`]'s calibration).
pub const MIN_TICK_LOSS: f64 = 2e-4;

/// A run's drift needs this many balance rows (10 s at 0.1 s).
const MIN_DRIFT_ROWS: usize = 100;

/// Does an encoder lose ticks? A lost tick is a step of one tick in the
/// recorded angle that is never given back, so the recorded twist φ2 − φ1
/// grows with the angle travelled: by p·φ1 when the rotor encoder loses a
/// fraction p of its ticks (by −p·φ2 for the motor's). A transport delay of
/// the encoder is a *shift*, φ1(t − d) ≈ φ1 − Ω1·d: bounded, the same at the
/// start and the end of a steady slip, zero in every stick. The balance
/// fitted on the records ([`BalanceData::fit`], C and C_r free) leaves both
/// faults in its residual: a delay as K·Ω1·d, constant within a steady run
/// (it is what the `channel_delay` candidate fits), a tick loss as
/// −K·p·(φ1 − φ̄1), a ramp on the travelled angle.
///
/// Statistic: per run with at least [`MIN_DRIFT_ROWS`] steady rows, the
/// least-squares slope of the balance residual on the recorded rotor angle,
/// divided by −K: p_r, the twist gained per radian travelled
/// (dimensionless; ticks lost per tick). Over runs, the mean p̄ (a tick loss
/// is the same fraction in every run; a model error that drifts does not
/// keep its sign across 30 runs of different set-points). Floor: p̄'s
/// standard error over runs ⊕ [`MIN_TICK_LOSS`]. Flagged above
/// `tick_loss_ratio` (pipeline.toml); when flagged the `channel_delay`
/// candidate refuses the rotor encoder ([`crate::structure`]).
pub fn tick_loss_check_of(data: &BalanceData, o: &ChannelOptions) -> ChannelCheck {
    let ids: Vec<String> = data.runs.iter().map(|r| r.id.clone()).collect();
    let Some(fit) = data.fit(|_| true, true, true) else {
        return ChannelCheck::not_testable(TICK_LOSS_CHECK, ids, "the rotor balance regression is singular".into());
    };
    let beta = fit.beta(data.j1_kgm2);
    let k = fit.stiffness_nm_rad;
    let mut p = Vec::new();
    for r in data.runs.iter().filter(|r| r.rows.len() >= MIN_DRIFT_ROWS) {
        let e = residuals(&r.rows, &beta);
        let n = e.len() as f64;
        let (ma, me) = (r.angle_rad.iter().sum::<f64>() / n, e.iter().sum::<f64>() / n);
        let sxx: f64 = r.angle_rad.iter().map(|a| (a - ma).powi(2)).sum();
        let sxy: f64 = r.angle_rad.iter().zip(&e).map(|(a, y)| (a - ma) * (y - me)).sum();
        if sxx > 0.0 && k > 0.0 {
            p.push((r.id.as_str(), -sxy / sxx / k));
        }
    }
    if p.len() < 3 || k <= 0.0 {
        return ChannelCheck::not_testable(
            TICK_LOSS_CHECK,
            ids,
            format!("{} runs with {MIN_DRIFT_ROWS} steady balance rows (3 needed)", p.len()),
        );
    }
    let n = p.len() as f64;
    let mean = p.iter().map(|x| x.1).sum::<f64>() / n;
    let sd = (p.iter().map(|x| (x.1 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let se = sd / n.sqrt();
    let same_sign = p.iter().filter(|x| x.1 * mean > 0.0).count();
    ChannelCheck::new(
        TICK_LOSS_CHECK,
        p.iter().map(|x| x.0.to_string()).collect(),
        mean.abs(),
        se.hypot(MIN_TICK_LOSS),
        o.tick_loss_ratio,
        format!(
            "the recorded twist drifts by {:.2e} rad per rad the rotor travels (mean over {} runs ± {:.1e}, {} of \
             them of that sign; {}): {}",
            mean,
            p.len(),
            se,
            same_sign,
            if mean > 0.0 { "the rotor encoder falls behind" } else { "the motor encoder falls behind" },
            "a lost tick is a step in the angle never given back; a delay is a shift"
        ),
    )
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
        Recorded { runs, w, dt: 1.0 / rate_hz, r_m, kernel_gain: 1.0, j1_kgm2 }
    }
}

#[cfg(test)]
mod tests {
    use super::{Recorded, RecordedRun, Row, row_at, rows_lanes};
    use std::borrow::Cow;

    fn rows(phi1: &[f64], phi2: &[f64], f: &[f64], dt: f64, w: usize, r_m: f64, from: usize) -> Vec<Row> {
        let [out] = rows_lanes([(phi1, phi2, f)], dt, w, r_m, from);
        out
    }

    /// Lanes built together are each lane built alone, bit for bit (the
    /// sensor grid's balances are read as the single balance's).
    #[test]
    fn lanes_are_each_balance_alone() {
        let (n, dt, w, r_m) = (2500, 0.002, 40, 0.09);
        let t = |k: usize| k as f64 * dt;
        let phi1: Vec<f64> = (0..n).map(|k| 3.0 * t(k) + 0.02 * (40.0 * t(k)).sin()).collect();
        let phi2: Vec<Vec<f64>> =
            (0..3).map(|j| (0..n).map(|k| 3.0 * t(k) + 0.5 + 0.01 * j as f64 * (7.0 * t(k)).cos()).collect()).collect();
        let f: Vec<Vec<f64>> =
            (0..3).map(|j| (0..n).map(|k| 10.0 + ((k * 7919 + j * 31) % 101) as f64 * 0.01).collect()).collect();
        for from in [0, 37] {
            let lanes =
                rows_lanes(std::array::from_fn::<_, 3, _>(|j| (&phi1[..], &phi2[j][..], &f[j][..])), dt, w, r_m, from);
            for (j, lane) in lanes.iter().enumerate() {
                let alone = rows(&phi1, &phi2[j], &f[j], dt, w, r_m, from);
                assert!(!alone.is_empty());
                let bits = |r: &[Row]| {
                    r.iter()
                        .flat_map(|(x, y)| x.iter().chain([y]).map(|v| v.to_bits()).collect::<Vec<_>>())
                        .collect::<Vec<_>>()
                };
                assert_eq!(bits(lane), bits(&alone), "lane {j}, from {from}");
            }
        }
        // Lanes on the same angles (a force sensor's points) share the
        // twist's sums: still each lane alone, to the bit.
        let shared =
            rows_lanes(std::array::from_fn::<_, 3, _>(|j| (&phi1[..], &phi2[0][..], &f[j][..])), dt, w, r_m, 37);
        for (j, lane) in shared.iter().enumerate() {
            let alone = rows(&phi1, &phi2[0], &f[j], dt, w, r_m, 37);
            let bits =
                |r: &[Row]| r.iter().flat_map(|(x, y)| x.iter().chain([y]).map(|v| v.to_bits())).collect::<Vec<_>>();
            assert!(!alone.is_empty());
            assert_eq!(bits(lane), bits(&alone), "shared angles, lane {j}");
        }
        assert!(shared[0] != shared[1], "the lanes' forces differ");
        // Unequal lengths: each lane alone.
        let short = &f[1][..n - 300];
        let [a, b] =
            rows_lanes([(&phi1[..], &phi2[0][..], &f[0][..]), (&phi1[..], &phi2[1][..], short)], dt, w, r_m, 0);
        assert_eq!(a.len(), rows(&phi1, &phi2[0], &f[0], dt, w, r_m, 0).len());
        assert_eq!(b, rows(&phi1, &phi2[1], short, dt, w, r_m, 0));
        assert!(b.len() < a.len());
    }

    /// The running box sums give [`row_at`]'s rows (its explicit triangle
    /// weights, the independent reference) on a record with every term
    /// moving: ramps, a ring and a noisy force.
    #[test]
    fn rows_are_the_triangle_rows() {
        let (n, dt, w, r_m) = (3000, 0.002, 50, 0.09);
        let t = |k: usize| k as f64 * dt;
        let phi1: Vec<f64> = (0..n).map(|k| 3.0 * t(k) + 0.02 * (40.0 * t(k)).sin()).collect();
        let phi2: Vec<f64> = (0..n).map(|k| 3.0 * t(k) + 0.5 + 0.01 * (7.0 * t(k)).cos()).collect();
        let f: Vec<f64> = (0..n).map(|k| 10.0 + ((k * 7919) % 101) as f64 * 0.01).collect();
        for from in [0, 37, 120] {
            let fast = rows(&phi1, &phi2, &f, dt, w, r_m, from);
            let slow: Vec<_> =
                (from.max(w)..n).step_by(w).map_while(|b| row_at(&phi1, &phi2, &f, dt, w, r_m, b)).collect();
            assert_eq!(fast.len(), slow.len());
            for ((x, y), (xs, ys)) in fast.iter().zip(&slow) {
                assert!((y - ys).abs() < 1e-12 * ys.abs().max(1.0), "{y} vs {ys}");
                for (a, b) in x.iter().zip(xs) {
                    assert!((a - b).abs() < 1e-9 * b.abs().max(1.0), "{a} vs {b}");
                }
            }
        }
    }

    /// A balance of F + a1·G1 + a2·G2 combined from the three balances
    /// ([`super::BalanceData::force_combination`]) is the balance of that
    /// force built sample by sample (the independent reference), rows,
    /// event-locked rows, normal equations and fits, to rounding: on two
    /// runs with transitions, a noisy force and coefficients of the force
    /// sensor's grid (a2 up to rate²/ω² ≈ 1.6·10³ at 2 Hz).
    #[test]
    fn a_force_combination_is_the_combined_force_balance() {
        let (n, dt, w, r_m) = (4000, 0.002, 50, 0.09);
        let t = |k: usize| k as f64 * dt;
        let run = |j: usize| {
            let rotor_rad: Vec<f64> = (0..n).map(|k| 2.0 * t(k) + 0.05 * (9.0 * t(k) + j as f64).sin()).collect();
            let motor_rad: Vec<f64> = (0..n).map(|k| 2.0 * t(k) + 0.4 + 0.01 * (3.0 * t(k)).cos()).collect();
            let force_n: Vec<f64> =
                (0..n).map(|k| 30.0 + (6.0 * t(k)).sin() + ((k * 7919 + j) % 101) as f64 * 0.003).collect();
            RecordedRun {
                id: format!("op-{j}"),
                rotor_rad,
                motor_rad,
                force_n,
                from: 120,
                transitions: vec![(1, 400), (0, 900), (1, 1500), (0, 2100), (1, 3920)],
                force_noise_n: 0.01,
            }
        };
        let rec = Recorded { runs: vec![run(0), run(1)], w, dt, r_m, kernel_gain: 0.5, j1_kgm2: 0.02 };
        let diff = |f: &[f64], second: bool| -> Vec<f64> {
            (0..f.len())
                .map(|k| match (k.checked_sub(1), f.get(k + 1)) {
                    (Some(j), Some(&next)) if second => next - 2.0 * f[k] + f[j],
                    (Some(j), Some(&next)) => next - f[j],
                    _ => 0.0,
                })
                .collect()
        };
        let [f0, g1, g2] = rec.balance_lanes(|_, r| {
            [
                Cow::Borrowed(r.force_n.as_slice()),
                Cow::Owned(diff(&r.force_n, false)),
                Cow::Owned(diff(&r.force_n, true)),
            ]
            .map(|f| (Cow::Borrowed(r.rotor_rad.as_slice()), Cow::Borrowed(r.motor_rad.as_slice()), f))
        });
        for (a1, a2) in [(0.0, 0.0), (0.8, 1583.0), (0.05, 6.3)] {
            let combined = f0.force_combination(&[(a1, &g1), (a2, &g2)]);
            let direct = rec.balance_with(|_, r| {
                let (d1, d2) = (diff(&r.force_n, false), diff(&r.force_n, true));
                let f: Vec<f64> = (0..n).map(|k| r.force_n[k] + a1 * d1[k] + a2 * d2[k]).collect();
                (r.rotor_rad.as_slice().into(), r.motor_rad.as_slice().into(), f.into())
            });
            let close = |a: f64, b: f64, scale: f64| (a - b).abs() <= 1e-12 * scale.max(1.0);
            for (c, d) in combined.runs.iter().zip(&direct.runs) {
                assert_eq!((c.rows.len(), c.events.len()), (d.rows.len(), d.events.len()));
                assert!(c.rows.len() > 50 && c.events.len() == 4, "{} rows, {} events", c.rows.len(), c.events.len());
                let scale = d.rows.iter().fold(0.0f64, |m, (_, y)| m.max(y.abs()));
                for ((xc, yc), (xd, yd)) in c
                    .rows
                    .iter()
                    .chain(c.events.iter().flat_map(|e| &e.1))
                    .zip(d.rows.iter().chain(d.events.iter().flat_map(|e| &e.1)))
                {
                    assert_eq!(xc, xd, "the regressors are the angles'");
                    assert!(close(*yc, *yd, scale), "a1 {a1}, a2 {a2}: {yc} vs {yd}");
                }
                assert_eq!(c.ata, d.ata);
                assert!(
                    c.atb.iter().zip(&d.atb).all(|(u, v)| close(*u, *v, v.abs() * 1e3)),
                    "{:?} vs {:?}",
                    c.atb,
                    d.atb
                );
                assert!(close(c.yty, d.yty, d.yty), "{} vs {}", c.yty, d.yty);
            }
            let (fc, fd) = (combined.fit(|_| true, true, false).unwrap(), direct.fit(|_| true, true, false).unwrap());
            assert!(
                close(fc.stiffness_nm_rad, fd.stiffness_nm_rad, 1e3 * fd.stiffness_nm_rad.abs()),
                "{fc:?} vs {fd:?}"
            );
            let (rc, rd) = (combined.run_rms(&fc, |_| true), direct.run_rms(&fd, |_| true));
            assert!(rc.iter().zip(&rd).all(|(u, v)| (u.1 - v.1).abs() <= 1e-9 * v.1), "{rc:?} vs {rd:?}");
        }
        // The differences move the balance: a sensor point is not the record.
        let moved = f0.force_combination(&[(0.8, &g1), (1583.0, &g2)]);
        assert!(moved.runs[0].rows.iter().zip(&f0.runs[0].rows).any(|(a, b)| (a.1 - b.1).abs() > 1e-6));
    }
}
