//! The drive-limit search: the limit Vmax minimising the voltage RSS, the
//! gains refitted at every trial limit ([`super::gains`]).

use super::gains::fit_gains_lm;
use super::{Pi, Recording, visit};
use crate::prepare::RunSignals;
use rig_types::minimize::brent_min;

/// The drive-limit candidate: Vmax minimising the voltage RSS (gains refitted
/// at every trial limit), searched between 5 % of the supply and the supply;
/// a limit no training sample reaches is reported as the lowest limit the
/// training runs fit equally well at (see below).
/// Returns (Pi, rss, n, stderr of Vmax from the RSS curvature).
///
/// # The gains at a trial limit
///
/// At every trial limit the gains are the voltage RSS's minimum in (kp, ki)
/// (`drive/gains.rs`: Levenberg–Marquardt on the clamped recursion's exact
/// sensitivities), so Brent minimises the profile RSS(Vmax) = min over the
/// gains. Until the sixteenth session they were the 8th iterate of an
/// alternation (clamp pattern ↔ least squares on the unclamped samples,
/// [`super::fit_gains`]), which is not a descent of the RSS: it walked past
/// the RSS minimum, rarely met its stop, and the limit Brent read
/// depended on the pass cap (docs/findings.md, issue 23).
///
/// # Two starts
///
/// The RSS in the gains has more than one minimum at a limit near a
/// record's clip: the unlimited fit `p0`, which a clipped record wrecks
/// (its plateau samples, V flat while ∫e grows, pull ki to 0), predicts no
/// clamp at a limit near the plateau, and a fit started there can stay on
/// the wrecked gains (`ladder-drive_voltage_limit-1-16` of the full
/// battery: clip at 4.29 V, RSS 1.6·10⁹ at 4.29 V from `p0` against
/// 3.5·10⁶ at 4.15 V, with the alternation; the grid's 4.2 V point fell on
/// the wrecked gains, the bracket then ended below the clip and the limit
/// was read at 4.11 V, 0.17 V low, which slowed every clipped run of the
/// free run). So the grid points between the first pass's best and the flat
/// stretch are scored again from the best point's gains, and Brent's
/// search starts from the gains at the best grid point after that
/// rescoring, each later trial from the nearest earlier trial's gains.
pub fn fit_limit(runs: &[&RunSignals], supply_v: f64) -> Option<(Pi, f64, usize, f64)> {
    search_limit(&Recording::all(runs), supply_v, true)
}

/// [`fit_limit`]'s gains and limit alone, as a cross-validation fold uses
/// them: the same search and the same [`Pi`] to the bit, without the two
/// fits of the RSS curvature that only the standard error reads.
pub fn fit_limit_gains(runs: &[&RunSignals], supply_v: f64) -> Option<Pi> {
    search_limit(&Recording::all(runs), supply_v, false).map(|x| x.0)
}

/// [`fit_limit`] on prepared recordings; the standard error (NaN without
/// `with_se`) from two more fits beside the optimum.
fn search_limit(runs: &[Recording], supply_v: f64, with_se: bool) -> Option<(Pi, f64, usize, f64)> {
    // Every trial limit refits the gains from the unlimited fit (warm start):
    // the gains' RSS minimum at the supply, from zero gains (where every run
    // is linear in them, so the first Gauss–Newton steps are its least squares).
    let zero = Pi { kp_v_s_rad: 0.0, ki_v_rad: 0.0, limit_v: supply_v };
    let p0 = fit_gains_lm(runs, supply_v, &zero, |_| {})?.pi;
    let fits = FitMemo::default();
    let eval_from = |l: f64, start: &Pi| fits.fit(runs, l, start).map_or(f64::INFINITY, |f| f.1);
    // A limit that binds nowhere gives the same arithmetic as any other such
    // limit (the clamp and the exclusion of saturated samples are the only
    // places the limit enters), so those trials reuse one evaluation.
    let free = non_binding_from(runs, supply_v, &p0);
    let eval_with = |l: f64, start: &Pi| match free {
        Some((l_free, rss)) if l >= l_free => rss,
        _ => eval_from(l, start),
    };
    // Coarse grid first (the RSS is not unimodal far from the optimum), then Brent's method.
    // The grid is scored from the top down, and a limit whose RSS cannot beat the best
    // so far is not fitted (branch and bound): a sample measured beyond ±l is predicted
    // within ±l, so RSS(l) ≥ Σ w (|V| − l)² over those samples. A skipped limit's RSS
    // is above the best score, so the grid's minimum (the first of equal ones) is the
    // one scoring every limit finds. Skipping the limits far below what the runs drive,
    // each fitted with every sample clamped in up to eight passes, took the diagnosis
    // stage from 10.7 to 9.6 s of CPU.
    let grid: Vec<f64> = (0..=38).map(|j| supply_v * (0.05 + 0.025 * j as f64)).collect();
    let mut scores = vec![f64::INFINITY; grid.len()];
    let mut best_rss = f64::INFINITY;
    for (j, &l) in grid.iter().enumerate().rev() {
        if rss_lower_bound(runs, l, best_rss) > best_rss {
            continue;
        }
        scores[j] = eval_with(l, &p0);
        best_rss = best_rss.min(scores[j]);
    }
    let mut best = (0..grid.len()).min_by(|&a, &b| scores[a].total_cmp(&scores[b]))?;
    // The second start (doc above): the best grid point's gains, for the
    // binding grid points above it.
    let l_free = free.map_or(f64::INFINITY, |f| f.0);
    let mut start = p0;
    // The best grid point's fit as Brent's first neighbour: (limit, its start, its gains).
    let mut seed = None;
    if grid[best] < l_free
        && let Some((p1, _)) = fits.fit(runs, grid[best], &p0)
    {
        start = p1;
        for j in best + 1..grid.len() {
            if grid[j] >= l_free {
                break;
            }
            scores[j] = scores[j].min(eval_from(grid[j], &p1));
        }
        best = (0..grid.len()).min_by(|&a, &b| scores[a].total_cmp(&scores[b]))?;
        if let Some((p, _)) = fits.fit(runs, grid[best], &p1) {
            start = p;
            seed = Some((grid[best], p1, p));
        }
    }
    // Brent's trials, each warm-started from the fitted gains of the trial
    // nearest in limit so far (the first of equally near ones; the best grid
    // point's fit, `start`, seeds them where the grid's best binds; `start`
    // alone where nothing was fitted yet): the fit is the RSS minimum to its
    // stop rule's tenth of a standard error (`drive/gains.rs`), so the start
    // moves it only within that, and a neighbour's gains are a few RSS
    // evaluations closer to it than the grid point's (docs/performance.md,
    // seventeenth session). Each trial keeps (limit, start, fit): the
    // memo's key is the start, so the reported gains are the trial's own.
    // With the alternation the unlimited fit was a second start at every
    // trial; with the gains' RSS minimum it gave the same answers to the
    // bit on drive-limit rungs 1, 4 and 5 and the strided samples, at 29 %
    // more of rung 1's CPU (sixteenth session).
    let trials = std::cell::RefCell::new(Vec::<(f64, Pi, Pi)>::from_iter(seed));
    let warm = |l: f64| {
        trials.borrow().iter().min_by(|a, b| (a.0 - l).abs().total_cmp(&(b.0 - l).abs())).map_or(start, |t| t.2)
    };
    let eval = |l: f64| match free {
        Some((l_free, rss)) if l >= l_free => rss,
        _ => {
            let s = warm(l);
            let fit = fits.fit(runs, l, &s);
            if let Some((p, _)) = fit {
                trials.borrow_mut().push((l, s, p));
            }
            fit.map_or(f64::INFINITY, |f| f.1)
        }
    };
    let lo = grid[best.saturating_sub(1)];
    let hi = grid[(best + 1).min(grid.len() - 1)];
    // Vmax to 10⁻⁷ of the supply (golden section's 24 steps on this bracket reached 5·10⁻⁷).
    let l = brent_min(lo, hi, 1e-7 * supply_v, 26, eval);
    // Where no training sample reaches the limit (l ≥ l_free, the RSS flat),
    // every such limit fits equally well and the data say only that Vmax is
    // at least what was driven: the limit is read at the flat stretch's
    // lower end, the lowest limit the training runs fit as well as any
    // higher one. When the effect is there (the candidate is kept only for
    // its held-out gain), a held-out run that drives harder than every
    // training run is the one that clips: the full battery's weakest drive
    // limit clips one run of 30 (`ladder-drive_voltage_limit-5-4`, op-16 at
    // 7.14 V), and the fold that holds it out, reading its limit as the
    // supply, predicted it 0.61 × the supply off (its PI winding up to
    // 24 V), 14.5× the noise floor over the campaign; read at the flat
    // stretch's end (7.11 V), 0.0045. When it is not there, clamping the
    // harder-driving held-out run only costs the candidate held-out gain.
    let l = match free {
        Some((l_free, _)) if l >= l_free => l_free,
        _ => l,
    };
    let n = runs.iter().map(|r| r.p.e_rad_s.len()).sum::<usize>();
    // The gains at the returned limit: Brent's own trial there (the memo's
    // entry for its start); at the flat stretch's end, from `start`.
    let at = trials.borrow().iter().find(|t| t.0.to_bits() == l.to_bits()).map_or(start, |t| t.1);
    let (pi, rss) = fits.fit(runs, l, &at)?;
    if !with_se {
        return Some((pi, rss, n, f64::NAN));
    }
    // Profile-likelihood curvature: Var(Vmax) ≈ 2σ²/RSS''; RSS is in noise units (σ² = rss/n).
    let h = (1e-3 * supply_v).max(1e-4);
    let d2 = (eval(l + h) - 2.0 * rss + eval(l - h)) / (h * h);
    let se = if d2 > 0.0 { (2.0 * (rss / n as f64) / d2).sqrt() } else { f64::NAN };
    Some((pi, rss, n, se))
}

/// The gains [`fit_gains_lm`] reaches at a trial limit from a start, with
/// their voltage RSS, kept for the rest of one limit search: the search
/// asks for some (limit, start) pairs more than once — the grid's best
/// point again from the unlimited fit for the second start, the best point
/// after the second start's rescoring again from it, and Brent's returned
/// trial (from the start it had) for the reported gains (with the alternation of eight
/// passes the fits were 61 % of a clipped ladder rung's CPU in `perf`, 4–9
/// of a fold search's 29–53 fits repeats, issue 23). A fit is a function
/// of the limit and the start's gains alone (the start's own limit is
/// replaced), so a repeat is the same gains and RSS to the bit.
#[derive(Default)]
struct FitMemo {
    /// (limit, start's kp, start's ki) bits, and the fit with its RSS.
    done: std::cell::RefCell<Vec<MemoEntry>>,
}

/// An entry of [`FitMemo`].
type MemoEntry = ([u64; 3], Option<(Pi, f64)>);

impl FitMemo {
    /// [`fit_gains_lm`] at `limit_v` from `start`, with its RSS.
    fn fit(&self, runs: &[Recording], limit_v: f64, start: &Pi) -> Option<(Pi, f64)> {
        let key = [limit_v.to_bits(), start.kp_v_s_rad.to_bits(), start.ki_v_rad.to_bits()];
        if let Some((_, f)) = self.done.borrow().iter().find(|(k, _)| *k == key) {
            return *f;
        }
        let f = fit_gains_lm(runs, limit_v, start, |_| {}).map(|f| (f.pi, f.rss));
        self.done.borrow_mut().push((key, f));
        f
    }
}

/// A lower bound of the voltage RSS (noise units, as [`voltage_rss`]) of any
/// gains at limit `l`: the prediction is clamped to ±l, so a sample measured
/// at |V| > l misses by at least |V| − l. Only the samples beyond `l` add, so
/// each run's are read from the top of its |V| in ascending order
/// ([`Prepared`]'s `v_abs_sorted`), largest first, and the sum stops once it
/// exceeds `cap` (every term is ≥ 0, so it can only grow): the grid's
/// limits far below the driven voltage, each a pass over every sample of
/// every training run, were 2.8 % of a ladder rung's CPU in `perf` (issue
/// 23). The terms are added in another order than the samples', so the
/// bound differs from the per-sample sum by rounding (≈ 10⁻¹⁶ of itself);
/// it decides only whether a limit is fitted, and a limit whose RSS is
/// within that rounding of the best one's is the only one it could decide
/// otherwise.
fn rss_lower_bound(runs: &[Recording], l: f64, cap: f64) -> f64 {
    let mut total = 0.0;
    for s in runs {
        let w = 1.0 / s.voltage_noise_v.max(1e-6).powi(2);
        let v = &s.p.v_abs_sorted;
        let beyond = &v[v.partition_point(|&x| x <= l)..];
        let mut run_sum = 0.0;
        for chunk in beyond.rchunks(256) {
            run_sum += chunk.iter().rev().map(|x| (x - l).powi(2)).sum::<f64>();
            if total + w * run_sum > cap {
                return total + w * run_sum;
            }
        }
        total += w * run_sum;
    }
    total
}

/// The lowest limit from which on the drive-limit fit no longer depends on
/// the limit, with the RSS there: the fit at the supply, traced, clamps no
/// sample at any gains it evaluates; then every limit above both the
/// largest |V̂| of those gains and the largest |V|/0.999 gives the same
/// evaluations (the limit enters the fit through the clamp alone), and a
/// limit that low is one no training sample reaches.
/// `None` when the supply itself binds; else (that limit, the RSS there).
fn non_binding_from(runs: &[Recording], supply_v: f64, p0: &Pi) -> Option<(f64, f64)> {
    let v_meas = runs.iter().flat_map(|s| s.voltage_v.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    let v_floor = v_meas / 0.999;
    let mut v_pred = 0.0f64;
    let mut binds = false;
    let mut visited = Vec::new();
    let fitted = fit_gains_lm(runs, supply_v, p0, |pi| visited.push(*pi))?;
    for pi in &visited {
        for r in runs {
            // An unclamped run's largest |V̂| at its hull's vertices (within
            // 10⁻¹⁵ of the samples', which the margin below covers). Where
            // its bound without the hull ([`Prepared::max_abs_bound`], never
            // below it) is at most max(v_pred, v_floor) so far, the run's
            // maximum cannot raise `l_free` (a max of maxima), and the hull
            // is not built.
            if r.p.idle(pi) {
                if r.p.max_abs_bound(pi) <= v_pred.max(v_floor) {
                    continue;
                }
                v_pred = v_pred.max(r.p.max_abs_unclamped(pi).0);
                continue;
            }
            visit(pi, r, |_, _, v, _, sat| {
                v_pred = v_pred.max(v.abs());
                binds |= sat;
            });
        }
    }
    let l_free = v_pred.max(v_floor) * (1.0 + 1e-12);
    if binds || v_meas >= 0.999 * supply_v || l_free > supply_v {
        return None;
    }
    Some((l_free, fitted.rss))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::tests::runs;
    use crate::drive::{fit_gains, rss_of, voltage_rss};

    /// The search's memo answers a repeated (limit, start) with the fit and
    /// RSS computed the first time, the same bits as fitting again, and
    /// keeps one entry per pair; a start differing only in its own limit
    /// (which the fit replaces) is the same pair.
    #[test]
    fn a_repeated_fit_of_the_search_is_the_fit_again() {
        let rs = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 2.0, 3.0]);
        let r: Vec<&RunSignals> = rs.iter().collect();
        let rec = Recording::all(&r);
        let start = fit_gains(&r, 24.0).expect("unlimited fit");
        let memo = FitMemo::default();
        let bits =
            |f: Option<(Pi, f64)>| f.map(|(p, rss)| [p.kp_v_s_rad, p.ki_v_rad, p.limit_v, rss].map(f64::to_bits));
        for l in [4.8, 5.2, 4.8] {
            let direct = fit_gains_lm(&rec, l, &start, |_| {}).map(|f| (f.pi, f.rss));
            assert!(direct.is_some_and(|(p, _)| !rec.iter().all(|x| x.p.idle(&p))), "a clamping fit at {l} V");
            assert_eq!(bits(memo.fit(&rec, l, &start)), bits(direct));
            assert_eq!(bits(memo.fit(&rec, l, &Pi { limit_v: 1.0, ..start })), bits(direct));
        }
        assert_eq!(memo.done.borrow().len(), 2);
    }

    /// The limit search's reported RSS is its gains' RSS to the bit, and a
    /// fold's gains-only search gives the same gains and limit.
    #[test]
    fn the_reported_rss_is_the_gains_rss_and_the_folds_search_the_same_gains() {
        for (truth, sp) in [(5.0, [1.0, 2.0, 3.0]), (24.0, [1.0, 1.5, 2.0])] {
            let rs = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: truth }, &sp);
            let r: Vec<&RunSignals> = rs.iter().collect();
            let (pi, rss, n, _) = fit_limit(&r, 24.0).expect("fit");
            let rec = Recording::all(&r);
            assert_eq!((rss.to_bits(), n), (rss_of(&pi, &rec).0.to_bits(), rss_of(&pi, &rec).1));
            assert_eq!(fit_limit_gains(&r, 24.0), Some(pi));
        }
    }

    /// The bound that lets the limit's grid skip fits holds: at every grid limit
    /// the fitted gains' RSS is at least [`rss_lower_bound`], which is zero where
    /// no sample is beyond the limit; and it prunes: far below the driven
    /// voltage it exceeds the grid's best RSS, so those limits are not fitted.
    #[test]
    fn the_lower_bound_is_below_every_fitted_rss_and_prunes_hopeless_limits() {
        let limited = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 2.0, 3.0]);
        let r: Vec<&RunSignals> = limited.iter().collect();
        let rec = Recording::all(&r);
        // The gains the search fits at a grid limit: from the unlimited fit.
        let p0 = fit_gains(&r, 24.0).expect("unlimited fit");
        let scored: Vec<(f64, f64, f64)> = (0..=38)
            .map(|j| {
                let l = 24.0 * (0.05 + 0.025 * j as f64);
                (
                    l,
                    rss_lower_bound(&rec, l, f64::INFINITY),
                    fit_gains_lm(&rec, l, &p0, |_| {}).map(|f| voltage_rss(&f.pi, &r).0).expect("fit"),
                )
            })
            .collect();
        let best = scored.iter().map(|x| x.2).fold(f64::INFINITY, f64::min);
        for &(l, bound, rss) in &scored {
            assert!(bound <= rss, "limit {l}: bound {bound} > rss {rss}");
            // The bound read from the sorted tails is the per-sample sum, up to rounding.
            let per_sample: f64 = limited
                .iter()
                .map(|s| {
                    let w = 1.0 / s.voltage_noise_v.max(1e-6).powi(2);
                    w * s.voltage_v.iter().map(|v| (v.abs() - l).max(0.0).powi(2)).sum::<f64>()
                })
                .sum();
            assert!((bound - per_sample).abs() <= 1e-12 * per_sample, "limit {l}: {bound} vs {per_sample}");
            // Capped, it stops above the cap, never below it.
            let capped = rss_lower_bound(&rec, l, 0.5 * per_sample);
            assert!(capped <= bound && (per_sample == 0.0 || capped > 0.5 * per_sample), "limit {l}: {capped}");
            if l > 5.1 {
                assert_eq!(bound, 0.0, "limit {l}");
            }
        }
        let pruned = scored.iter().filter(|x| x.1 > best).count();
        assert!(pruned >= 5, "{pruned} of {} limits pruned", scored.len());
    }

    /// A limit the training runs never reach fits no better anywhere above
    /// what they drive: the fit reports that stretch's lower end, just above
    /// the largest voltage driven (not the supply, which let a held-out run
    /// that drives harder wind up to 24 V, nor an accidental point of the
    /// stretch). A limit the runs do reach is found (within 5 %: the gains,
    /// refitted at each trial limit, absorb part of it).
    #[test]
    fn an_unreached_limit_is_read_at_the_largest_voltage_driven_and_a_reached_one_is_found() {
        let free = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 24.0 }, &[1.0, 1.5, 2.0]);
        let r: Vec<&RunSignals> = free.iter().collect();
        let driven = free.iter().flat_map(|s| s.voltage_v.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
        let (pi, ..) = fit_limit(&r, 24.0).expect("fit");
        assert!(pi.limit_v >= driven / 0.999 && pi.limit_v < 1.2 * driven, "{pi:?}, driven {driven}");
        let pi_free = fit_gains(&r, 24.0).expect("fit");
        let (rss_at, _) = voltage_rss(&pi, &r);
        let (rss_supply, _) = voltage_rss(&pi_free, &r);
        assert!((rss_at - rss_supply).abs() <= 1e-9 * rss_supply, "{rss_at} vs {rss_supply}");
        let limited = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 2.0, 3.0]);
        let (pi, ..) = fit_limit(&limited.iter().collect::<Vec<_>>(), 24.0).expect("fit");
        assert!((pi.limit_v - 5.0).abs() < 0.25 && pi.limit_v < 24.0, "{pi:?}");
    }
}
