//! Torque balance of rotor 1 in the measured channels of the operating
//! points: encoders and force sensor must satisfy the rotor equation.
//!
//! `rows.rs` the window rows and their running box sums, `recorded.rs` the
//! operating points' channels read once and the balances built from them,
//! `checks.rs` the torque-balance and tick-loss checks; here the balance's
//! data and its fits.

use super::rms;
use rig_calibrate::CampaignCalibration;
use rig_types::Campaign;

mod checks;
mod recorded;
mod rows;
#[cfg(test)]
mod tests;

use super::ChannelOptions;
use crate::DiagnoseOptions;
pub use checks::{TICK_LOSS_CHECK, tick_loss_check_of, torque_balance_check, torque_balance_check_of};
pub use recorded::{Channels, Recorded, RecordedRun};

/// Regressors of one window boundary: [⟨Ω̇1⟩, ⟨φ2−φ1⟩, ⟨Ω2−Ω1⟩, ⟨Ω1⟩, 1] and r⟨F⟩.
type Row = ([f64; 5], f64);

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
    /// The balance window's duration T, s: its w samples times the step
    /// the time columns measure (the rows' derivatives divide by it).
    window_s: f64,
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
        BalanceData { runs, j1_kgm2: self.j1_kgm2, window_s: self.window_s }
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
