//! Selection on several views of one fit ([`select_on_views`]): each
//! candidate scored per view, the views' standings and the step decided by
//! the best-standing view (the diagnosis' structures).

use super::*;

/// Where an admitted candidate ranks: a higher `tier` wins; within a tier,
/// the larger gain on the view `by_view` (ties: candidate order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Standing {
    pub tier: u32,
    pub by_view: usize,
}

/// The criterion of a one-step selection on views: from candidate
/// `candidate`'s comparisons with the baseline (one per view, in view order),
/// whether it is admitted (`Some`) and where it ranks.
pub trait ViewRule: Sync {
    fn standing(&self, candidate: usize, comparisons: &[Comparison]) -> Option<Standing>;
}

/// One candidate of a one-step selection on views.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewTrial<M> {
    /// Index into the candidates passed to [`select_on_views`].
    pub candidate: usize,
    pub id: String,
    /// The fitted models, one per distinct training set; empty when a fit failed.
    pub fitted: Vec<M>,
    pub error: Option<String>,
    /// `misfits[view][i]`: the held-out unit `units[i]`'s misfit in that view.
    pub misfits: Vec<Vec<Option<f64>>>,
    /// Each view's comparison with the baseline over the units both score.
    pub comparisons: Vec<Comparison>,
    /// The candidate's admissibility verdict ([`Candidate::inadmissible`],
    /// asked of every candidate that fitted).
    pub inadmissible: Option<String>,
    /// The rule's standing (`None`: not admitted by the rule).
    pub standing: Option<Standing>,
    pub accepted: bool,
}

/// The outcome of [`select_on_views`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewSelection<M> {
    pub units: Vec<usize>,
    pub fold_of: Vec<usize>,
    pub train_sets: Vec<Vec<usize>>,
    /// `baseline_misfits[view][i]`, as a trial's misfits.
    pub baseline_misfits: Vec<Vec<Option<f64>>>,
    /// One trial per candidate, in candidate order.
    pub trials: Vec<ViewTrial<M>>,
    /// Index into `trials` of the chosen candidate, if any.
    pub chosen: Option<usize>,
}

/// The comparison of two views' misfit vectors over the units both score,
/// in unit order (the step rule, [`compare`]).
pub fn compare_scored(before: &[Option<f64>], after: &[Option<f64>], fold_of: &[usize], folds: usize) -> Comparison {
    let (mut b, mut a, mut f) = (Vec::new(), Vec::new(), Vec::new());
    for ((x, y), g) in before.iter().zip(after).zip(fold_of) {
        if let (Some(x), Some(y)) = (x, y) {
            b.push(*x);
            a.push(*y);
            f.push(*g);
        }
    }
    compare(&b, &a, &f, folds)
}

/// [`compare`] over the units scored on both sides: a unit whose misfit is
/// NaN in `before` or `after` (the study has none for it, [`Study::score`])
/// is left out, as [`compare_scored`] leaves out a view's unscored units.
/// The comparison [`forward_select_from`] makes at every step; with no NaN it
/// is [`compare`] itself.
pub fn compare_where_scored(before: &[f64], after: &[f64], fold_of: &[usize], folds: usize) -> Comparison {
    let scored = |v: &[f64]| v.iter().map(|m| (!m.is_nan()).then_some(*m)).collect::<Vec<_>>();
    compare_scored(&scored(before), &scored(after), fold_of, folds)
}

/// One step of selection judged on several views: every candidate is fitted
/// on each distinct training set on top of that set's baseline
/// (`baselines[s]` on [`train_sets`]`(folds)[s]`), every held-out unit is
/// scored in every view with the fit of its fold, each view compared with the
/// baseline's ([`compare_scored`]); the rule gives each candidate its
/// standing, every candidate that fitted is asked its admissibility, and the
/// admissible admitted candidate of the highest standing is chosen (within a
/// tier the larger gain on the tier's view; ties: candidate order). Fits and
/// scores run in parallel and are collected in order: the result is the
/// same on any number of threads. `search.units_ascending` orders the units
/// as in [`forward_select_from`]; the pair step does not apply.
pub fn select_on_views<S, M>(
    study: &S,
    candidates: &[&dyn Candidate<S, M>],
    baselines: &[M],
    folds: &[Fold],
    rule: &dyn ViewRule,
    search: &Search,
) -> Result<ViewSelection<M>, SelectError>
where
    S: ViewStudy<M>,
    M: Clone + Send + Sync,
{
    let Layout { units, fold_of, train_sets, set_of_fold } = Layout::of(folds, search, baselines.len())?;
    let views = study.views();
    let score_all = |models: &[M]| -> Vec<Vec<Option<f64>>> {
        let cells: Vec<Option<f64>> = (0..views * units.len())
            .into_par_iter()
            .map(|k| {
                let (v, i) = (k / units.len(), k % units.len());
                study.score_view(&models[set_of_fold[fold_of[i]]], v, units[i])
            })
            .collect();
        cells.chunks(units.len().max(1)).map(<[Option<f64>]>::to_vec).collect()
    };
    let baseline_misfits = score_all(baselines);
    let tasks: Vec<(usize, usize)> =
        (0..candidates.len()).flat_map(|c| (0..train_sets.len()).map(move |s| (c, s))).collect();
    let fits: Vec<Result<M, String>> =
        tasks.par_iter().map(|&(c, s)| candidates[c].fit(study, &baselines[s], &train_sets[s])).collect();
    let mut trials: Vec<ViewTrial<M>> = (0..candidates.len())
        .map(|c| {
            let set = &fits[c * train_sets.len()..(c + 1) * train_sets.len()];
            let (fitted, error, misfits) = match set.iter().cloned().collect::<Result<Vec<M>, String>>() {
                Ok(models) => {
                    let ms = score_all(&models);
                    (models, None, ms)
                }
                // A failed fit scores an infinite misfit wherever the baseline scores.
                Err(e) => (
                    Vec::new(),
                    Some(e),
                    baseline_misfits.iter().map(|v| v.iter().map(|m| m.map(|_| f64::INFINITY)).collect()).collect(),
                ),
            };
            let comparisons: Vec<Comparison> =
                (0..views).map(|v| compare_scored(&baseline_misfits[v], &misfits[v], &fold_of, folds.len())).collect();
            let inadmissible = match error {
                None => candidates[c].inadmissible(study, baselines, &fitted),
                Some(_) => None,
            };
            let standing = if error.is_none() { rule.standing(c, &comparisons) } else { None };
            ViewTrial {
                candidate: c,
                id: candidates[c].id().to_string(),
                fitted,
                error,
                misfits,
                comparisons,
                inadmissible,
                standing,
                accepted: false,
            }
        })
        .collect();
    let rank = |t: &ViewTrial<M>| t.standing.map(|s| (s.tier, t.comparisons[s.by_view].gain));
    let mut chosen: Option<usize> = None;
    for (k, t) in trials.iter().enumerate() {
        let (Some(r), None) = (rank(t), &t.inadmissible) else { continue };
        let better = chosen.and_then(|c| rank(&trials[c])).is_none_or(|b| r.0 > b.0 || (r.0 == b.0 && r.1 > b.1));
        if better {
            chosen = Some(k);
        }
    }
    if let Some(k) = chosen {
        trials[k].accepted = true;
    }
    Ok(ViewSelection { units, fold_of, train_sets, baseline_misfits, trials, chosen })
}
