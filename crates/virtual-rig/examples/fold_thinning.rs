//! What fitting the friction channel on thinned slip samples changes
//! (`fold_fit_spacing_s`, docs/performance.md, issue 23): on a campaign's
//! every run, each friction set fitted on every slip sample (with its
//! standard errors, inflated by √τ for the correlated residuals) and on the
//! samples `spacing` seconds apart; per parameter the change in units of the
//! full fit's standard error, and the residuals' τ (integrated
//! autocorrelation, samples). One line per (campaign, set, spacing).
//! `cargo run --workspace --example fold_thinning -- CASE…` where CASE is
//! `shipped` (data/emulated-rig-2026) or a full-battery case index.

use rig_diagnose::composite::{self, CompositeFit, FrictionSet};
use rig_diagnose::friction::{self, SlipData};
use rig_diagnose::prepare::{self, SensorLaw};
use rig_virtual_rig::battery::Battery;

fn sets() -> Vec<(&'static str, FrictionSet)> {
    let s = |time_mod, angle_mod, stribeck, viscous| FrictionSet { time_mod, angle_mod, stribeck, viscous };
    vec![
        ("coulomb", s(false, false, false, false)),
        ("stribeck", s(false, false, true, false)),
        ("viscous", s(false, false, false, true)),
        ("time", s(true, false, false, false)),
        ("angle", s(false, true, false, false)),
        ("time+stribeck", s(true, false, true, false)),
        ("angle+viscous", s(false, true, false, true)),
    ]
}

fn tau(d: &SlipData, f: &CompositeFit) -> f64 {
    let r: Vec<f64> = (0..d.len())
        .map(|i| {
            let ph = f.phases.get(d.run[i]).copied().unwrap_or((0.0, 0.0));
            d.run_weight[d.run[i]].sqrt() * (d.mu[i] - f.model.mu(d.t[i], d.phi[i], d.omega[i], ph))
        })
        .collect();
    friction::inflation_of(&r, &d.run)
}

fn main() {
    let opts = rig_diagnose::DiagnoseOptions::from_pipeline_toml(include_str!("../../../pipeline.toml"))
        .expect("pipeline.toml");
    let freqs: Vec<f64> = {
        let n = ((opts.freq_max_hz - opts.freq_min_hz) / opts.freq_step_hz).floor() as usize;
        (0..=n).map(|j| opts.freq_min_hz + opts.freq_step_hz * j as f64).collect()
    };
    let battery = Battery::full();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for arg in std::env::args().skip(1) {
        let (name, c) = if arg == "shipped" {
            ("shipped".to_string(), rig_ingest::read_campaign(&root.join("data/emulated-rig-2026")).expect("campaign"))
        } else {
            let case = &battery.cases[arg.parse::<usize>().expect("case index")];
            (case.id.clone(), case.generate(&battery.protocol).expect("generate"))
        };
        let cal = rig_calibrate::calibrate_campaign(&c).expect("calibration");
        let fc = rig_diagnose::ForceCal { factor_mv_per_n: cal.force_factor_mv_per_n, offset_mv: cal.force_offset_mv };
        let runs = prepare::prepare_runs(&c, SensorLaw::Line(fc), &opts).expect("signals");
        let all: Vec<&rig_diagnose::RunSignals> = runs.iter().collect();
        let d = SlipData::from_runs(&all);
        for (set_name, set) in sets() {
            let Some(full) = composite::fit_composite(&d, set, &freqs, opts.max_order) else { continue };
            let t = tau(&d, &full);
            for spacing in [0.004, 0.008, 0.016, 0.032] {
                let dt = SlipData::from_runs_spaced(&all, spacing);
                let Some(thin) = composite::fit_composite(&dt, set, &freqs, opts.max_order) else { continue };
                let moves: Vec<String> = full
                    .params
                    .iter()
                    .zip(&thin.params)
                    .map(|(a, b)| {
                        let z = if a.1 == "order" { b.2 - a.2 } else { (b.2 - a.2) / a.3 };
                        format!("{}:{z:+.3}", a.1)
                    })
                    .collect();
                let worst = full
                    .params
                    .iter()
                    .zip(&thin.params)
                    .filter(|(a, _)| a.1 != "order")
                    .map(|(a, b)| ((b.2 - a.2) / a.3).abs())
                    .fold(0.0, f64::max);
                println!(
                    "{name} {set_name} spacing {spacing} n {} -> {} tau {t:.1} max|dz| {worst:.3} [{}]",
                    d.len(),
                    dt.len(),
                    moves.join(" ")
                );
            }
        }
    }
}
