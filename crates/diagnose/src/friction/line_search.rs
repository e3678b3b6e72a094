//! The stop rule and the line search's start shared by the Gauss–Newton
//! fits (`fit_sine` here, `composite::refine_speed_time`): how close to
//! stationary a step has to be, in standard errors ([`near_stationary`]),
//! when the joint block's realised decrease says it crawls ([`crawling`]),
//! and where the next step's halving search begins ([`LineStart`]). No
//! thesis equation: these are numerical rules, stated with their reasons.

use rig_estimate::linear::Normal;

/// Stop rule of the sine fits' Gauss–Newton ([`fit_sine`],
/// `composite::refine_speed_time`): the step δ = (JᵀJ)⁻¹Jᵀr predicts an RSS
/// decrease δᵀJᵀr = (θ* − θ)ᵀ JᵀJ (θ* − θ) to the stationary point θ* of the
/// local quadratic model, i.e. σ² times the squared distance to it in the
/// parameters' own standard errors (the covariance is σ²(JᵀJ)⁻¹, σ² =
/// RSS/(n − p)). Once that distance is below [`GN_STOP_SE`] standard errors
/// the step is taken and the iteration ends: what is left moves every
/// parameter, and every combination of them, by less than a tenth of its
/// standard error (less still in the correlated-residual errors reported,
/// which are √τ ≥ 1 times these), far inside what any comparison of the
/// selection resolves. The relative-RSS rule (10⁻¹⁰) kept iterating where
/// Gauss–Newton converges only linearly — a modulation far below the noise
/// (large residuals) or absent, whose frequency and phases the data do not
/// pin: up to 30 iterations over ≈ 400 000 slip samples per fit on every
/// unmodulated set of a full-protocol campaign, each step a few 10⁻⁴
/// standard errors.
pub(crate) fn near_stationary(step: &[f64], ne: &Normal, rss: f64, n: usize) -> bool {
    let predicted = step.iter().zip(&ne.atb).map(|(s, g)| s * g).sum::<f64>();
    let var = rss / n.saturating_sub(step.len()).max(1) as f64;
    predicted <= GN_STOP_SE * GN_STOP_SE * var
}

/// [`near_stationary`]'s distance, in standard errors.
pub(crate) const GN_STOP_SE: f64 = 0.1;

/// Stop rule on the realised decrease of the joint block's Gauss–Newton
/// (`composite::refine_speed_time`): the fit ends once its last
/// [`GN_CRAWL_ITERS`] accepted steps together lowered the weighted RSS by at
/// most `GN_STOP_SE²·σ²` (σ² = RSS/(n − p)) — the decrease
/// [`near_stationary`] accepts as the end when one step predicts it, here
/// realised over three. Where Gauss–Newton converges only linearly (a
/// speed law and a time modulation the data barely separate: the
/// velocity-weakening rung's joint block gained 0.23 → 6·10⁻⁴ σ² per
/// iteration at a ratio ≈ 0.9 and ran all 30 unconverged, the
/// time-modulation rung's ≈ 10⁻³ σ² per iteration from the fourth on, 28 %
/// and 18 % of those cases' sine and joint sample evaluations; sixteenth
/// session) its predicted decrease stays above the stop rule's while each
/// step realises a fraction of it. At a ratio ρ per iteration the steps
/// still to come would gain ≈ ρ/(1 − ρ) times the last one, ≈ 0.03 σ² at
/// ρ = 0.9: a distance of ≈ 0.2 standard errors in the parameters' own
/// metric, below what any comparison of the selection resolves (its
/// rules read RSS differences of whole σ² and more, and errors inflated
/// by √τ ≥ 1). Three iterations, not one: a single short step (a line
/// search that had to halve) is no evidence of a crawl.
pub(crate) fn crawling(gains: &[f64], rss: f64, n: usize, p: usize) -> bool {
    if gains.len() < GN_CRAWL_ITERS {
        return false;
    }
    let var = rss / n.saturating_sub(p).max(1) as f64;
    gains[gains.len() - GN_CRAWL_ITERS..].iter().sum::<f64>() <= GN_STOP_SE * GN_STOP_SE * var
}

/// [`crawling`]'s window, in accepted iterations.
pub(crate) const GN_CRAWL_ITERS: usize = 3;

/// Where a Gauss–Newton (or Newton) line search starts: the full step, or
/// twice the fraction of it the last accepted step of the same kind took,
/// whichever is smaller (the search then halves as before, up to 12 times,
/// and accepts the first fraction that does not raise the RSS). A fit
/// whose steps are accepted whole, or at half, starts every search at the
/// full step, as before; one that needed a quarter of its step or less
/// (a modulation the data barely pin, whose quadratic model overshoots on
/// every iteration: 30 iterations of 4–9 trials each on the 37-case
/// sample's worst fits, 42 % of the sine fits' RSS passes over 5 % of the
/// calls) starts the next search near the fraction that worked, and grows
/// back by doubling. The directions and the stop rules
/// ([`near_stationary`], the relative RSS) are unchanged; where the
/// search starts lower it accepts a shorter step than the first trial
/// that would have passed, so such fits follow another path to the same
/// stop rule (issue 23).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LineStart {
    pub(crate) lambda: f64,
}

impl Default for LineStart {
    fn default() -> Self {
        LineStart { lambda: 1.0 }
    }
}

impl LineStart {
    /// The search accepted `lambda` of its step.
    pub(crate) fn accepted(&mut self, lambda: f64) {
        self.lambda = (2.0 * lambda).min(1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crawling_reads_the_last_three_gains_against_a_hundredth_of_sigma2() {
        // σ² = 100 / (104 − 4) = 1: the threshold is 0.01.
        assert!(!crawling(&[0.004, 0.004], 100.0, 104, 4), "two iterations are no window");
        assert!(crawling(&[5.0, 0.004, 0.003, 0.003], 100.0, 104, 4));
        assert!(!crawling(&[0.004, 0.004, 0.003, 0.0031], 100.0, 104, 4));
        // The same gains against a noise ten times smaller are progress.
        assert!(!crawling(&[5.0, 0.004, 0.003, 0.003], 10.0, 104, 4));
    }
}
