//! The misfit's local roughness about a fit (issue 26: what a difference of
//! misfits can resolve). The calibration misfit is piecewise smooth with
//! jumps at every scale — a simulated stretch lengthened or not
//! ([`predict`]'s integer count of periods), a slip near the hysteresis
//! counted or not (docs/findings.md, twentieth session, h/slider9) — so two
//! fits whose misfits differ by less than the misfit moves between
//! neighbouring points are not told apart by the search that found them.
//! [`landscape`] scans one search axis; [`roughness`] reads the largest move
//! at one relative step along every axis, both ways.

use super::{CandidateResult, Fitted, Measured, StudyParams, predict};
use crate::fit::{Model, run_misfit};
use rayon::prelude::*;
use rig_types::select::{Comparison, Fold, compare};

/// One point of a scan: the parameter's value, the mean misfit over the
/// runs (what the fits minimise) and each run's.
#[derive(Debug, Clone)]
pub struct ScanPoint {
    /// The step i: the parameter is x0 · (1 + i · rel).
    pub step: i32,
    pub value: f64,
    pub misfit: f64,
    pub per_run: Vec<f64>,
}

/// `model`'s mean misfit over `runs` (the fits' cost: [`run_misfit`] of
/// [`predict`], averaged over the runs in their order) at `x`, and each run's.
pub fn misfit_at(model: Model, x: &[f64], runs: &[&Measured], p: &StudyParams) -> (f64, Vec<f64>) {
    let per: Vec<f64> = runs.par_iter().map(|r| run_misfit(&r.features, &predict(model, x, r, p))).collect();
    (per.iter().sum::<f64>() / per.len().max(1) as f64, per)
}

/// The misfit along parameter `axis` about `x0`: the parameter scaled by
/// 1 + i · `rel`, i = −`steps`..=`steps` (the `landscape` example's scan).
pub fn landscape(
    model: Model,
    x0: &[f64],
    axis: usize,
    rel: f64,
    steps: i32,
    runs: &[&Measured],
    p: &StudyParams,
) -> Vec<ScanPoint> {
    (-steps..=steps)
        .map(|i| {
            let mut x = x0.to_vec();
            x[axis] *= 1.0 + rel * f64::from(i);
            let (misfit, per_run) = misfit_at(model, &x, runs, p);
            ScanPoint { step: i, value: x[axis], misfit, per_run }
        })
        .collect()
}

/// How far the misfit moves one relative step away from a fitted point.
#[derive(Debug, Clone, PartialEq)]
pub struct Roughness {
    /// The relative step (`roughness_rel_step`, pipeline.toml).
    pub rel_step: f64,
    /// The misfit at the point itself.
    pub misfit: f64,
    /// The largest |M(neighbour) − M(point)| over every axis, both ways...
    pub max_change: f64,
    /// ...along this parameter...
    pub axis: &'static str,
    /// ...and the mean |change| over the 2 × (parameters) neighbours.
    pub mean_change: f64,
}

impl Roughness {
    /// The largest move as a fraction of the point's misfit: what a
    /// relative gain is compared with.
    pub fn relative(&self) -> f64 {
        self.max_change / self.misfit
    }
}

/// The misfit's roughness at `x` (a fit of `model` on `runs`): the mean
/// misfit at x and at x with each parameter scaled by 1 ± `p.roughness_rel_step`
/// (1 + 2 × parameters evaluations). Deterministic: every point is
/// simulated on its own and averaged in the runs' order.
pub fn roughness(model: Model, x: &[f64], runs: &[&Measured], p: &StudyParams) -> Roughness {
    let specs = model.params();
    let rel = p.roughness_rel_step;
    let centre = misfit_at(model, x, runs, p).0;
    let moves: Vec<(usize, f64)> = (0..2 * x.len())
        .into_par_iter()
        .map(|k| {
            let (axis, sign) = (k / 2, if k % 2 == 0 { -1.0 } else { 1.0 });
            let mut y = x.to_vec();
            y[axis] *= 1.0 + sign * rel;
            (axis, (misfit_at(model, &y, runs, p).0 - centre).abs())
        })
        .collect();
    let (axis, max_change) = moves.iter().fold((0, 0.0), |(a, m), &(ax, d)| if d > m { (ax, d) } else { (a, m) });
    let mean_change = moves.iter().map(|m| m.1).sum::<f64>() / moves.len().max(1) as f64;
    Roughness { rel_step: rel, misfit: centre, max_change, axis: specs[axis].name, mean_change }
}

/// The calibration misfit about a fit read as a local mean
/// ([`local_misfit`]): the misfit at the point, and its mean and sample sd
/// over `moves` fixed random moves of relative size `rel`.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalMisfit {
    pub at: f64,
    pub mean: f64,
    pub sd: f64,
    pub moves: usize,
    pub rel: f64,
    /// The misfit at each move, in the moves' order (the same moves at
    /// every call: common random numbers across fits, laws and runs).
    pub values: Vec<f64>,
}

/// The first index of [`local_misfit`]'s moves in the track's generator:
/// a travel of 2⁴⁰ correlation lengths backwards, which no run reaches.
const MOVES_FROM: i64 = -(1 << 40);

/// The generator's indices one move takes: move j's value for parameter i
/// is node(MOVES_FROM − j · MOVE_STRIDE − i) whatever the model's parameter
/// count (at most this many), so every law's move j is drawn from the same
/// values (common random numbers across laws, not only across runs).
const MOVE_STRIDE: i64 = 16;

/// `model`'s mean misfit over `runs` at `x` and over `moves` points
/// x_i (1 + `rel` z_ij), z_ij fixed standard normal values (the track's
/// generator, [`crate::track`], from [`MOVES_FROM`], where no travel reaches: the
/// same moves at every call). Why (docs/findings.md, twenty-first session,
/// h/slider11): a law whose slips land on a threshold that varies over
/// lengths far below a slip (`track_threshold`) gives a chaotic sample path,
/// whose events decorrelate within relative moves of 10⁻⁶–10⁻⁵ of σ or ℓ;
/// its misfit is then a sample statistic of a few tens of events, noisy at
/// any scale a search resolves, and a fit's point misfit is one draw of that
/// noise (a search's best is its lowest draw). The local mean is the misfit
/// smoothed by a Gaussian kernel in the parameters (Nesterov & Spokoiny
/// 2017's Gaussian smoothing; the smoothing of a simulated criterion that
/// jumps, Bruins, Duffy, Keane & Smith 2018, J. Econometrics 205), what two
/// fits of such a law can be compared on, and the sd the noise one draw
/// carries. Deterministic: the moves are evaluated in parallel, collected in order.
pub fn local_misfit(
    model: Model,
    x: &[f64],
    runs: &[&Measured],
    p: &StudyParams,
    moves: usize,
    rel: f64,
) -> LocalMisfit {
    let at = misfit_at(model, x, runs, p).0;
    assert!(x.len() as i64 <= MOVE_STRIDE, "local_misfit: {} parameters, at most {MOVE_STRIDE}", x.len());
    let vals: Vec<f64> = (0..moves as i64)
        .into_par_iter()
        .map(|j| {
            let y: Vec<f64> = x
                .iter()
                .enumerate()
                .map(|(i, v)| v * (1.0 + rel * crate::track::node(MOVES_FROM - j * MOVE_STRIDE - i as i64)))
                .collect();
            misfit_at(model, &y, runs, p).0
        })
        .collect();
    let mean = vals.iter().sum::<f64>() / moves.max(1) as f64;
    let sd = if moves > 1 {
        (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (moves - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    LocalMisfit { at, mean, sd, moves, rel, values: vals }
}

/// The misfit the selection reads of `fit` at run `r` (the lead's decision,
/// issue 26, twenty-first session: a law whose misfit is a noisy statistic
/// is judged on its expected misfit, not on one draw): a noisy fit's
/// ([`Fitted::noisy`]) is its local mean over the study's fixed moves
/// ([`local_misfit`] on the one run, returned beside it with its sd), a
/// smooth fit's its point misfit.
pub fn read_misfit(fit: &Fitted, r: &Measured, p: &StudyParams) -> (f64, Option<LocalMisfit>) {
    if fit.noisy {
        let l = local_misfit(fit.model, &fit.params, &[r], p, p.local_moves, p.local_rel_step);
        (l.mean, Some(l))
    } else {
        (run_misfit(&r.features, &predict(fit.model, &fit.params, r, p)), None)
    }
}

/// A step's held-out gain among neighbouring fits of its best: each fold's
/// fit of the best moved one `roughness_rel_step` along one parameter, either
/// way, the other folds' fits and the model the step starts from kept, and
/// the gain and paired t recomputed by the engine's own
/// [`rig_types::select::compare`].
#[derive(Debug, Clone, PartialEq)]
pub struct GainSpread {
    /// Neighbouring fits tried: folds × parameters × 2.
    pub neighbours: usize,
    pub gain_min: f64,
    pub gain_max: f64,
    pub t_min: f64,
    pub t_max: f64,
    /// How many of them the step rule (`[shared.selection]`) admits.
    pub admitted: usize,
    /// True when the best's fits are noisy: the neighbours are then the
    /// study's fixed moves (move j of every fold's fit at once, the held-out
    /// misfit of each run at that move: one draw of the gain its local means
    /// average), not the ± `roughness_rel_step` moves along one axis.
    pub over_moves: bool,
}

/// [`GainSpread`] of `best` over `from` (two records of one selection,
/// their held-out misfits per run under the folds `folds`); None when a
/// fold has no fit of `best`.
pub fn gain_spread(
    from: &CandidateResult,
    best: &CandidateResult,
    folds: &[Fold],
    runs: &[Measured],
    p: &StudyParams,
) -> Option<GainSpread> {
    let units: Vec<usize> = from.heldout.iter().map(|h| h.0).collect();
    if best.heldout.iter().map(|h| h.0).ne(units.iter().copied()) {
        return None;
    }
    let fold_of: Vec<usize> =
        units.iter().map(|r| folds.iter().position(|f| f.held_out.contains(r))).collect::<Option<_>>()?;
    let before: Vec<f64> = from.heldout.iter().map(|h| h.1).collect();
    let after: Vec<f64> = best.heldout.iter().map(|h| h.1).collect();
    if best.fold_fits.iter().any(|f| f.noisy) {
        return Some(spread_over_moves(from, best, &before, &after, &fold_of, folds.len(), p));
    }
    let mut moves: Vec<(usize, usize, f64)> = Vec::new();
    for (k, fold) in folds.iter().enumerate() {
        let fit = best.fold_fits.iter().find(|f| f.train == fold.train)?;
        for axis in 0..fit.params.len() {
            for sign in [-1.0, 1.0] {
                moves.push((k, axis, sign));
            }
        }
    }
    let compared: Vec<Comparison> = moves
        .par_iter()
        .map(|&(k, axis, sign)| {
            let fit = best.fold_fits.iter().find(|f| f.train == folds[k].train).expect("checked above");
            let mut y = fit.params.clone();
            y[axis] *= 1.0 + sign * p.roughness_rel_step;
            let mut a = after.clone();
            for (i, &r) in units.iter().enumerate().filter(|(i, _)| fold_of[*i] == k) {
                a[i] = run_misfit(&runs[r].features, &predict(best.model, &y, &runs[r], p));
            }
            compare(&before, &a, &fold_of, folds.len())
        })
        .collect();
    Some(GainSpread::of(&compared, p, false))
}

impl GainSpread {
    /// The range of gain and t over `compared`, and how many of them the
    /// step rule admits.
    fn of(compared: &[Comparison], p: &StudyParams, over_moves: bool) -> GainSpread {
        let fold = |f: fn(f64, f64) -> f64, init: f64, g: fn(&Comparison) -> f64| compared.iter().map(g).fold(init, f);
        GainSpread {
            neighbours: compared.len(),
            gain_min: fold(f64::min, f64::INFINITY, |c| c.gain),
            gain_max: fold(f64::max, f64::NEG_INFINITY, |c| c.gain),
            t_min: fold(f64::min, f64::INFINITY, |c| c.t),
            t_max: fold(f64::max, f64::NEG_INFINITY, |c| c.t),
            admitted: compared.iter().filter(|c| p.selection.admits(c)).count(),
            over_moves,
        }
    }
}

/// [`GainSpread`] of a noisy best over the study's fixed moves: at move j
/// each held-out run's misfit is its value at move j of its fold's fit
/// (the local mean's j-th term, [`LocalMisfit::values`]) where that fit is
/// noisy, its point misfit where smooth; the gain and t by the engine's
/// [`compare`]. No simulation: the values are the local means' own.
fn spread_over_moves(
    from: &CandidateResult,
    best: &CandidateResult,
    before: &[f64],
    after: &[f64],
    fold_of: &[usize],
    folds: usize,
    p: &StudyParams,
) -> GainSpread {
    let at = |c: &CandidateResult, point: &[f64], j: usize| -> Vec<f64> {
        point
            .iter()
            .enumerate()
            .map(|(i, &m)| c.heldout_local.get(i).and_then(Option::as_ref).map_or(m, |l| l.values[j]))
            .collect()
    };
    let compared: Vec<Comparison> =
        (0..p.local_moves).map(|j| compare(&at(from, before, j), &at(best, after, j), fold_of, folds)).collect();
    GainSpread::of(&compared, p, true)
}
