//! The composite module's tests (split from `mod.rs`, which passed 700 lines).

use super::*;

pub(super) fn synth(runs: usize, law: impl Fn(usize, f64, f64, f64) -> f64) -> SlipData {
    crate::friction::tests::synth_noisy(runs, 7, 0.003, law)
}

/// The sets that share one memo of the data (the cold Stribeck fit, the
/// angle block's sin and cos by order) get the models they get fitted
/// alone, bit for bit, whichever of them fills the memo first.
#[test]
fn a_shared_cold_stribeck_fit_is_each_fit_alone() {
    let d = synth(4, |r, t, _, w| {
        (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64))
            * (1.0 + 0.1 * (2.0 * PI * 1.3 * t + 0.7 * r as f64).sin())
    });
    let freqs: Vec<f64> = (0..200).map(|j| 0.5 + 0.01 * j as f64).collect();
    let s = FrictionSet::default().with(Term::Stribeck);
    let sets = [s.with(Term::TimeSine), s, s.with(Term::AngleSine), s.with(Term::Viscous)];
    let bits = |m: Option<Composite>| {
        format!(
            "{:?}",
            m.map(|m| {
                let f = |x: f64| x.to_bits();
                (
                    f(m.mu_k),
                    m.stribeck.map(|(a, b)| (f(a), f(b))),
                    m.viscous.map(f),
                    m.time_mod.map(|(a, b)| (f(a), f(b))),
                    m.angle_mod.map(|(a, n)| (f(a), n)),
                )
            })
        )
    };
    let cold = DataMemo::default();
    for set in sets {
        let alone = fit_composite_model_from(&d, set, &freqs, 4, None);
        assert!(alone.as_ref().is_some_and(|m| m.stribeck.is_some()), "{set:?}");
        let shared = fit_composite_model_from_cached(&d, set, &freqs, 4, None, &cold);
        assert_eq!(bits(shared), bits(alone), "{set:?}");
    }
    assert!(cold.fits.iter().all(|f| f.get().is_some()));
    // The angle block at its order on every pass, from the memo the
    // `{stribeck, angle}` set filled.
    let set = FrictionSet::default().with(Term::AngleSine).with(Term::TimeSine);
    let alone = fit_composite_model_from(&d, set, &freqs, 4, None);
    let n = alone.as_ref().and_then(|m| m.angle_mod).expect("an angle order").1;
    assert_eq!(bits(fit_composite_model_from_cached(&d, set, &freqs, 4, None, &cold)), bits(alone));
    assert_eq!(cold.angles.get(&d, n).len(), d.len());
    // The sets a step adds to `{stribeck}`, warm-started from its model:
    // the first pass's Stribeck search from the memo (filled by whichever
    // set comes first) is each set's own search, bit for bit.
    let start = fit_composite_model_from(&d, s, &freqs, 4, None).expect("the Stribeck fit");
    let cold = DataMemo::default();
    for set in [s.with(Term::TimeSine), s.with(Term::AngleSine), s.with(Term::Viscous), s.with(Term::TimeSine)] {
        let alone = fit_composite_model_from(&d, set, &freqs, 4, Some(&start));
        assert!(alone.as_ref().is_some_and(|m| m.stribeck.is_some()), "{set:?}");
        let shared = fit_composite_model_from_cached(&d, set, &freqs, 4, Some(&start), &cold);
        assert_eq!(bits(shared), bits(alone), "{set:?}");
    }
    let near = cold.near.lock().unwrap();
    assert_eq!(near.len(), 2, "one search without and one with the viscous column: {:?}", near.keys());
}

/// The selection's fit on every run, deferred and then inflated, is
/// [`fit_composite`]'s: the same model, phases, parameters and standard
/// errors, scan and convergence, to the bit, for every set of terms.
#[test]
fn a_deferred_fit_inflated_is_the_full_fit() {
    let d = synth(4, |r, t, phi, w| {
        (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64) + 0.003 * w)
            * (1.0 + 0.1 * (2.0 * PI * 1.3 * t + 0.7 * r as f64).sin())
            * (1.0 + 0.08 * (2.0 * phi + 0.3 * r as f64).sin())
    });
    let freqs: Vec<f64> = (0..200).map(|j| 0.5 + 0.01 * j as f64).collect();
    let terms = [Term::TimeSine, Term::AngleSine, Term::Stribeck, Term::Viscous];
    let bits = |f: &CompositeFit| {
        let b = |x: f64| x.to_bits();
        let params: Vec<_> = f.params.iter().map(|p| (p.0, p.1, b(p.2), b(p.3))).collect();
        let phases: Vec<_> = f.phases.iter().map(|p| (b(p.0), b(p.1))).collect();
        let scan: Vec<_> = f.scan.iter().map(|p| (b(p.0), b(p.1))).collect();
        (format!("{:?}", f.model), phases, params, scan, f.converged)
    };
    for mask in 0..16u32 {
        let set = (0..4).filter(|b| mask >> b & 1 == 1).fold(FrictionSet::default(), |s, b| s.with(terms[b]));
        let full = fit_composite(&d, set, &freqs, 4).expect("the full fit");
        let mut deferred = fit_composite_deferred(&d, set, &freqs, 4).expect("the deferred fit");
        inflate_errors(&d, &mut deferred);
        assert_eq!(bits(&deferred), bits(&full), "{set:?}");
        assert!(full.params.iter().all(|p| p.1 == "order" || p.3 > 0.0), "{set:?}: {:?}", full.params);
    }
}

/// A fit asked for its model alone (a fold's) skips the closing RSS and
/// the last block's factors where the pass ends the fit anyway: the
/// same model, to the bit, as the full fit's, for every set of terms.
#[test]
fn the_model_alone_is_the_full_fits_model() {
    let d = synth(4, |r, t, phi, w| {
        (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64) + 0.003 * w)
            * (1.0 + 0.1 * (2.0 * PI * 1.3 * t + 0.7 * r as f64).sin())
            * (1.0 + 0.08 * (2.0 * phi + 0.3 * r as f64).sin())
    });
    let freqs: Vec<f64> = (0..200).map(|j| 0.5 + 0.01 * j as f64).collect();
    let terms = [Term::TimeSine, Term::AngleSine, Term::Stribeck, Term::Viscous];
    for mask in 0..16u32 {
        let set = (0..4).filter(|b| mask >> b & 1 == 1).fold(FrictionSet::default(), |s, b| s.with(terms[b]));
        let full = fit_composite(&d, set, &freqs, 4).map(|f| f.model);
        let alone = fit_composite_model(&d, set, &freqs, 4);
        assert!(full.is_some(), "{set:?}");
        assert_eq!(format!("{alone:?}"), format!("{full:?}"), "{set:?}");
        let bits = |m: &Composite| {
            let f = |x: f64| x.to_bits();
            (f(m.mu_k), m.stribeck.map(|(a, b)| (f(a), f(b))), m.viscous.map(f), m.time_mod.map(|(a, b)| (f(a), f(b))))
        };
        assert_eq!(bits(&alone.unwrap()), bits(&full.unwrap()), "{set:?}");
    }
}

#[test]
fn two_effects_at_once_are_recovered() {
    // Stribeck speed law × normal-force modulation at 1.3 Hz, own phase per run.
    let d = synth(5, |r, t, _, w| {
        (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64))
            * (1.0 + 0.12 * (2.0 * PI * 1.3 * t + 0.9 * r as f64).sin())
    });
    let freqs: Vec<f64> = (0..300).map(|j| 0.05 + 0.01 * j as f64).collect();
    let set = FrictionSet::default().with(Term::Stribeck).with(Term::TimeSine);
    let f = fit_composite(&d, set, &freqs, 8).unwrap();
    let m = &f.model;
    let (mu_s, vs) = m.stribeck.unwrap();
    let (a, fr) = m.time_mod.unwrap();
    assert!((m.mu_k - 0.4).abs() < 4e-3 && (mu_s - 0.6).abs() < 1e-2 && (vs - 2.0).abs() < 0.1, "{m:?}");
    assert!((a - 0.12).abs() < 5e-3 && (fr - 1.3).abs() < 2e-3, "{m:?}");
    // Each single effect alone leaves far more.
    let one = fit_composite(&d, FrictionSet::default().with(Term::Stribeck), &freqs, 8);
    assert!(one.unwrap().rss_w > 20.0 * f.rss_w);
    // A held-out run's phase is recovered from its own data with the shared parameters fixed.
    let held = synth(1, |_, t, _, w| {
        (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64)) * (1.0 + 0.12 * (2.0 * PI * 1.3 * t + 2.5).sin())
    });
    let ph = heldout_phases(m, &held);
    let e = (ph.0 - 2.5).rem_euclid(2.0 * PI);
    assert!(e.min(2.0 * PI - e) < 0.05, "phase {}", ph.0);
}

/// What the fit reports is the law it returns: after the angle block
/// rescaled the speed law, μk and c in `params` are the model's.
#[test]
fn reported_speed_law_is_the_fitted_model() {
    let d = synth(4, |r, _, phi, w| (0.4 + 0.01 * w) * (1.0 + 0.1 * (3.0 * phi + 0.5 * r as f64).sin()));
    let set = FrictionSet::default().with(Term::Viscous).with(Term::AngleSine);
    let f = fit_composite(&d, set, &[], 8).unwrap();
    let value = |key: &str| f.params.iter().find(|p| p.1 == key).map(|p| p.2).unwrap();
    assert_eq!(value("viscous_per_rad_s"), f.model.viscous.unwrap());
    assert_eq!(value("mu_kinetic"), f.model.mu_k);
    assert!((f.model.viscous.unwrap() - 0.01).abs() < 1e-3 && (f.model.mu_k - 0.4).abs() < 1e-2, "{:?}", f.model);
}

#[test]
fn the_empty_set_is_coulomb() {
    let d = synth(2, |_, _, _, _| 0.5);
    let f = fit_composite(&d, FrictionSet::default(), &[], 8).unwrap();
    assert!((f.model.mu_k - 0.5).abs() < 1e-3 && f.params.is_empty());
}
