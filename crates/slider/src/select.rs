//! Forward selection over folds, behind a small trait that maps one-to-one
//! onto "fit on a training fold, score on a held-out fold" ([`FoldCandidate`]):
//! the folds are the caller's, and a step is judged by the workspace's one
//! step rule ([`rig_types::select::compare`] and
//! [`rig_types::contract::SelectionRule::admits`]: the relative gain of the
//! RMS held-out misfit and the paired t of ln(M_before/M_after)). The slider's models implement the trait in
//! `study.rs`; a workspace-wide selection engine with the same contract can
//! take this module's place without touching them.

use rayon::prelude::*;
pub use rig_types::select::Comparison;
pub use rig_types::select::best_of as best;
use rig_types::select::compare;

/// A fold: runs to fit on, runs to score (indices into the caller's runs).
#[derive(Debug, Clone, PartialEq)]
pub struct Fold {
    pub train: Vec<usize>,
    pub test: Vec<usize>,
}

/// A candidate of a forward selection.
pub trait FoldCandidate: Sync {
    /// What a fit returns (parameters, training misfit).
    type Fit: Clone + Send;
    /// Fits on the runs `train`.
    fn fit(&self, train: &[usize]) -> Self::Fit;
    /// The misfit of `fit` at each run of `test`, in its order.
    fn score(&self, fit: &Self::Fit, test: &[usize]) -> Vec<f64>;
}

/// A candidate's held-out record over the folds.
#[derive(Debug, Clone)]
pub struct Evaluation<F> {
    /// One fit per fold, in the folds' order.
    pub fits: Vec<F>,
    /// (run, held-out misfit), sorted by run; a run held out by two folds appears twice.
    pub heldout: Vec<(usize, f64)>,
    pub mean: f64,
}

/// Fits `c` on every fold's training runs and scores it on its held-out ones.
pub fn evaluate<C: FoldCandidate>(c: &C, folds: &[Fold]) -> Evaluation<C::Fit> {
    type Scored<F> = (F, Vec<(usize, f64)>);
    let per: Vec<Scored<C::Fit>> = folds
        .par_iter()
        .map(|f| {
            let fit = c.fit(&f.train);
            let s = c.score(&fit, &f.test);
            (fit, f.test.iter().copied().zip(s).collect())
        })
        .collect();
    let mut fits = Vec::with_capacity(per.len());
    let mut heldout = Vec::new();
    for (fit, h) in per {
        fits.push(fit);
        heldout.extend(h);
    }
    heldout.sort_by_key(|h| h.0);
    let mean = heldout.iter().map(|h| h.1).sum::<f64>() / heldout.len().max(1) as f64;
    Evaluation { fits, heldout, mean }
}

/// A candidate's held-out record compared with the current model's by the
/// one step rule of the workspace ([`rig_types::select::compare`]: the
/// overall misfit √(mean M²) over the held-out runs, its relative gain, the
/// spread of each fold's own gain and the paired t of ln(M_before/M_after)),
/// the folds being the ones both records were scored over.
pub fn comparison(before: &[(usize, f64)], after: &[(usize, f64)], folds: &[Fold]) -> Comparison {
    assert_eq!(before.len(), after.len(), "the same held-out runs");
    let fold_of: Vec<usize> = before
        .iter()
        .zip(after)
        .map(|(b, a)| {
            assert_eq!(b.0, a.0, "the same held-out runs");
            folds.iter().position(|f| f.test.contains(&b.0)).expect("a fold holds the run out")
        })
        .collect();
    let ms = |h: &[(usize, f64)]| h.iter().map(|x| x.1).collect::<Vec<f64>>();
    compare(&ms(before), &ms(after), &fold_of, folds.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A candidate that predicts a constant: fitted as the mean of its training values.
    struct Mean<'a>(&'a [f64]);
    impl FoldCandidate for Mean<'_> {
        type Fit = f64;
        fn fit(&self, train: &[usize]) -> f64 {
            train.iter().map(|&i| self.0[i]).sum::<f64>() / train.len() as f64
        }
        fn score(&self, fit: &f64, test: &[usize]) -> Vec<f64> {
            test.iter().map(|&i| (self.0[i] - fit).abs()).collect()
        }
    }

    #[test]
    fn leave_one_out_scores_each_run_with_the_others_fit() {
        let y = [1.0, 2.0, 6.0];
        let folds: Vec<Fold> =
            (0..3).map(|k| Fold { train: (0..3).filter(|&i| i != k).collect(), test: vec![k] }).collect();
        let e = evaluate(&Mean(&y), &folds);
        assert_eq!(e.fits, [4.0, 3.5, 1.5]);
        assert_eq!(e.heldout, [(0, 3.0), (1, 1.5), (2, 4.5)]);
        assert!((e.mean - 3.0).abs() < 1e-12);
        // The engine's rule on these records: RMS misfit √10.5 → √(8.5/3), paired t of ln(before/after).
        let c = comparison(&e.heldout, &[(0, 1.0), (1, 1.5), (2, 2.5)], &folds);
        assert!((c.before - ((9.0 + 2.25 + 20.25) / 3.0f64).sqrt()).abs() < 1e-12, "{c:?}");
        assert!((c.after - ((1.0 + 2.25 + 6.25) / 3.0f64).sqrt()).abs() < 1e-12, "{c:?}");
        let d = [3.0f64.ln(), 0.0, 1.8f64.ln()];
        let mean = d.iter().sum::<f64>() / 3.0;
        let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
        assert!((c.t - mean / (sd / 3f64.sqrt())).abs() < 1e-9, "{c:?}");
        assert_eq!(best(&[c, Comparison { after: f64::NAN, gain: 2.0, ..c }]), Some(0));
    }
}
