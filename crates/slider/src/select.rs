//! Forward selection over folds, behind a small trait that maps one-to-one
//! onto "fit on a training fold, score on a held-out fold" ([`FoldCandidate`]):
//! the folds are the caller's, a step keeps the candidate with the lowest
//! mean held-out misfit when it lowers the current model's by the selection
//! rule's relative gain, and the gain is reported with its spread over the
//! held-out runs ([`Gain`]). The slider's models implement the trait in
//! `study.rs`; a workspace-wide selection engine with the same contract can
//! take this module's place without touching them.

use rayon::prelude::*;

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

/// The gain of a candidate over the current model, run by run held out:
/// misfit before − misfit after.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gain {
    pub mean: f64,
    /// Sample standard deviation of the per-run gains (0 for one run).
    pub sd: f64,
    pub runs: usize,
    /// 1 − mean after / mean before.
    pub relative: f64,
}

/// The gain of `after` over `before` (the same held-out runs, in the same order).
pub fn gain(before: &[(usize, f64)], after: &[(usize, f64)]) -> Gain {
    assert_eq!(before.len(), after.len(), "the same held-out runs");
    let d: Vec<f64> = before
        .iter()
        .zip(after)
        .map(|(b, a)| {
            assert_eq!(b.0, a.0, "the same held-out runs");
            b.1 - a.1
        })
        .collect();
    let n = d.len();
    let mean = d.iter().sum::<f64>() / n.max(1) as f64;
    let sd = if n > 1 { (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt() } else { 0.0 };
    let m_before = before.iter().map(|h| h.1).sum::<f64>() / n.max(1) as f64;
    Gain { mean, sd, runs: n, relative: if m_before > 0.0 { mean / m_before } else { 0.0 } }
}

/// One forward step: the index of the candidate (of `means`) with the lowest
/// mean held-out misfit, when it is at most (1 − `min_relative_gain`) × `current`.
pub fn step(current: f64, means: &[f64], min_relative_gain: f64) -> Option<usize> {
    (0..means.len())
        .filter(|&i| means[i].is_finite())
        .min_by(|&a, &b| means[a].total_cmp(&means[b]))
        .filter(|&i| means[i] <= (1.0 - min_relative_gain) * current)
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
        let g = gain(&e.heldout, &[(0, 1.0), (1, 1.5), (2, 2.5)]);
        assert!((g.mean - 4.0 / 3.0).abs() < 1e-12 && (g.relative - 4.0 / 9.0).abs() < 1e-12, "{g:?}");
        assert!((g.sd - (4.0f64 / 3.0).sqrt()).abs() < 1e-12, "{g:?}");
        // The rule: the best candidate, kept only with enough gain.
        assert_eq!(step(3.0, &[2.9, 2.0, f64::NAN], 0.05), Some(1));
        assert_eq!(step(3.0, &[2.9, 2.86], 0.05), None);
    }
}
