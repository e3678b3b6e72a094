//! The cause from the literature, what the study could and could not show
//! of it, what no candidate reached, and what the search's budget says
//! (slider.md's prose).

use super::*;
use crate::study::Measured;

/// What the literature says a Coulomb law misses on paper on paper, and what
/// this study could and could not show of it (the text of slider.md).
pub(super) const CAUSE: &str = "The cause, from the literature on paper on paper (Heslot, Baumberger, Perrin, Caroli & Caroli, \
Phys. Rev. E 49, 4973 (1994); Baumberger & Caroli, Adv. Phys. 55, 279 (2006)): the interface has a memory. At rest its \
static threshold grows with the time stuck, μs(t) ≈ μs0 + B ln(1 + t/τ) (contacts age); sliding, the friction relaxes over \
a length Dc of about a micrometre; before a slip the slider creeps. A Coulomb law has no memory: it sticks rigidly \
(no creep), its threshold does not depend on the stick time, and it stick-slips at any stiffness. Rate-and-state \
friction (Dieterich–Ruina) turns this into a stability boundary in (k, V): below k_c = m g (b − a)/Dc the sliding is \
unstable (stick-slip; creep-dominated near k_c), above it the slider slides steadily, and at high V inertia turns the \
bifurcation into nearly harmonic oscillations near 2π√(m/k) (the inertial regime). Heslot et al. 1994 measured the memory \
length D0 at about a micrometre on paper and the logarithmic ageing of the static threshold; their heuristic model is the \
rate-and-state law with an inertia term, whose Hopf frequency Ω² = k/(m + N a D0/V²) gives the creep regime at low V (the \
interface term dominates) and the inertial one at high V (m dominates). The candidates here are three forms of that \
memory (static ageing with a rate-strengthening kinetic law; rate-and-state with the ageing law, started also on a \
creeping calibration run's Hopf point; Heslot et al.'s law with the speed and the age cut off at small values, \
`heslot_creep`, whose speed term vanishing at rest gives a static threshold), one of the interface's heterogeneity \
(`track_threshold`: Coulomb whose threshold varies along the paper, σ over a correlation length ℓ — a stiff spring \
follows the track, creeping, and slips only where the threshold falls faster than k/(m g) per metre; a soft one \
stick-slips over it) and three set-ups (an \
effective mass, a compliance in series, a scaled spring), fitted by simulation on the calibration runs and chosen by \
forward selection on the held-out runs.";

/// The two failures a Coulomb law on the stated set-up cannot mend, with the
/// records' numbers: where the slider creeps (the load rate in the loading
/// phase below L: the slider moves at (1 − rate/L) V while the force rises),
/// what each rate-and-state fit puts its critical stiffness
/// k_c = m g (b − a)/Dc at (Baumberger & Caroli 2006: steady sliding above,
/// creep just below, stick-slip well below), and how the set-up the inertial
/// periods point to (`effective_mass`) fares run by run held out.
pub(super) fn causes(s: &Study) -> String {
    let mut out = String::from("## The causes, from the records\n\n");
    let weight_n = s.params.mass_kg * s.params.gravity_m_s2;
    for r in s.runs.iter().filter(|r| r.features.regime == Regime::Creep) {
        let f = &r.features;
        let _ = writeln!(
            out,
            "- {} creeps: through the loading phase the force rises at {:.2} ± {:.2} L (the slider moving at about {:.0} % of V \
             on the stated spring), stick fraction {:.2}, against {} where the slider rests. A Coulomb slider rests until it \
             slips at any stiffness; rate and state creeps near its critical stiffness. Its period, {:.4} s, is {:.1} T0 \
             (the mass does not set it) and P V = {:.1} µm, of order ten times the memory length D0 ≈ 1 µm of paper (the \
             interface sets it: near the boundary rate and state oscillates at ω = (V/Dc) √((b − a)/a), so \
             Dc √(a/(b − a)) = P V/2π = {:.2} µm); a slip gives back {:.1} µm (drop × m g/k), the rest of the drive's \
             travel is crept; the cycles spread (period sd {:.0} % of its median): a relaxation past the Hopf point, \
             not the harmonic oscillation at it.",
            r.name,
            f.load_rate.median,
            f.load_rate.sd,
            100.0 * (1.0 - f.load_rate.median),
            f.stick_fraction.median,
            s.runs
                .iter()
                .filter(|q| q.features.regime == Regime::StickSlip)
                .map(|q| format!("{} ({:.2} L)", q.name, q.features.load_rate.median))
                .collect::<Vec<_>>()
                .join(", "),
            f.period_s.median,
            f.period_s.median / f.natural_period_s,
            1e6 * f.period_s.median * r.drive_speed_um_s * 1e-6,
            f.period_s.median * r.drive_speed_um_s / (2.0 * std::f64::consts::PI),
            1e6 * f.drop.median * weight_n / r.stiffness_n_m,
            100.0 * f.period_s.sd / f.period_s.median
        );
    }
    for c in s.candidates.iter().filter(|c| matches!(c.model.friction, Candidate::RateState | Candidate::RateStateSlip))
    {
        let kc: Vec<String> = c
            .fold_fits
            .iter()
            .map(|f| {
                let ks = distinct(f.train.iter().map(|&i| s.runs[i].stiffness_n_m));
                let dc_at_bound = f.at_bounds.contains(&"dc_m");
                format!(
                    "fitted on k = {ks:?} N/m: k_c = {:.0} N/m (b − a = {:.2e}, Dc = {:.2} µm{})",
                    weight_n * f.params[2] / f.params[3],
                    f.params[2],
                    1e6 * f.params[3],
                    if dc_at_bound { ", at its bound" } else { "" }
                )
            })
            .collect();
        let _ = writeln!(
            out,
            "- {}: k_c = m g (b − a)/Dc {}. Runs that all stick-slip bound k_c from below only (k_c above their \
             stiffness); the creep that places it is at the stiffer spring, so a fit that has not seen that spring \
             cannot place it.",
            c.model.id(),
            kc.join("; ")
        );
    }
    for b in &s.boundary_scans {
        let r = &s.runs[b.run];
        let cases: Vec<String> = b
            .scans
            .iter()
            .map(|(a, dc, regimes)| {
                let first_unstable = regimes.iter().find(|x| x.1 != Regime::SteadySliding);
                let creeps = regimes.iter().filter(|x| x.1 == Regime::Creep).count();
                format!(
                    "a = {a}, Dc = {:.1} µm: {}{}",
                    1e6 * dc,
                    first_unstable.map_or("steady throughout".to_string(), |x| format!(
                        "{} from k_c = {:.3} k",
                        x.1.label(),
                        x.0
                    )),
                    if creeps > 0 { format!(" ({creeps} of 13 creep)") } else { String::new() }
                )
            })
            .collect();
        let _ = writeln!(
            out,
            "- Does rate and state creep at {} at all? Its critical stiffness m g (b − a)/Dc scanned from 0.85 to 1.15 k in \
             steps of 0.025 k, simulated and read by the one feature function: {}. {}",
            r.name,
            cases.join("; "),
            if b.scans.iter().all(|(_, _, v)| v.iter().all(|x| x.1 != Regime::Creep)) {
                "At every (a, Dc) scanned it goes from steady sliding straight to stick-slip, with no creep band wider than the \
                 step: a fit of this law has no creep to find there, calibrated or held out — within the scanned range what \
                 it misses is in the law as simulated, not in the fit."
            } else {
                "It creeps in a band of the scan: the law can give this regime (the last case: a direct effect a several \
                 times b − a, which the Hopf period asks for)."
            }
        );
        if let Some((x, at)) = &b.creeping_law {
            let others: Vec<String> = at
                .iter()
                .map(|(j, f, m)| {
                    format!(
                        "{} measured {} → {} (period {:.4} s against {:.4} s, drop {:.3} against {:.3}; misfit {:.2})",
                        s.runs[*j].name,
                        s.runs[*j].features.regime.label(),
                        f.regime.label(),
                        f.period_s.median,
                        s.runs[*j].features.period_s.median,
                        f.drop.median,
                        s.runs[*j].features.drop.median,
                        m
                    )
                })
                .collect();
            let mean = at.iter().map(|a| a.2).sum::<f64>() / at.len().max(1) as f64;
            let _ = writeln!(
                out,
                "- What creeping at {} costs on the same spring: the first law of the scan that creeps there (μ0 = {:.3}, \
                 a = {:.4}, b − a = {:.4}, Dc = {:.1} µm), simulated at every run of k = {} N/m: {}; mean misfit {:.2}. \
                 The fit of `rate_state_ageing` on these runs (it starts from this Hopf point too, \
                 `rig_slider::fit::hopf_starts`) keeps the lower misfit elsewhere.",
                r.name,
                x[0],
                x[1],
                x[2],
                1e6 * x[3],
                r.stiffness_n_m,
                others.join("; "),
                mean
            );
        }
    }
    for (i, r) in s.runs.iter().enumerate().filter(|(_, r)| r.features.regime == Regime::Creep) {
        let _ = writeln!(out, "- {}", creep_resolution(s, i, r));
    }
    let base = &s.candidates[0];
    let light = Model { friction: Candidate::Coulomb, setup: SetupCandidate::EffectiveMass };
    if let Some(c) = s.candidates.iter().find(|c| c.model == light) {
        let runs: Vec<String> = c
            .heldout
            .iter()
            .zip(&base.heldout)
            .map(|((i, m, f), (_, m0, f0))| {
                let r = &s.runs[*i];
                let regime = if f.regime != f0.regime {
                    format!(", predicted {} (was {})", f.regime.label(), f0.regime.label())
                } else {
                    String::new()
                };
                format!("{} {:.2} → {:.2}{regime}", r.name, m0, m)
            })
            .collect();
        let _ = writeln!(
            out,
            "- {} held out, run by run (misfit of Coulomb on the stated set-up → with the effective mass): {}.",
            c.model.id(),
            runs.join("; ")
        );
    }
    out
}

/// What the data can resolve of a creeping run `r` (index `i`): the
/// stiffnesses recorded at its drive speed on either side that do not creep
/// (the bracket the creep's onset lies in at that speed, one run on each
/// side), and which of the study's models predict its regime held out.
fn creep_resolution(s: &Study, i: usize, r: &Measured) -> String {
    let same_v: Vec<&Measured> = s
        .runs
        .iter()
        .filter(|q| q.drive_speed_um_s == r.drive_speed_um_s && q.features.regime != Regime::Creep)
        .collect();
    let nearest = |below: bool| {
        same_v
            .iter()
            .filter(|q| if below { q.stiffness_n_m < r.stiffness_n_m } else { q.stiffness_n_m > r.stiffness_n_m })
            .min_by(|a, b| {
                (a.stiffness_n_m - r.stiffness_n_m).abs().total_cmp(&(b.stiffness_n_m - r.stiffness_n_m).abs())
            })
            .map(|q| format!("{} ({})", q.name, q.features.regime.label()))
    };
    let lower = nearest(true).map_or_else(
        || "is not bounded from below (no softer spring recorded at this speed)".to_string(),
        |q| format!("lies between {q} and this run's {:.0} N/m", r.stiffness_n_m),
    );
    let upper = nearest(false).map_or_else(
        || "is not bounded (no stiffer spring recorded at this speed)".to_string(),
        |q| format!("lies between this run's {:.0} N/m and {q}", r.stiffness_n_m),
    );
    let mut by_regime: Vec<(Regime, Vec<String>)> = Vec::new();
    for c in &s.candidates {
        if let Some((_, _, f)) = c.heldout.iter().find(|h| h.0 == i) {
            match by_regime.iter_mut().find(|(g, _)| *g == f.regime) {
                Some((_, ids)) => ids.push(c.model.id()),
                None => by_regime.push((f.regime, vec![c.model.id()])),
            }
        }
    }
    let predicted: Vec<String> =
        by_regime.iter().map(|(g, ids)| format!("{} by {} ({})", g.label(), ids.len(), ids.join(", "))).collect();
    let creeping = by_regime.iter().find(|(g, _)| *g == Regime::Creep).map_or(0, |(_, ids)| ids.len());
    let count = if creeping == 0 { "none".to_string() } else { creeping.to_string() };
    format!(
        "What the data can resolve of {}'s creep: it is one run. At {:.0} µm/s the creep band's lower end {}, its upper \
         end {}: one run on each side of an end brackets it, it does not place it, and a law whose creep band starts \
         anywhere in the bracket fits the records alike — a threshold that varies along the paper (a stiff spring \
         follows it, creeping) and a memory law with a creep band there cannot be told apart, nor the creep of this \
         interface from that of another strip of paper. Held out, {count} of the study's {} models predict it: {}.",
        r.name,
        r.drive_speed_um_s,
        lower,
        upper,
        s.candidates.len(),
        predicted.join("; ")
    )
}

/// What no model reaches held out: per run, the checks every model fails,
/// with the measured value and the range of the predictions.
pub(super) fn unreached(s: &Study) -> String {
    let mut out = Vec::new();
    for (i, r) in s.runs.iter().enumerate() {
        let preds: Vec<&Features> =
            s.candidates.iter().filter_map(|c| c.heldout.iter().find(|h| h.0 == i).map(|h| &h.2)).collect();
        let all_fail = |check: &dyn Fn(&Bounds) -> Option<bool>| {
            let v: Vec<Option<bool>> = preds.iter().map(|f| check(&bounds(&r.features, f))).collect();
            !v.is_empty() && v.iter().all(|b| *b != Some(true)) && v.contains(&Some(false))
        };
        let range = |pick: fn(&Features) -> f64| {
            let v: Vec<f64> = preds.iter().map(|f| pick(f)).filter(|x| x.is_finite()).collect();
            let (lo, hi) = v.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            format!("{lo:.3}–{hi:.3}")
        };
        let f = &r.features;
        if preds.iter().all(|p| p.regime != f.regime) && !preds.is_empty() {
            let mut got: Vec<&str> = preds.iter().map(|p| p.regime.label()).collect();
            got.sort_unstable();
            got.dedup();
            out.push(format!("{}: regime {} (predicted: {})", r.name, f.regime.label(), got.join(", ")));
        }
        type Check = (&'static str, &'static str, fn(&Bounds) -> Option<bool>, fn(&Features) -> f64);
        let checks: [Check; 4] = [
            ("inertial period", " s", |b| b.inertial_period, |f| f.period_s.median),
            ("force at slip onset", "", |b| b.onset, |f| f.onset.median),
            ("period", " s", |b| b.period, |f| f.period_s.median),
            ("drop", "", |b| b.drop, |f| f.drop.median),
        ];
        for (name, unit, check, pick) in checks {
            if all_fail(&check) {
                out.push(format!("{}: {name} {:.4}{unit} (predicted {}{unit})", r.name, pick(f), range(pick)));
            }
        }
    }
    if out.is_empty() {
        return "- Every check is met held out by at least one model.".into();
    }
    format!("- What no model here reaches held out: {}.", out.join("; "))
}

/// slider.md's sentence on how far every fit searched: the fixed count, or
/// the convergence criterion (`fit_tolerance`, pipeline.toml), with the fits'
/// evaluations and how many the safeguard stopped.
pub(super) fn search_note(s: &Study) -> String {
    let p = &s.params;
    let fits: Vec<&crate::study::Fitted> = s.candidates.iter().flat_map(CandidateResult::fits).collect();
    let evals = fits.iter().map(|f| f.evals).sum::<usize>();
    if p.fit_tolerance <= 0.0 && p.fit_race_keep > 0 {
        return format!(
            "Every fit races Nelder–Mead (`rig_types::minimize::nelder_mead_race`) from the {} best-scored of its \
             starts: each start {} evaluations, then the {} best of them on to {} ({} fits, {evals} misfit \
             evaluations): fixed counts, not a convergence criterion (docs/findings.md, eighteenth session).",
            p.fit_starts,
            p.fit_evals,
            p.fit_race_keep,
            p.fit_race_evals,
            fits.len()
        );
    }
    if p.fit_tolerance <= 0.0 {
        return format!(
            "Every fit runs Nelder–Mead (`rig_types::minimize::nelder_mead`) for {} evaluations from each of the {} \
             best-scored of its starts, the better kept ({} fits, {evals} misfit evaluations): a fixed count, not a \
             convergence criterion. The fits are not converged at it, and the verdict moves with the search, under a \
             fixed count and under a convergence criterion alike (`fit_tolerance`, pipeline.toml; docs/findings.md, \
             fourteenth and fifteenth sessions).",
            p.fit_evals,
            p.fit_starts,
            fits.len()
        );
    }
    format!(
        "Every fit runs Nelder–Mead (`rig_types::minimize::nelder_mead_converged`) to a stated convergence criterion, \
         not an evaluation count (`fit_tolerance` = {tol}, pipeline.toml): until the simplex's calibration misfits lie \
         within {tol} of each other (the misfit's units) and its vertices within {tol} of each parameter's bound width, \
         then restarted from its best point with a fresh simplex until a restart lowers the misfit by no more than {tol} \
         (Press et al., Numerical Recipes 3rd ed., §10.5); from the candidate's starts in the order of their scores, at \
         least {}, on while a start lowers the best misfit by more than {tol}; the best kept. Here {} fits, {evals} \
         misfit evaluations; {} stopped by the safeguard of {} evaluations per start before converging.",
        p.fit_starts,
        fits.len(),
        fits.iter().filter(|f| !f.converged).count(),
        p.fit_evals,
        tol = p.fit_tolerance
    )
}
