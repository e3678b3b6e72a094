//! The Stribeck law's fits: μ = μk + Δ·exp(−(Ω/vs)²) [+ c|Ω|] (Eq. 4-10's
//! velocity weakening as the diagnosis vocabulary states it, the law of
//! `rig_model::friction::stribeck_mu`), linear in (μk, Δ[, c]) at a fixed vs;
//! vs by a log grid on a subsample and Brent's search on every sample
//! ([`fit_stribeck`]), or by Brent's search alone in a basin already found
//! ([`fit_stribeck_near`], the composite's later passes).

use super::{FrictionFit, FrictionModel, SEARCH_EVERY, SlipData, linear_fit};
use rig_estimate::linear::Normal;
use rig_types::minimize::brent_min;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// The distinct |Ω| of a set of slip samples (by bit pattern, in order of
/// first appearance) and each sample's index among them. The rotor speed is
/// a centred difference of encoder angles, so it takes few values: on the
/// 37-case strided battery sample 2.4 % of the samples the Stribeck searches
/// evaluate carry a bit pattern not seen before in their data (issue 23,
/// docs/performance.md, eighteenth session). The decay g = exp(−(Ω/vs)²) of
/// a trial vs is computed once per distinct Ω and gathered per sample: the
/// same `stribeck_decay` of the same bits gives the same g, so every sum
/// over the samples, made in sample order as before, has the same bits.
struct Levels {
    values: Vec<f64>,
    index: Vec<u32>,
}

impl Levels {
    fn of(omega: &[f64]) -> Self {
        let mut seen: HashMap<u64, u32, BuildHasherDefault<BitsHasher>> =
            HashMap::with_capacity_and_hasher(omega.len().min(4096), Default::default());
        let mut values = Vec::new();
        let index = omega
            .iter()
            .map(|&w| {
                *seen.entry(w.to_bits()).or_insert_with(|| {
                    values.push(w);
                    (values.len() - 1) as u32
                })
            })
            .collect();
        Levels { values, index }
    }

    /// g = `stribeck_decay(Ω, vs)` of every distinct Ω, into `g`.
    fn decay_into(&self, vs: f64, g: &mut [f64]) {
        for (g, &w) in g.iter_mut().zip(&self.values) {
            *g = rig_model::friction::stribeck_decay(w, vs);
        }
    }
}

/// A hash of an f64's bits for [`Levels`] (a multiply–xorshift: the std
/// hasher's SipHash costs more per sample than the `exp` it saves).
#[derive(Default)]
struct BitsHasher(u64);

impl Hasher for BitsHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        let h = (self.0 ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 = h ^ (h >> 32);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

/// The weighted RSS of the Stribeck regression μ = μk + Δ g(Ω; vs) [+ c Ω]
/// at a given vs, as [`linear_solve`] computes it (the same products summed
/// in the same order, so the same bits), without its per-call row storage
/// and general sparse accumulation: the sums that do not involve g (Σw,
/// ΣwΩ, ΣwΩ², Σwμ, ΣwΩμ) are made once, and each vs costs one exp per
/// distinct Ω ([`Levels`]) and a few products per sample. The Stribeck
/// speed search evaluates it ~70 times per fit.
struct StribeckRss<'a> {
    d: &'a SlipData,
    viscous: bool,
    levels: Levels,
    /// √w and μ√w per sample.
    sw: Vec<f64>,
    y: Vec<f64>,
    /// Σ sw², Σ sw·(Ω sw), Σ (Ω sw)², Σ sw·y, Σ (Ω sw)·y.
    fixed: [f64; 5],
    /// g of every distinct Ω at the last vs (the residual pass reuses it).
    g: Vec<f64>,
}

impl<'a> StribeckRss<'a> {
    fn new(d: &'a SlipData, viscous: bool) -> Self {
        let sw: Vec<f64> = (0..d.len()).map(|i| d.w(i).sqrt()).collect();
        let y: Vec<f64> = (0..d.len()).map(|i| d.mu[i] * sw[i]).collect();
        let mut fixed = [0.0; 5];
        for i in 0..d.len() {
            let (v0, v2) = (1.0 * sw[i], d.omega[i] * sw[i]);
            fixed[0] += v0 * v0;
            fixed[1] += v0 * v2;
            fixed[2] += v2 * v2;
            fixed[3] += v0 * y[i];
            fixed[4] += v2 * y[i];
        }
        let levels = Levels::of(&d.omega);
        let g = vec![0.0; levels.values.len()];
        StribeckRss { d, viscous, levels, sw, y, fixed, g }
    }

    /// The RSS at `vs` (∞ when the normal equations are singular).
    fn at(&mut self, vs: f64) -> f64 {
        let d = self.d;
        self.levels.decay_into(vs, &mut self.g);
        let (g, index) = (&self.g, &self.levels.index);
        let (mut a01, mut a11, mut a12, mut b1) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..d.len() {
            let g = g[index[i] as usize];
            let (v0, v1, v2) = (1.0 * self.sw[i], g * self.sw[i], d.omega[i] * self.sw[i]);
            a01 += v0 * v1;
            a11 += v1 * v1;
            a12 += v1 * v2;
            b1 += v1 * self.y[i];
        }
        let [a00, a02, a22, b0, b2] = self.fixed;
        let ne = if self.viscous {
            Normal::from_row_major(3, &[a00, a01, a02, a01, a11, a12, a02, a12, a22], vec![b0, b1, b2])
        } else {
            Normal::from_row_major(2, &[a00, a01, a01, a11], vec![b0, b1])
        };
        let Some(p) = ne.solve() else { return f64::INFINITY };
        let mut rss = 0.0;
        for i in 0..d.len() {
            let g = g[index[i] as usize];
            let fit = if self.viscous { 1.0 * p[0] + g * p[1] + d.omega[i] * p[2] } else { 1.0 * p[0] + g * p[1] };
            let e = d.mu[i] - fit;
            rss += d.w(i) * e * e;
        }
        rss
    }
}

/// μ = μk + Δ exp(−(Ω/vs)²) [+ c|Ω| when `with_viscous`]: linear in (μk, Δ[, c])
/// for fixed vs; vs by a log grid then Brent's refinement; covariance
/// from the numerical Jacobian.
pub fn fit_stribeck(d: &SlipData, with_viscous: bool) -> Option<FrictionFit> {
    let grid: Vec<f64> = (0..41).map(|j| 0.05 * 10f64.powf(j as f64 * 3.0 / 40.0)).collect();
    // The grid on a subsample locates the basin; Brent's method on every sample.
    let ds = d.subsample(SEARCH_EVERY);
    let mut coarse = StribeckRss::new(&ds, with_viscous);
    let (best, _) = grid.iter().enumerate().map(|(j, &v)| (j, coarse.at(v))).min_by(|a, b| a.1.total_cmp(&b.1))?;
    let lo = grid[best.saturating_sub(1)].ln();
    let hi = grid[(best + 1).min(grid.len() - 1)].ln();
    stribeck_in(d, with_viscous, lo, hi)
}

/// Decades per step of [`fit_stribeck`]'s log grid of vs (41 points over 0.05–50 rad/s, 3/40 decade apart).
const STRIBECK_GRID_STEP_LN10: f64 = 3.0 / 40.0;

/// [`fit_stribeck`] started in a known basin: Brent's search on the bracket
/// of the same width the grid gives (one grid step either side) around
/// `vs_near`, without the grid. The composite's later passes refit the speed
/// law on a target that only the modulations' re-estimation changed (by a
/// fraction of a percent per pass), so the basin its first pass's grid found
/// is the one to refine; the grid's 41 subsample evaluations (≈ 10 passes
/// over every sample, a third of the fit) are saved. The search is the same
/// (ln vs to 10⁻⁶); where the optimum lies inside both brackets it is found
/// to that tolerance either way. Off the grid's 0.05–50 rad/s range the
/// cold fit runs instead.
pub fn fit_stribeck_near(d: &SlipData, with_viscous: bool, vs_near: f64) -> Option<FrictionFit> {
    let h = STRIBECK_GRID_STEP_LN10 * std::f64::consts::LN_10;
    let lv = vs_near.ln();
    if !lv.is_finite() || lv - h < 0.05f64.ln() || lv + h > 50f64.ln() {
        return fit_stribeck(d, with_viscous);
    }
    stribeck_in(d, with_viscous, lv - h, lv + h)
}

/// Brent's search for ln vs on [lo, hi], then the linear fit and the covariance at it.
fn stribeck_in(d: &SlipData, with_viscous: bool, lo: f64, hi: f64) -> Option<FrictionFit> {
    let ncol = if with_viscous { 3 } else { 2 };
    let mut fine = StribeckRss::new(d, with_viscous);
    // The decay g of every sample at the lowest RSS Brent has seen, which
    // is the point it returns (its x, replaced by a trial whose RSS is not
    // higher): the linear fit and the covariance at the returned vs read
    // these same numbers (each was an `exp` per sample again, two passes
    // of the ≈ 20 a search makes; issue 23). Should the returned point not
    // be the one kept, g is computed at it.
    let mut kept: Option<(f64, f64)> = None;
    let mut g = vec![0.0; fine.g.len()];
    // ln vs to 10⁻⁶ (golden section's 25 steps on this bracket reached 2·10⁻⁶).
    let lv = brent_min(lo, hi, 1e-6, 27, |lv| {
        let rss = fine.at(lv.exp());
        if kept.is_none_or(|k| rss <= k.1) {
            kept = Some((lv, rss));
            std::mem::swap(&mut g, &mut fine.g);
        }
        rss
    });
    let vs = lv.exp();
    if kept.is_none_or(|k| k.0.to_bits() != lv.to_bits()) {
        fine.levels.decay_into(vs, &mut g);
    }
    let index = &fine.levels.index;
    let (p, _, rss) = linear_fit(d, ncol, |i, r| {
        r[0] = 1.0;
        r[1] = g[index[i] as usize];
        if with_viscous {
            r[2] = d.omega[i];
        }
    })?;
    let (mu_k, dmu) = (p[0], p[1]);
    let c = if with_viscous { p[2] } else { 0.0 };
    // Gauss–Newton covariance over (μk, Δ, vs[, c]).
    let np = ncol + 1;
    let mut ne = Normal::new(np);
    for i in 0..d.len() {
        let g = g[index[i] as usize];
        let dg_dvs = g * 2.0 * d.omega[i].powi(2) / vs.powi(3);
        let sw = d.w(i).sqrt();
        if with_viscous {
            ne.add_sparse(&[(0, sw), (1, sw * g), (2, sw * dmu * dg_dvs), (3, sw * d.omega[i])], 0.0);
        } else {
            ne.add_sparse(&[(0, sw), (1, sw * g), (2, sw * dmu * dg_dvs)], 0.0);
        }
    }
    let var = rss / (d.len().saturating_sub(np).max(1)) as f64;
    let inv = ne.inverse();
    let se = |a: usize, b: usize| inv.as_ref().map(|m| m[a * np + b] * var).unwrap_or(f64::NAN);
    let se_mu_s = (se(0, 0) + se(1, 1) + 2.0 * se(0, 1)).max(0.0).sqrt();
    let mut params = vec![
        ("mu_static", mu_k + dmu, se_mu_s),
        ("mu_kinetic", mu_k, se(0, 0).max(0.0).sqrt()),
        ("stribeck_speed_rad_s", vs, se(2, 2).max(0.0).sqrt()),
    ];
    if with_viscous {
        params.push(("viscous_per_rad_s", c, se(3, 3).max(0.0).sqrt()));
    }
    Some(FrictionFit {
        model: FrictionModel::Stribeck { mu_k, mu_s: mu_k + dmu, vs, c },
        phases: vec![],
        params,
        rss_w: rss,
        n: d.len(),
        k: np,
        converged: inv.is_some(),
        scan: vec![],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::friction::tests::synth;
    use crate::friction::{fit_coulomb, linear_solve};

    #[test]
    fn stribeck_law_is_recovered() {
        let d = synth(4, |_, _, _, w| 0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64));
        let f = fit_stribeck(&d, false).unwrap();
        let FrictionModel::Stribeck { mu_k, mu_s, vs, .. } = f.model else { panic!() };
        assert!((mu_k - 0.4).abs() < 1e-3 && (mu_s - 0.6).abs() < 5e-3 && (vs - 2.0).abs() < 0.05, "{:?}", f.model);
        // The Coulomb baseline is much worse on the same data.
        assert!(fit_coulomb(&d).rss_w > 10.0 * f.rss_w);
    }

    /// The RSS of a trial vs from the decay of each distinct |Ω| gathered per
    /// sample is `linear_solve`'s, which evaluates the decay of every sample:
    /// the same bits, with and without the viscous column, on speeds taken
    /// as the prepared data takes them (a centred difference of encoder
    /// angles, so many samples share a bit pattern) and at trial speeds
    /// where the decay underflows for some samples and not for others.
    #[test]
    fn the_rss_from_distinct_speeds_is_the_rss_of_every_sample() {
        let mut d = synth(3, |_, _, _, w| 0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 1.3f64) + 0.002 * w);
        let ticks: Vec<i64> =
            d.phi.iter().map(|&p| (p * 2048.0 / (2.0 * std::f64::consts::PI)).round() as i64).collect();
        let phi = rig_types::sensor::ticks_to_rad(&ticks, 2048);
        let mut omega = rig_types::sensor::central_difference_rad_s(&d.t, &phi, 10);
        omega.iter_mut().for_each(|w| *w = w.abs());
        d.omega = std::sync::Arc::new(omega);
        let levels = Levels::of(&d.omega);
        assert!(levels.values.len() < d.len() / 4, "{} distinct speeds of {}", levels.values.len(), d.len());
        assert!(
            levels.index.iter().zip(d.omega.iter()).all(|(&l, w)| levels.values[l as usize].to_bits() == w.to_bits())
        );
        for viscous in [false, true] {
            let mut rss = StribeckRss::new(&d, viscous);
            for vs in [0.02, 0.05, 0.3, 0.9, 1.3, 2.7, 11.0, 48.0] {
                let each = linear_solve(&d, 2 + usize::from(viscous), |i, r| {
                    r[0] = 1.0;
                    r[1] = rig_model::friction::stribeck_decay(d.omega[i], vs);
                    if viscous {
                        r[2] = d.omega[i];
                    }
                })
                .map_or(f64::INFINITY, |s| s.1);
                assert_eq!(rss.at(vs).to_bits(), each.to_bits(), "vs {vs}, viscous {viscous}");
            }
        }
    }

    /// The linear fit and the covariance at the speed Brent returns read the
    /// decay kept from its search: the same numbers, to the bit, as the
    /// decay computed at that speed anew (with and without the viscous column).
    #[test]
    fn the_fit_at_the_returned_speed_is_the_fit_with_its_decay_anew() {
        let d = synth(3, |_, _, _, w| 0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 1.3f64) + 0.002 * w);
        for with_viscous in [false, true] {
            let f = fit_stribeck(&d, with_viscous).unwrap();
            let FrictionModel::Stribeck { mu_k, mu_s, vs, c } = f.model else { panic!() };
            let (p, _, rss) = linear_fit(&d, 2 + usize::from(with_viscous), |i, r| {
                r[0] = 1.0;
                r[1] = rig_model::friction::stribeck_decay(d.omega[i], vs);
                if with_viscous {
                    r[2] = d.omega[i];
                }
            })
            .unwrap();
            let c_anew = if with_viscous { p[2] } else { 0.0 };
            let bits = |v: [f64; 4]| v.map(f64::to_bits);
            assert_eq!(
                bits([mu_k, mu_s, c, f.rss_w]),
                bits([p[0], p[0] + p[1], c_anew, rss]),
                "viscous {with_viscous}"
            );
            assert!(f.converged && f.params.iter().all(|x| x.2.is_finite() && x.2 > 0.0), "{:?}", f.params);
        }
    }
}
