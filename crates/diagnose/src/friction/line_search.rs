//! The stop rule and the line search's start shared by the Gauss–Newton
//! fits (`fit_sine` here, `composite::refine_speed_time`): how close to
//! stationary a step has to be, in standard errors ([`near_stationary`]),
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
