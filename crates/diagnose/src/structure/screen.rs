//! The structural grids' screened search: a grid point's rotor balance is
//! built one run at a time, and only as far as a lower bound of its training
//! cost needs to show that it cannot beat the best point found so far. The
//! point chosen is the full grid's by construction.
//!
//! # Why the minimum is the full grid's
//!
//! A grid point's training cost on the runs S a fit trains on
//! ([`super::channel_delay::training_cost`]) is Σ_{r∈S} RMS_r² + Σ_{r∈S}
//! E_r², with RMS_r the run's RMS residual of the steady rows under the
//! balance fitted on S and E_r its event-locked misfit. Every term is ≥ 0,
//! and Σ_{r∈B} RMS_r² over any B ⊆ S is at least the minimum of that sum
//! over every balance fit (K, C, C_r and the offset free, J1 held): a
//! weighted least squares on B's sums alone
//! ([`crate::channels::rms2_floor`]). So when that floor, over the runs of S
//! built so far, exceeds the best cost found, the point's full cost does too,
//! and the point can neither win nor tie; it is left unbuilt. A point that
//! is not screened out is built on every run of S and its cost computed
//! exactly as the full grid computes it (the same sums of the same runs in
//! the same order, so to the bit), and the best is the smallest cost, ties
//! to the records as recorded, then to the lower grid index: the full
//! grid's scan. The floor and the cost are computed in floating point from
//! the same sums; a point is screened out only when the floor exceeds the
//! best cost by [`MARGIN`] of the sums' scale (both sides' rounding is
//! ≈ 10⁻¹⁵ of it).
//!
//! # Cost
//!
//! A run's rows, once built, serve every fold and both calls of a
//! selection; the points whose runs are all built are scored first, so the
//! best cost is low before any new run is built. Measured in
//! docs/performance.md (issue 23).

use crate::channels::{BalanceData, BalanceFit, Recorded, RunRows, rms2_floor};
use std::sync::{Arc, OnceLock};

/// The screen's margin, relative to Σ_r yᵀy/n_r of the two costs compared
/// (module docs).
pub const MARGIN: f64 = 1e-9;

/// A training cost of a balance on the runs `include` accepts, with the fit
/// it was made with (`channel_delay::training_cost`'s signature).
pub type Cost = dyn Fn(&BalanceData, &dyn Fn(&str) -> bool) -> Option<(f64, BalanceFit)>;

/// Builds run `run` of grid point `point` from the records.
type BuildRun = dyn Fn(&Recorded, usize, usize) -> RunRows + Send + Sync;

/// A grid of balances, each point's runs built on demand and kept.
pub struct LazyGrid {
    rec: Recorded,
    /// Per point, per run (the records' order).
    runs: Vec<Vec<OnceLock<Arc<RunRows>>>>,
    /// Per point, the balance of every run (what a held-out score reads).
    full: Vec<OnceLock<BalanceData>>,
    build: Box<BuildRun>,
}

impl std::fmt::Debug for LazyGrid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (built, total) = self.built();
        write!(f, "LazyGrid {{ points: {}, runs built: {built} of {total} }}", self.full.len())
    }
}

/// The best of a screened search: the grid point (`None`: the records as
/// recorded) and the fit of its training cost.
pub type Best = (Option<usize>, BalanceFit);

impl LazyGrid {
    /// `points` grid points over the runs of `rec`; `build(rec, point, run)`
    /// makes a run's rows ([`Recorded::run_rows`]).
    pub fn new(
        rec: &Recorded,
        points: usize,
        build: impl Fn(&Recorded, usize, usize) -> RunRows + Send + Sync + 'static,
    ) -> Self {
        let n = rec.runs.len();
        LazyGrid {
            rec: rec.clone(),
            runs: (0..points).map(|_| (0..n).map(|_| OnceLock::new()).collect()).collect(),
            full: (0..points).map(|_| OnceLock::new()).collect(),
            build: Box::new(build),
        }
    }

    fn run(&self, p: usize, r: usize) -> &Arc<RunRows> {
        self.runs[p][r].get_or_init(|| Arc::new((self.build)(&self.rec, p, r)))
    }

    /// Point `p`'s balance on every run, built where it is not yet.
    pub fn data(&self, p: usize) -> &BalanceData {
        self.full[p].get_or_init(|| self.rec.gather((0..self.rec.runs.len()).map(|r| self.run(p, r).clone()).collect()))
    }

    /// Runs built so far over every point, and how many the grid has.
    pub fn built(&self) -> (usize, usize) {
        let built = self.runs.iter().flatten().filter(|r| r.get().is_some()).count();
        (built, self.runs.iter().map(Vec::len).sum())
    }

    /// The point of `points` with the smallest `cost` on the runs `include`
    /// accepts, if it is below the cost of `recorded` (the records as
    /// recorded); `None` when `recorded`'s cost is. Screened (module docs):
    /// the full grid's answer, bit for bit.
    pub fn best(
        &self,
        points: impl IntoIterator<Item = usize>,
        include: &dyn Fn(&str) -> bool,
        recorded: &BalanceData,
        cost: &Cost,
    ) -> Option<Best> {
        let (base_cost, base_fit) = cost(recorded, include)?;
        let train: Vec<usize> = (0..self.rec.runs.len()).filter(|&r| include(&self.rec.runs[r].id)).collect();
        let ready = |p: usize| train.iter().all(|&r| self.runs[p][r].get().is_some());
        let points: Vec<usize> = points.into_iter().collect();
        // Points already built on every training run first (exact from their sums).
        let order: Vec<usize> =
            points.iter().copied().filter(|&p| ready(p)).chain(points.iter().copied().filter(|&p| !ready(p))).collect();
        // (point, cost, its sums' scale, fit)
        let mut best = (None, base_cost, recorded.rms2_floor(include).1, base_fit);
        'points: for p in order {
            loop {
                let (floor, scale) = rms2_floor(train.iter().filter_map(|&r| self.runs[p][r].get()).map(|x| &**x));
                if floor - MARGIN * (scale + best.2) > best.1 {
                    continue 'points;
                }
                match train.iter().find(|&&r| self.runs[p][r].get().is_none()) {
                    Some(&r) => {
                        self.run(p, r);
                    }
                    None => break,
                }
            }
            let data = self.rec.gather(train.iter().map(|&r| self.run(p, r).clone()).collect());
            let Some((c, fit)) = cost(&data, include) else { continue };
            if c < best.1 || (c == best.1 && best.0.is_some_and(|q| p < q)) {
                best = (Some(p), c, data.rms2_floor(include).1, fit);
            }
        }
        Some((best.0, best.3))
    }
}

#[cfg(test)]
mod tests {
    use super::super::channel_delay::training_cost;
    use super::super::sensor_dynamics::{self, Sensor};
    use crate::channels::{Recorded, rms2_floor};

    /// The full grid's scan (the code before the screen): every point built
    /// on every run, the first strictly smaller cost, ties to the records.
    fn full_scan(
        points: &[sensor_dynamics::SensorPoint],
        grid: &super::LazyGrid,
        sensor: Sensor,
        include: &dyn Fn(&str) -> bool,
        recorded: &crate::channels::BalanceData,
    ) -> Option<(Option<usize>, f64)> {
        let (mut best_cost, _) = training_cost(recorded, include)?;
        let mut best = None;
        for (i, _) in points.iter().enumerate().filter(|(_, p)| p.sensor == sensor) {
            if let Some((c, _)) = training_cost(grid.data(i), include)
                && c < best_cost
            {
                (best_cost, best) = (c, Some(i));
            }
        }
        Some((best, best_cost))
    }

    /// A planted force sensor (7 Hz, ζ 0.2, a grid point) on records that
    /// satisfy the rotor balance: the screened search finds the full grid's
    /// point — the planted one — for every run and every fold, builds fewer
    /// runs than the grid has, and its floor is below the cost on every
    /// subset it bounds.
    #[test]
    fn the_screen_finds_the_full_grids_optimum_on_a_planted_sensor() {
        let (rate, n, runs) = (500.0, 8000, 10);
        let (j1, k, c, r_m) = (0.02, 0.27, 2e-3, 0.09);
        let dt = 1.0 / rate;
        let mut records = Vec::new();
        for i in 0..runs {
            let (w0, a, f) = (2.0 + i as f64, 0.3 + 0.05 * i as f64, 0.8 + 0.1 * i as f64);
            // The rotor's wobble: the run's fundamental and three faster lines
            // (what tells one resonance from another with the same lag).
            let lines: Vec<(f64, f64, f64)> = [(f, 1.0), (3.3, 0.5), (6.1, 0.3), (11.7, 0.2)]
                .iter()
                .enumerate()
                .map(|(q, &(hz, rel))| (2.0 * std::f64::consts::PI * hz, a * rel * f / hz, 0.7 * (q + i) as f64))
                .collect();
            let wf = lines[0].0;
            let t = |j: usize| j as f64 * dt;
            // Rotor angle and twist, smooth, with a tick-sized wobble as noise.
            let noise = |j: usize| 1e-4 * (((j * 7919 + i * 104_729) % 997) as f64 / 997.0 - 0.5);
            let wobble = |j: usize| lines.iter().map(|&(w, b, p)| b * (w * t(j) + p).sin()).sum::<f64>();
            let phi1: Vec<f64> = (0..n).map(|j| w0 * t(j) + wobble(j) + noise(j)).collect();
            let tw = |j: usize| 0.5 + 0.2 * (wf * t(j)).cos();
            let phi2: Vec<f64> = (0..n).map(|j| phi1[j] + tw(j)).collect();
            // r·F = −J1 Ω̇1 + K tw + C tẇ (Eq. 4-7's first row), then through the sensor.
            let torque: Vec<f64> = (0..n)
                .map(|j| {
                    let acc: f64 = lines.iter().map(|&(w, b, p)| -b * w * w * (w * t(j) + p).sin()).sum();
                    let twd = -0.2 * wf * (wf * t(j)).sin();
                    (-j1 * acc + k * tw(j) + c * twd) / r_m
                })
                .collect();
            let force = sensor_dynamics::through_force_sensor(&torque, rate, 7.0, 0.2);
            let transitions = (1..n / 1000).map(|e| (e % 2, e * 1000)).collect();
            records.push((format!("op{i:02}"), phi1, phi2, force, transitions));
        }
        let rec = Recorded::synthetic(records, rate, 0.1, r_m, j1);
        let (points, grid) = sensor_dynamics::grid(&rec, rate);
        let recorded = rec.balance();
        let planted = points
            .iter()
            .position(|p| p.sensor == Sensor::Force && p.natural_frequency_hz == 7.0 && p.damping_ratio == 0.2);
        let ids: Vec<String> = rec.runs.iter().map(|r| r.id.clone()).collect();
        let sets: Vec<Box<dyn Fn(&str) -> bool>> =
            std::iter::once(Box::new(|_: &str| true) as Box<dyn Fn(&str) -> bool>)
                .chain((0..5).map(|f| {
                    let ids = ids.clone();
                    Box::new(move |id: &str| ids.iter().position(|x| x == id).is_some_and(|i| i % 5 != f))
                        as Box<dyn Fn(&str) -> bool>
                }))
                .collect();
        for sensor in [Sensor::Force, Sensor::EncoderCoupling] {
            // A grid of its own, nothing built yet.
            let screened = sensor_dynamics::grid(&rec, rate).1;
            for include in &sets {
                let idx: Vec<usize> = (0..points.len()).filter(|&i| points[i].sensor == sensor).collect();
                let got = screened.best(idx, include.as_ref(), &recorded, &training_cost).map(|b| b.0);
                let want = full_scan(&points, &grid, sensor, include.as_ref(), &recorded).map(|b| b.0);
                assert_eq!(got, want, "{sensor:?}");
                if sensor == Sensor::Force {
                    assert_eq!(got, Some(planted), "the planted sensor");
                }
            }
            let (built, total) = screened.built();
            assert!(built < total, "{sensor:?}: the screen built {built} of {total} runs");
        }
        // The floor bounds the cost of every point on every prefix of its runs.
        for p in 0..points.len() {
            let (c, _) = training_cost(grid.data(p), &|_| true).expect("a cost");
            for m in 1..=runs {
                let sub: Vec<_> = (0..m).map(|r| grid.runs[p][r].get().expect("built").clone()).collect();
                let (floor, _) = rms2_floor(sub.iter().map(|x| &**x));
                assert!(floor <= c, "point {p}, {m} runs: floor {floor} above the cost {c}");
            }
        }
    }
}
