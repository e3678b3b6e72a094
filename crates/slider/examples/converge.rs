//! The slider study at a fit tolerance (issue 26: the verdict must not turn
//! on the search): every step's trials (gain, paired t, kept), the verdict,
//! every fit's evaluations and whether it converged, and the process's CPU.
//! `cargo run -p rig-slider --example converge -- [TOLERANCE] [STARTS] [DIR] [EVALS] [KEEP RACE_EVALS]`
//! from the workspace root (default: pipeline.toml's `fit_tolerance`,
//! `fit_starts` and `fit_evals`, no race; a tolerance above 0 with a safeguard of 2000
//! evaluations per start, ../shared/data/ens-lyon-slider-2019; with KEEP,
//! tolerance 0: the STARTS best-scored starts raced, EVALS each, the KEEP
//! best on to RACE_EVALS: `fit_race_keep`, `fit_race_evals`). The
//! calibration fits come first (`cal` lines: every fit's misfit on the runs
//! it was fitted on, what a budget is chosen on, and its parameters, which
//! the `landscape` example reads), the held-out selection after.

use rig_slider::{StudyParams, run_study};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut p = StudyParams::from_pipeline_toml(
        &std::fs::read_to_string("pipeline.toml").expect("run from the workspace root"),
    )
    .expect("the slider stanza");
    if let Some(t) = args.get(1) {
        p.fit_tolerance = t.parse().expect("TOLERANCE: a number");
        if p.fit_tolerance > 0.0 {
            p.fit_evals = 2000; // a safeguard per start, not a budget
        }
    }
    if let Some(s) = args.get(2) {
        p.fit_starts = s.parse().expect("STARTS: a count");
    }
    if let Some(e) = args.get(4) {
        p.fit_evals = e.parse().expect("EVALS: a count");
    }
    if let (Some(k), Some(e)) = (args.get(5), args.get(6)) {
        p.fit_race_keep = k.parse().expect("KEEP: a count");
        p.fit_race_evals = e.parse().expect("RACE_EVALS: a count");
    }
    let dir = args.get(3).cloned().unwrap_or_else(|| "../shared/data/ens-lyon-slider-2019".into());
    let s = run_study(std::path::Path::new(&dir), &p).unwrap_or_else(|e| panic!("{e}"));
    println!(
        "fit_tolerance {} fit_starts {} fit_evals {} fit_race_keep {} fit_race_evals {}",
        p.fit_tolerance, p.fit_starts, p.fit_evals, p.fit_race_keep, p.fit_race_evals
    );
    // Calibration only: each fit as (step, the model it extends, model, training stiffnesses).
    let from_of = |i: usize| {
        s.steps
            .iter()
            .find(|st| st.tried.contains(&i))
            .map_or((0, "-".to_string()), |st| (st.step, s.candidates[st.from].model.id()))
    };
    for (i, c) in s.candidates.iter().enumerate() {
        let (step, from) = from_of(i);
        for f in c.fits() {
            let mut ks: Vec<f64> = f.train.iter().map(|&r| s.runs[r].stiffness_n_m).collect();
            ks.dedup();
            println!(
                "cal step {step} from {from} model {} train {ks:?} misfit {:.4} evals {} params {}",
                c.model.id(),
                f.calibration_misfit,
                f.evals,
                f.params.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(",")
            );
        }
    }
    println!("--- held out below ---");
    for st in &s.steps {
        for (i, c) in st.tried.iter().zip(&st.compared) {
            let cand = &s.candidates[*i];
            let fits: Vec<String> = cand
                .fold_fits
                .iter()
                .map(|f| format!("{:.4}/{}{}", f.calibration_misfit, f.evals, if f.converged { "" } else { "!" }))
                .collect();
            println!(
                "step {} {:<40} gain {:>6.1} % t {:>5.2}{}{} fold fits (misfit/evals) {}",
                st.step,
                cand.model.id(),
                100.0 * c.gain,
                c.t,
                if *i == st.best { " best" } else { "" },
                if *i == st.best && st.kept { " KEPT" } else { "" },
                fits.join(" ")
            );
        }
    }
    let chosen = s.chosen.map(|i| s.candidates[i].model.id()).unwrap_or_else(|| "none (coulomb kept)".into());
    let fits: Vec<&rig_slider::study::Fitted> =
        s.candidates.iter().flat_map(rig_slider::study::CandidateResult::fits).collect();
    let evals: usize = fits.iter().map(|f| f.evals).sum();
    let stopped = fits.iter().filter(|f| !f.converged).count();
    println!("chosen {chosen}");
    for i in std::iter::once(0).chain(s.chosen) {
        let c = &s.candidates[i];
        let right = c.heldout.iter().filter(|(r, _, f)| f.regime == s.runs[*r].features.regime).count();
        let f = c.fitted.as_ref().expect("completed");
        println!(
            "  {} held-out mean misfit {:.4}, regimes right {right}/{}, params {:?}, calibration misfit {:.4}",
            c.model.id(),
            c.heldout_mean,
            c.heldout.len(),
            f.params,
            f.calibration_misfit
        );
    }
    println!(
        "fits {} evaluations {evals} stopped by the safeguard {stopped} cpu {:.2} s",
        fits.len(),
        rig_types::cpu::process_cpu_s().unwrap_or(f64::NAN)
    );
}
