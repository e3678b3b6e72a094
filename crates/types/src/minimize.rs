//! Minimisation without derivatives, one home for every crate's: Brent's
//! bracketed one-dimensional search ([`brent_min`]: the diagnosis' Stribeck
//! speed and drive limit, the stick-slip weakening law's speed) and the
//! Nelder–Mead simplex ([`nelder_mead`]: the LAVI study's candidate fits, the
//! slider's friction laws; to a convergence criterion,
//! [`nelder_mead_converged`]; raced over several starts, [`nelder_mead_race`]).

/// Minimum of `f` on [lo, hi] by Brent's method (Brent 1973, "Algorithms for
/// minimization without derivatives", ch. 5): parabolic interpolation through
/// the three best points where it falls inside the bracket and shrinks it,
/// golden-section steps otherwise, until the bracket is within `tol` of the
/// best point (or `max_evals` evaluations). A smooth minimum is reached in
/// about a third of the evaluations golden section alone needs for the same
/// bracket; a kink or a flat stretch (the drive limit's RSS) falls back to
/// golden steps, so it never does worse than golden section by more than a
/// few evaluations.
pub fn brent_min(lo: f64, hi: f64, tol: f64, max_evals: usize, mut f: impl FnMut(f64) -> f64) -> f64 {
    const C: f64 = 0.381_966_011_250_105_1; // (3 − √5)/2
    let (mut a, mut b) = (lo.min(hi), lo.max(hi));
    let mut x = a + C * (b - a);
    let (mut w, mut v) = (x, x);
    let mut fx = f(x);
    let (mut fw, mut fv) = (fx, fx);
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 1..max_evals {
        let m = 0.5 * (a + b);
        let tol1 = tol + 1e-12 * x.abs();
        let tol2 = 2.0 * tol1;
        if (x - m).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let golden_step = |x: f64| {
            let e = if x >= m { a - x } else { b - x };
            (C * e, e)
        };
        if e.abs() > tol1 {
            // Parabola through (v, fv), (w, fw), (x, fx): its vertex is x + p/q.
            let r = (x - w) * (fx - fv);
            let q0 = (x - v) * (fx - fw);
            let mut p = (x - v) * q0 - (x - w) * r;
            let mut q = 2.0 * (q0 - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let e_prev = e;
            e = d;
            if p.abs() >= (0.5 * q * e_prev).abs() || p <= q * (a - x) || p >= q * (b - x) {
                (d, e) = golden_step(x);
            } else {
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = tol1.copysign(m - x);
                }
            }
        } else {
            (d, e) = golden_step(x);
        }
        let u = if d.abs() >= tol1 { x + d } else { x + tol1.copysign(d) };
        let fu = f(u);
        if fu <= fx {
            if u >= x {
                a = x;
            } else {
                b = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    x
}

/// Nelder–Mead simplex (Nelder & Mead 1965; standard coefficients 1, 2, ½, ½),
/// deterministic, at most `max_evals` evaluations (a non-finite value counts
/// as 1e9), from `x0` with initial edges `step`, stopped when the simplex's
/// values lie within 1e-6 (1 + |f_best|) of each other. Returns (x, f(x),
/// evaluations).
pub fn nelder_mead(f: impl Fn(&[f64]) -> f64, x0: &[f64], step: &[f64], max_evals: usize) -> (Vec<f64>, f64, usize) {
    simplex(f, x0, step, max_evals, |pts| (pts[pts.len() - 1].1 - pts[0].1).abs() < 1e-6 * (1.0 + pts[0].1.abs()))
}

/// A race's result ([`nelder_mead_race`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RaceResult {
    /// The best point of every search and its value (the first of equals in start order).
    pub x: Vec<f64>,
    pub f: f64,
    /// Evaluations of `f`, every search's.
    pub evals: usize,
    /// Per start, its search's best value after the first round, in start order.
    pub first_round: Vec<f64>,
    /// The starts that ran on (indices into `starts`, best first).
    pub kept: Vec<usize>,
}

/// Nelder–Mead from several starts, raced: every start's simplex
/// ([`nelder_mead`]) runs `first_evals` evaluations, then only the `keep`
/// best of them (by their best value; the first of equals in start order)
/// run on to `max_evals` — a round of successive halving (Jamieson &
/// Talwalkar 2016, AISTATS; the multi-start's budget spent on the basins
/// that look best once each simplex has moved, not on the starts' own
/// values). A search that runs on takes exactly the points and decisions
/// [`nelder_mead`] from its start with `max_evals` takes (it resumes where
/// the first round stopped it). Deterministic; a non-finite value counts as 1e9.
pub fn nelder_mead_race(
    f: impl Fn(&[f64]) -> f64,
    starts: &[(&[f64], &[f64])],
    first_evals: usize,
    keep: usize,
    max_evals: usize,
) -> RaceResult {
    assert!(!starts.is_empty(), "a race needs a start");
    let done = |pts: &[(Vec<f64>, f64)]| (pts[pts.len() - 1].1 - pts[0].1).abs() < 1e-6 * (1.0 + pts[0].1.abs());
    let run = |s: &mut Search, cap: usize| {
        while !s.asked.is_empty() {
            let values: Vec<f64> = s.asked.iter().map(|x| f(x)).map(|v| if v.is_finite() { v } else { 1e9 }).collect();
            s.tell(&values, cap, &done);
        }
    };
    let best_of = |s: &Search| s.pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let mut searches: Vec<Search> = starts.iter().map(|(x0, step)| Search::new(x0, step)).collect();
    for s in searches.iter_mut() {
        run(s, first_evals);
    }
    let first_round: Vec<f64> = searches.iter().map(best_of).collect();
    let mut order: Vec<usize> = (0..searches.len()).collect();
    order.sort_by(|&a, &b| first_round[a].total_cmp(&first_round[b]));
    order.truncate(keep.max(1));
    for &i in &order {
        let s = &mut searches[i];
        if s.evals < max_evals {
            s.resume(&done);
            run(s, max_evals);
        }
    }
    let evals = searches.iter().map(|s| s.evals).sum();
    let mut best: Option<(Vec<f64>, f64)> = None;
    for s in searches.iter_mut() {
        s.pts.sort_by(|a, b| a.1.total_cmp(&b.1));
        if best.as_ref().is_none_or(|b| s.pts[0].1 < b.1) {
            best = Some(s.pts[0].clone());
        }
    }
    let (x, f) = best.expect("a race has a start");
    RaceResult { x, f, evals, first_round, kept: order }
}

/// When [`nelder_mead_converged`] stops: a simplex has converged when the
/// spread of its values, f(worst) − f(best), is at most `f_tol` and every
/// vertex lies within `x_tol` of the best one on every axis (both in the
/// caller's units: the absolute test of scipy's `fatol`/`xatol`); the
/// restarts stop when one lowers the best value by at most `f_tol`.
/// `max_evals` bounds the evaluations of the whole search (restarts
/// included): a safeguard, reported as not converged when it binds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimplexTolerance {
    pub f_tol: f64,
    pub x_tol: f64,
    pub max_evals: usize,
}

/// A converged search's result ([`nelder_mead_converged`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SimplexResult {
    pub x: Vec<f64>,
    pub f: f64,
    /// Evaluations of `f`, restarts included.
    pub evals: usize,
    /// Simplexes run (1: no restart improved on the first).
    pub simplexes: usize,
    /// False when `max_evals` stopped the search before the criterion held.
    pub converged: bool,
}

/// Nelder–Mead run to a stated convergence criterion instead of an
/// evaluation count ([`SimplexTolerance`]), then restarted from its best
/// point with a fresh simplex of edges `step(x)` until a restart lowers the
/// best value by no more than `f_tol`. A simplex can collapse onto a
/// hyperplane or stall on a kink of a piecewise-smooth objective and report a
/// false minimum; restarting at the claimed minimum is the standard remedy
/// (Press et al., Numerical Recipes, 3rd ed. 2007, §10.5: "it is a matter of
/// 5 or 10 lines of code to restart ... at a point where it claims to have
/// found a minimum"; Kelley 1999, SIAM J. Optim. 10:43, restarts on
/// stagnation). Deterministic; a non-finite value counts as 1e9.
pub fn nelder_mead_converged(
    f: impl Fn(&[f64]) -> f64,
    x0: &[f64],
    step: impl Fn(&[f64]) -> Vec<f64>,
    tol: &SimplexTolerance,
) -> SimplexResult {
    let done = |pts: &[(Vec<f64>, f64)]| {
        let (best, worst) = (&pts[0], &pts[pts.len() - 1]);
        worst.1 - best.1 <= tol.f_tol
            && pts[1..].iter().all(|p| p.0.iter().zip(&best.0).all(|(a, b)| (a - b).abs() <= tol.x_tol))
    };
    let (mut x, mut fx, mut evals) = simplex(&f, x0, &step(x0), tol.max_evals, done);
    let mut simplexes = 1;
    let mut converged = evals < tol.max_evals;
    while converged {
        let (y, fy, n) = simplex(&f, &x, &step(&x), tol.max_evals - evals, done);
        evals += n;
        simplexes += 1;
        converged = evals < tol.max_evals;
        let improved = fy < fx - tol.f_tol;
        if fy < fx {
            (x, fx) = (y, fy);
        }
        if !improved {
            break;
        }
    }
    SimplexResult { x, f: fx, evals, simplexes, converged }
}

/// The simplex of [`nelder_mead`] and [`nelder_mead_converged`]: stops when
/// `done` holds of the vertices sorted by value (best first) or after
/// `max_evals` evaluations. One search of [`simplex_many`].
fn simplex(
    f: impl Fn(&[f64]) -> f64,
    x0: &[f64],
    step: &[f64],
    max_evals: usize,
    done: impl Fn(&[(Vec<f64>, f64)]) -> bool,
) -> (Vec<f64>, f64, usize) {
    let all = |pts: &[(usize, &[f64])]| pts.iter().map(|p| f(p.1)).collect();
    simplex_many(all, &[(x0, step)], max_evals, done).pop().expect("one search gives one result")
}

/// [`nelder_mead`] from each start (x0, step) of `starts`, every search its
/// own, run side by side: at each round every search that is not done asks
/// for the points it needs next (its first n + 1 vertices, a reflection, an
/// expansion, a contraction, or a shrink's n vertices), and `f` gets them all
/// at once as (search, point) pairs, values in the same order. A caller whose
/// points are independent and costly (free runs of a model) evaluates them
/// together; each search takes the same points and decisions as alone.
/// Returns each search's (x, f(x), evaluations), in start order.
pub fn nelder_mead_many(
    f: impl Fn(&[(usize, &[f64])]) -> Vec<f64>,
    starts: &[(&[f64], &[f64])],
    max_evals: usize,
) -> Vec<(Vec<f64>, f64, usize)> {
    simplex_many(f, starts, max_evals, |pts| (pts[pts.len() - 1].1 - pts[0].1).abs() < 1e-6 * (1.0 + pts[0].1.abs()))
}

/// The simplexes of [`nelder_mead_many`] with the stop `done` (see [`simplex`]).
fn simplex_many(
    f: impl Fn(&[(usize, &[f64])]) -> Vec<f64>,
    starts: &[(&[f64], &[f64])],
    max_evals: usize,
    done: impl Fn(&[(Vec<f64>, f64)]) -> bool,
) -> Vec<(Vec<f64>, f64, usize)> {
    let mut searches: Vec<Search> = starts.iter().map(|(x0, step)| Search::new(x0, step)).collect();
    loop {
        let asked: Vec<(usize, &[f64])> =
            searches.iter().enumerate().flat_map(|(i, s)| s.asked.iter().map(move |x| (i, x.as_slice()))).collect();
        if asked.is_empty() {
            break;
        }
        let values = f(&asked);
        assert_eq!(values.len(), asked.len(), "one value per point asked");
        let mut values = values.into_iter().map(|v| if v.is_finite() { v } else { 1e9 });
        for s in searches.iter_mut() {
            let k = s.asked.len();
            if k > 0 {
                let mine: Vec<f64> = values.by_ref().take(k).collect();
                s.tell(&mine, max_evals, &done);
            }
        }
    }
    searches
        .into_iter()
        .map(|mut s| {
            s.pts.sort_by(|a, b| a.1.total_cmp(&b.1));
            let (x, v) = s.pts.swap_remove(0);
            (x, v, s.evals)
        })
        .collect()
}

/// What a simplex waits on (Nelder & Mead's steps; coefficients 1, 2, ½, ½).
enum Wait {
    /// The n + 1 vertices of the first simplex.
    Start,
    /// The reflection of the worst vertex through the centroid of the others.
    Reflect,
    /// The expansion, after the reflection `xr` gave `fr` below the best.
    Expand {
        xr: Vec<f64>,
        fr: f64,
    },
    /// The contraction, after the reflection gave `fr`.
    Contract {
        fr: f64,
    },
    /// The shrink's n vertices toward the best.
    Shrink,
    Finished,
}

/// One simplex of [`simplex_many`]: its vertices (sorted, best first, when a
/// step is asked), the evaluations spent, and the points it asked for.
struct Search {
    pts: Vec<(Vec<f64>, f64)>,
    evals: usize,
    centroid: Vec<f64>,
    wait: Wait,
    asked: Vec<Vec<f64>>,
}

impl Search {
    fn new(x0: &[f64], step: &[f64]) -> Self {
        let mut asked = vec![x0.to_vec()];
        for i in 0..x0.len() {
            let mut x = x0.to_vec();
            x[i] += step[i];
            asked.push(x);
        }
        Search { pts: Vec::with_capacity(x0.len() + 1), evals: 0, centroid: Vec::new(), wait: Wait::Start, asked }
    }

    /// The point centroid + t (worst − centroid).
    fn along(&self, t: f64) -> Vec<f64> {
        let n = self.centroid.len();
        (0..n).map(|k| self.centroid[k] + t * (self.pts[n].0[k] - self.centroid[k])).collect()
    }

    /// The loop's test of the single simplex (sorted), then its reflection
    /// asked: the next step of a search that goes on.
    fn reflect_unless(&mut self, done: &impl Fn(&[(Vec<f64>, f64)]) -> bool) {
        self.pts.sort_by(|a, b| a.1.total_cmp(&b.1));
        if done(&self.pts) {
            return;
        }
        let n = self.pts.len() - 1;
        self.centroid = (0..n).map(|k| self.pts[..n].iter().map(|p| p.0[k]).sum::<f64>() / n as f64).collect();
        self.asked = vec![self.along(-1.0)];
        self.wait = Wait::Reflect;
    }

    /// After a stop by the evaluation cap: asks the next step, as [`Search::tell`] would have
    /// with a larger cap (nothing when the simplex has converged or is mid-step).
    fn resume(&mut self, done: &impl Fn(&[(Vec<f64>, f64)]) -> bool) {
        if !self.asked.is_empty() || !matches!(self.wait, Wait::Finished) || self.pts.is_empty() {
            return;
        }
        self.reflect_unless(done);
    }

    /// Takes the values of the points asked (in order, non-finite already 1e9) and asks the next.
    fn tell(&mut self, values: &[f64], max_evals: usize, done: &impl Fn(&[(Vec<f64>, f64)]) -> bool) {
        let asked = std::mem::take(&mut self.asked);
        let n = asked[0].len();
        match std::mem::replace(&mut self.wait, Wait::Finished) {
            Wait::Start => {
                self.pts = asked.into_iter().zip(values.iter().copied()).collect();
                self.evals = n + 1;
            }
            Wait::Reflect => {
                let (xr, fr) = (asked.into_iter().next().expect("a reflection"), values[0]);
                let n = self.pts.len() - 1;
                self.evals += 1;
                if fr < self.pts[0].1 {
                    self.asked = vec![self.along(-2.0)];
                    self.wait = Wait::Expand { xr, fr };
                    return;
                } else if fr < self.pts[n - 1].1 {
                    self.pts[n] = (xr, fr);
                } else {
                    self.asked = vec![if fr < self.pts[n].1 { self.along(-0.5) } else { self.along(0.5) }];
                    self.wait = Wait::Contract { fr };
                    return;
                }
            }
            Wait::Expand { xr, fr } => {
                let (xe, fe) = (asked.into_iter().next().expect("an expansion"), values[0]);
                self.evals += 1;
                let n = self.pts.len() - 1;
                self.pts[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
            }
            Wait::Contract { fr } => {
                let (xc, fc) = (asked.into_iter().next().expect("a contraction"), values[0]);
                self.evals += 1;
                let n = self.pts.len() - 1;
                if fc < fr.min(self.pts[n].1) {
                    self.pts[n] = (xc, fc);
                } else {
                    let best = &self.pts[0].0;
                    self.asked = self.pts[1..]
                        .iter()
                        .map(|p| (0..n).map(|k| best[k] + 0.5 * (p.0[k] - best[k])).collect())
                        .collect();
                    self.wait = Wait::Shrink;
                    return;
                }
            }
            Wait::Shrink => {
                for (p, (x, v)) in self.pts.iter_mut().skip(1).zip(asked.into_iter().zip(values.iter().copied())) {
                    *p = (x, v);
                }
                self.evals += n;
            }
            Wait::Finished => return,
        }
        // The next step: the loop's test of the single simplex, then a reflection.
        if self.evals >= max_evals {
            return;
        }
        self.reflect_unless(done);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn searches_side_by_side_are_each_the_search_alone_to_the_bit() {
        // Rosenbrock (reflections, expansions, contractions), a kinked valley, a NaN
        // region, a shrinking simplex, dimensions 1 to 3, and budgets
        // that stop searches at different rounds.
        let rosen = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let kink = |x: &[f64]| x[0].abs() + 3.0 * (x[1] - 0.5).abs() + (x[2] + x[0]).abs().sqrt();
        let holed = |x: &[f64]| if x[0] > 2.0 { f64::NAN } else { (x[0] - 1.5).powi(2) };
        // A point minimum on a plateau: every reflection and contraction fails, the simplex shrinks.
        let spike = |x: &[f64]| if x.iter().all(|v| *v == 0.0) { 0.0 } else { 1.0 };
        type Objective<'a> = &'a dyn Fn(&[f64]) -> f64;
        let fs: [Objective; 4] = [&rosen, &kink, &holed, &spike];
        let starts: [(&[f64], &[f64]); 4] = [
            (&[-1.2, 1.0], &[0.5, 0.5]),
            (&[2.0, -1.0, 1.0], &[1.0, 1.0, 1.0]),
            (&[0.0], &[3.0]),
            (&[0.0, 0.0], &[1.0, 1.0]),
        ];
        for max_evals in [3, 40, 400] {
            // Per round, the most points one search asked for (after the first round: a shrink).
            let rounds = std::cell::RefCell::new(Vec::new());
            let many = nelder_mead_many(
                |pts| {
                    let most = (0..4).map(|i| pts.iter().filter(|p| p.0 == i).count()).max().unwrap_or(0);
                    rounds.borrow_mut().push(most);
                    pts.iter().map(|&(i, x)| fs[i](x)).collect()
                },
                &starts,
                max_evals,
            );
            for (i, (x0, step)) in starts.iter().enumerate() {
                let alone = nelder_mead(fs[i], x0, step, max_evals);
                let bits = |r: &(Vec<f64>, f64, usize)| {
                    (r.0.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), r.1.to_bits(), r.2)
                };
                assert_eq!(bits(&many[i]), bits(&alone), "search {i}, budget {max_evals}");
            }
            // Fewer rounds than evaluations: the searches' points came together.
            let (rounds, evals) = (rounds.into_inner(), many.iter().map(|r| r.2).sum::<usize>());
            assert!(rounds.len() < evals, "{} rounds for {evals} evaluations", rounds.len());
            if max_evals == 400 {
                assert!(rounds[1..].iter().any(|&k| k > 1), "a shrink was asked for side by side");
            }
        }
    }

    /// The race: a search that runs on ends to the bit where [`nelder_mead`]
    /// from its start with the full budget ends; the others stop at the first
    /// round's count; and on two basins whose starts' own values point to the
    /// shallow one, the first round's simplexes pick the deep one.
    #[test]
    fn a_race_keeps_the_searches_that_have_moved_best_and_resumes_them_exactly() {
        // Two basins: a shallow one at x = −2 (value 0.5) and a deep one at x = 3 (value 0),
        // with a slope that makes a start near 3 look worse than one near −2.
        let f = |x: &[f64]| {
            let shallow = 0.5 + (x[0] + 2.0).powi(2) + (x[1] - 1.0).powi(2);
            let deep = 0.3 * ((x[0] - 3.0).powi(2) + (x[1] + 1.0).powi(2));
            shallow.min(deep)
        };
        let starts: [(&[f64], &[f64]); 3] =
            [(&[-1.5, 1.5], &[0.3, 0.3]), (&[0.4, 2.0], &[0.3, 0.3]), (&[-2.6, 0.2], &[0.3, 0.3])];
        // The starts' values: the deep basin's start (index 1) is the worst of the three.
        let at: Vec<f64> = starts.iter().map(|s| f(s.0)).collect();
        assert!(at[1] > at[0] && at[1] > at[2], "{at:?}");
        let r = nelder_mead_race(f, &starts, 20, 1, 300);
        assert_eq!(r.kept, vec![1], "first round {:?}", r.first_round);
        let alone = nelder_mead(f, starts[1].0, starts[1].1, 300);
        assert_eq!((r.x.clone(), r.f.to_bits()), (alone.0.clone(), alone.1.to_bits()));
        assert!(r.f < 1e-6 && (r.x[0] - 3.0).abs() < 1e-3, "{r:?}");
        let short: Vec<usize> = [0, 2].iter().map(|&i| nelder_mead(f, starts[i].0, starts[i].1, 20).2).collect();
        assert_eq!(r.evals, alone.2 + short[0] + short[1]);
        // Keeping every start: each search is its full run alone, the best of them returned.
        let all = nelder_mead_race(f, &starts, 20, 3, 300);
        let full: Vec<(Vec<f64>, f64, usize)> = starts.iter().map(|s| nelder_mead(f, s.0, s.1, 300)).collect();
        assert_eq!(all.evals, full.iter().map(|r| r.2).sum::<usize>());
        assert_eq!(all.f.to_bits(), full.iter().map(|r| r.1).fold(f64::INFINITY, f64::min).to_bits());
    }

    #[test]
    fn nelder_mead_finds_a_quadratic_minimum() {
        let (x, v, _) =
            nelder_mead(|x| (x[0] - 1.0).powi(2) + 3.0 * (x[1] + 2.0).powi(2), &[0.0, 0.0], &[1.0, 1.0], 500);
        assert!((x[0] - 1.0).abs() < 1e-3 && (x[1] + 2.0).abs() < 1e-3 && v < 1e-6, "{x:?}");
    }

    /// The converged search stops on its criterion, not a count: on
    /// Rosenbrock's valley (minimum 0 at (1, 1)) from (−1.2, 1) it ends with
    /// every vertex within `x_tol` and within `f_tol` of the minimum's value;
    /// a tighter tolerance lands closer and costs more evaluations; and a
    /// budget that binds first is reported as not converged.
    #[test]
    fn nelder_mead_converged_stops_on_its_tolerance_and_says_when_the_budget_binds() {
        let rosen = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let step = |_: &[f64]| vec![0.1, 0.1];
        let run = |f_tol: f64, x_tol: f64, max_evals: usize| {
            nelder_mead_converged(rosen, &[-1.2, 1.0], step, &SimplexTolerance { f_tol, x_tol, max_evals })
        };
        let loose = run(1e-4, 1e-3, 5000);
        let tight = run(1e-10, 1e-6, 5000);
        for r in [&loose, &tight] {
            assert!(r.converged && r.simplexes >= 2, "{r:?}");
        }
        assert!(loose.f < 1e-3 && (loose.x[0] - 1.0).abs() < 0.1, "{loose:?}");
        assert!(tight.f < 1e-9 && (tight.x[0] - 1.0).abs() < 1e-4 && (tight.x[1] - 1.0).abs() < 1e-4, "{tight:?}");
        assert!(tight.evals > loose.evals, "{} vs {}", tight.evals, loose.evals);
        let short = run(1e-10, 1e-6, 40);
        assert!(!short.converged && short.evals <= 40 + 2, "{short:?}");
    }

    /// Brent's method against golden section on the same brackets: a smooth
    /// minimum, one off-centre with a quartic term, a kink and a flat stretch
    /// beside a minimum (the drive limit's RSS, constant where the limit never
    /// binds): it lands within its tolerance of the minimum, and on the smooth
    /// ones in under half of golden section's 27 evaluations.
    #[test]
    fn brent_finds_smooth_kinked_and_flat_sided_minima() {
        // (name, bracket, minimum, f, smooth)
        type Case = (&'static str, f64, f64, f64, fn(f64) -> f64, bool);
        let cases: [Case; 4] = [
            ("parabola", -1.0, 2.0, 0.3, |x| (x - 0.3) * (x - 0.3), true),
            ("quartic", -0.2, 0.145, 0.0, |x| x * x * (1.0 + 10.0 * x * x) + 2.0, true),
            ("kink", 0.0, 1.0, 0.7, |x| (x - 0.7).abs(), false),
            ("flat side", 0.0, 3.0, 1.2, |x| (x - 1.2).powi(2).min(0.25), false),
        ];
        for (name, lo, hi, at, f, smooth) in cases {
            let mut n = 0;
            let x = brent_min(lo, hi, 1e-6, 60, |x| {
                n += 1;
                f(x)
            });
            assert!((x - at).abs() < 1e-5, "{name}: {x} against {at}");
            if smooth {
                assert!(n <= 13, "{name}: {n} evaluations");
            }
        }
    }
}
