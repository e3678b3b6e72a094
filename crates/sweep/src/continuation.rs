//! Continuation sweeps: chains of operating points where each point starts
//! from the previous point's end state (rig_model::simulate_from), run up and
//! down so that a bistable band shows as hysteresis; severity maps as one
//! chain per (friction row, direction), sharded by chain index and merged.
//!
//! Windows (see [`WindowSpec`]): after every parameter change the first
//! `transient_s` are discarded and the next `window_s` are classified. The
//! torsional period is ≈ 2 s (0.45 Hz, Table 4.2's decays) and ξ is a few
//! per cent, so a free transient decays by e^{-2πξ} per period: 10 s (5
//! periods) after a *small* step between neighbouring grid points is enough
//! for the attractor to be reached or left; the stick-slip period is the
//! torsional period plus the stick time (a twist of 2(μs − μk)N r/K built at
//! the motor speed), between ≈ 2 s and ≈ 6 s on the maps' range, so a 20 s
//! window holds 3 to 10 cycles — the classifier asks for three per period.
//! The first point of a chain starts from rest with a set-point step and gets
//! `first_transient_s` instead.

use crate::SweepError;
use crate::classify::{Classification, ClassifyOptions, classify};
use rayon::prelude::*;
use rig_model::{SimOptions, State, simulate_from};
use rig_types::RigParams;
use serde::{Deserialize, Serialize};

/// Transient and window lengths of every point, and the classifier's sample rate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WindowSpec {
    pub first_transient_s: f64,
    pub transient_s: f64,
    pub window_s: f64,
    pub sample_rate_hz: f64,
}

impl Default for WindowSpec {
    fn default() -> Self {
        WindowSpec { first_transient_s: 20.0, transient_s: 10.0, window_s: 20.0, sample_rate_hz: 100.0 }
    }
}

/// Everything a sweep needs besides the chains.
#[derive(Debug, Clone)]
pub struct SweepSettings {
    pub window: WindowSpec,
    pub sim: SimOptions,
    pub classify: ClassifyOptions,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    Up,
    Down,
}

impl Direction {
    pub fn as_str(self) -> &'static str {
        match self {
            Direction::Up => "up",
            Direction::Down => "down",
        }
    }
}

/// One operating point: motor set-point and normal force N0 (the chapter's Frict).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Point {
    pub motor_rpm: f64,
    pub normal_force_n: f64,
}

/// A continuation chain: points run in order, each from the last one's end state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chain {
    /// Position in the sweep (fixes the output order).
    pub index: usize,
    pub direction: Direction,
    pub points: Vec<Point>,
}

/// A point's result; a model failure is data (`Err` with the reason), and
/// the chain restarts from rest at the next point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointOutcome {
    pub point: Point,
    pub result: Result<Classification, String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainResult {
    pub index: usize,
    pub direction: Direction,
    pub points: Vec<PointOutcome>,
}

/// Runs one chain (sequential by nature).
pub fn run_chain(params: &RigParams, chain: &Chain, s: &SweepSettings, progress: &(dyn Fn() + Sync)) -> ChainResult {
    let dt = 1.0 / s.window.sample_rate_hz;
    let n_window = (s.window.window_s * s.window.sample_rate_hz).round().max(4.0) as usize;
    let mut state: Option<State> = None;
    let mut points = Vec::with_capacity(chain.points.len());
    for p in &chain.points {
        let start = state.clone().unwrap_or_default();
        let transient = if state.is_some() { s.window.transient_s } else { s.window.first_transient_s };
        let t0 = start.time_s + transient;
        let times: Vec<f64> = (0..n_window).map(|k| t0 + k as f64 * dt).collect();
        let result = match simulate_from(params, &start, p.motor_rpm, p.normal_force_n, &times, &s.sim) {
            Ok((traj, end)) => {
                state = Some(end);
                Ok(classify(&traj.rotor_speed_rad_s, s.window.sample_rate_hz, &s.classify))
            }
            Err(e) => {
                state = None;
                Err(e.to_string())
            }
        };
        points.push(PointOutcome { point: *p, result });
        progress();
    }
    ChainResult { index: chain.index, direction: chain.direction, points }
}

/// Runs chains in parallel on the current rayon pool; the result is in chain
/// order whatever the thread count.
pub fn run_chains(
    params: &RigParams,
    chains: &[Chain],
    s: &SweepSettings,
    progress: &(dyn Fn() + Sync),
) -> Vec<ChainResult> {
    chains.par_iter().map(|c| run_chain(params, c, s, progress)).collect()
}

/// A bifurcation diagram's two chains: `values` swept up, then down, with the
/// other parameter fixed. `point(v)` builds the operating point of a value.
pub fn bifurcation_chains(values: &[f64], point: impl Fn(f64) -> Point) -> Vec<Chain> {
    let up: Vec<Point> = values.iter().map(|&v| point(v)).collect();
    let down: Vec<Point> = up.iter().rev().copied().collect();
    vec![
        Chain { index: 0, direction: Direction::Up, points: up },
        Chain { index: 1, direction: Direction::Down, points: down },
    ]
}

/// A severity map over motor speed × normal force: chain 2j is row j (force
/// `forces_n[j]`) swept up in speed, chain 2j + 1 the same row swept down.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapSpec {
    pub speeds_rpm: Vec<f64>,
    pub forces_n: Vec<f64>,
}

impl MapSpec {
    pub fn chains(&self) -> Vec<Chain> {
        let mut chains = Vec::with_capacity(2 * self.forces_n.len());
        for (j, &n) in self.forces_n.iter().enumerate() {
            let mut c = bifurcation_chains(&self.speeds_rpm, |v| Point { motor_rpm: v, normal_force_n: n });
            c[0].index = 2 * j;
            c[1].index = 2 * j + 1;
            chains.extend(c);
        }
        chains
    }

    pub fn n_points(&self) -> usize {
        2 * self.speeds_rpm.len() * self.forces_n.len()
    }
}

/// Evenly spaced grid from `lo` to `hi` inclusive (n ≥ 2 points; n = 1 gives `lo`).
pub fn linspace(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if n <= 1 {
        return vec![lo];
    }
    (0..n).map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64).collect()
}

/// Shard `i` of `n` (1-based, as in `--shard 2/4`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// Parses `"i/n"` with 1 ≤ i ≤ n.
    pub fn parse(text: &str) -> Result<Shard, SweepError> {
        let bad = |rule: &'static str| SweepError::BadShard { text: text.to_string(), rule };
        let (i, n) = text.split_once('/').ok_or_else(|| bad("expected i/n, e.g. 1/1 or 2/4"))?;
        let index: usize = i.trim().parse().map_err(|_| bad("i is not a whole number"))?;
        let count: usize = n.trim().parse().map_err(|_| bad("n is not a whole number"))?;
        if count == 0 || index == 0 || index > count {
            return Err(bad("need 1 <= i <= n"));
        }
        Ok(Shard { index, count })
    }

    /// The chain indices of this shard among `total` chains: contiguous,
    /// sizes differing by at most one, the shards together covering 0..total.
    pub fn range(&self, total: usize) -> std::ops::Range<usize> {
        let lo = (self.index - 1) * total / self.count;
        let hi = self.index * total / self.count;
        lo..hi
    }
}

/// One shard's results of a map, mergeable with the others.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapSlice {
    pub spec: MapSpec,
    pub total_chains: usize,
    pub chains: Vec<ChainResult>,
}

/// Runs the chains of `map` that fall in `shard`.
pub fn run_map_shard(
    params: &RigParams,
    map: &MapSpec,
    shard: Shard,
    s: &SweepSettings,
    progress: &(dyn Fn() + Sync),
) -> MapSlice {
    let chains = map.chains();
    let total = chains.len();
    let mine = &chains[shard.range(total)];
    MapSlice { spec: map.clone(), total_chains: total, chains: run_chains(params, mine, s, progress) }
}

/// Joins shards into the whole map: same spec, every chain exactly once.
pub fn merge_slices(slices: Vec<MapSlice>) -> Result<MapSlice, SweepError> {
    let first = slices.first().ok_or(SweepError::Merge { rule: "no slice to merge" })?;
    let (spec, total) = (first.spec.clone(), first.total_chains);
    if slices.iter().any(|s| s.spec != spec || s.total_chains != total) {
        return Err(SweepError::Merge { rule: "slices come from different maps (grid or chain count differ)" });
    }
    let mut chains: Vec<ChainResult> = slices.into_iter().flat_map(|s| s.chains).collect();
    chains.sort_by_key(|c| c.index);
    let complete = chains.len() == total && chains.iter().enumerate().all(|(k, c)| c.index == k);
    if !complete {
        return Err(SweepError::Merge {
            rule: "slices must cover every chain exactly once (missing or duplicate shard)",
        });
    }
    Ok(MapSlice { spec, total_chains: total, chains })
}

/// Points where the up and down chains of the same parameter values disagree
/// on the regime (vibrating or not, or the regime label): the bistable band.
/// `up` and `down` run over the same values in opposite order.
pub fn hysteresis(up: &ChainResult, down: &ChainResult) -> Vec<(Point, String, String)> {
    let label = |o: &PointOutcome| match &o.result {
        Ok(c) => c.regime.label(),
        Err(_) => "failed".to_string(),
    };
    up.points
        .iter()
        .zip(down.points.iter().rev())
        .filter_map(|(u, d)| {
            let (lu, ld) = (label(u), label(d));
            (lu != ld).then_some((u.point, lu, ld))
        })
        .collect()
}
