//! Probe (issue 25): the shipped campaign's diagnosis with the baseline's
//! static friction coefficient replaced, to see what the free run does.
//! `cargo run --example breakaway_probe -- <mu_static[,mu_kinetic]>...`
//! (the shipped level is 1.4643698308330335). `TRANSIENT=1` prints each
//! operating point's transient instead: the last time Ω1 is stuck after the
//! ramp, record vs final model, with the regime over the free-run window and
//! at the end of the run; `PHASES=0,0.785,…` reruns the model with the
//! modulation's phase moved by each (rad), `RUNS=op-19,…` selects runs. The
//! numbers of `channels::free_run::attractor_stick_slip`'s docs come from it.

use anyhow::{Context, Result};
use rig_diagnose::{DiagnoseOptions, diagnose};
use rig_types::{FrictionLaw, RigParams};
use std::path::Path;

fn main() -> Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let c = rig_ingest::read_campaign(&root.join("data/emulated-rig-2026"))?;
    let opts = DiagnoseOptions::from_pipeline_toml(&std::fs::read_to_string(root.join("pipeline.toml"))?)
        .map_err(anyhow::Error::msg)?;
    let cal = rig_calibrate::calibrate_campaign(&c)?;
    let shipped: RigParams =
        serde_json::from_str(&std::fs::read_to_string(root.join("reports/data/rig-params.json"))?)?;
    let shipped = if std::env::var("REEST").is_ok() {
        let th = rig_calibrate::thesis_data(&rig_ingest::thesis::read_thesis_tables(&root.join("data/thesis"))?)?;
        let o = rig_estimate::EstimateOptions {
            damping: rig_estimate::DampingStructure::RotorAbsolute {
                rotor_damping: rig_estimate::RotorDamping::Fitted,
            },
            ..rig_estimate::EstimateOptions::new(
                rig_estimate::InitialValues::from_thesis_data(&th),
                opts.integrator.clone(),
            )
        };
        let e = rig_estimate::estimate_rig(&c, &cal, &o)?.params;
        println!(
            "re-estimated: C {:.3e} C_r {:.3e} motor {:?} drive {:?}",
            e.shaft_damping_nm_s_rad, e.rotor_damping_nm_s_rad, e.motor, e.drive
        );
        e
    } else {
        shipped
    };
    for a in std::env::args().skip(1) {
        let (a, k) = a.split_once(',').unwrap_or((&a, ""));
        let mu_s: f64 = a.parse().context("mu_static")?;
        let mut p = shipped.clone();
        if let FrictionLaw::Coulomb { mu_static, mu_kinetic } = &mut p.friction {
            *mu_static = mu_s;
            if !k.is_empty() {
                *mu_kinetic = k.parse().context("mu_kinetic")?;
            }
        }
        let d = diagnose(&c, &cal, Some(&p), Some(1.2), &opts)?;
        println!("== mu_static {mu_s}: verdict {}", d.verdict);
        for k in &d.detail.free_run_extended {
            println!("  {:<28} ratio {:6.2} thr {:.1} {} {}", k.channel, k.ratio, k.threshold, k.flagged, k.detail);
        }
        println!("  structure {} | {}", d.structure.damping, d.structure.notes);
        if let Ok(list) = std::env::var("SCAN") {
            let vocab: Vec<_> = d
                .findings
                .iter()
                .filter_map(|f| rig_diagnose::EffectId::from_id(&f.effect).map(|e| (e, f.params.clone())))
                .collect();
            let mut ext = rig_diagnose::extended_params(&p, &vocab);
            if let Some(l) = &d.detail.breakaway {
                ext = rig_diagnose::breakaway::with_static_level(&ext, l);
            }
            let s = rig_diagnose::channels::FreeRunSettings::of(&opts, &opts.channels);
            for v in list.split(',') {
                let c_r: f64 = v.parse()?;
                let m = RigParams { shaft_damping_nm_s_rad: 0.0, rotor_damping_nm_s_rad: c_r, ..ext.clone() };
                let pairs = rig_diagnose::channels::free_run_pairs_by(&c, &s, |id| {
                    let row = d.detail.runs.iter().find(|r| r.id == id)?;
                    Some(rig_diagnose::channels::with_run_phases(&m, row.phases_rad))
                });
                let ch = rig_diagnose::channels::free_run_checks_of(&c, &pairs, &s, &opts.channels);
                println!(
                    "  C_r {c_r:.2e}: {}",
                    ch.iter().map(|k| format!("{} {:.2}", k.channel, k.ratio)).collect::<Vec<_>>().join(" | ")
                );
                println!("     {}", ch[0].detail);
            }
        }
        let cr: f64 = std::env::var("CR").map_or(6.92e-3, |v| v.parse().unwrap());
        if std::env::var("TRANSIENT").is_ok() {
            transients(&c, &d, &p, cr, &opts);
            continue;
        }
        for id in ["op-19", "op-27", "op-03", "op-20"] {
            blocks(&c, &d, &p, id, cr, &opts.integrator);
        }
        for r in &d.detail.runs {
            if let (m, Some(e)) = (r.measured, r.extended) {
                println!(
                    "  {} ss {}/{} max {:.2}/{:.2} min {:.2}/{:.2}",
                    r.id,
                    m.stick_slip(),
                    e.stick_slip(),
                    m.rotor_max_rad_s,
                    e.rotor_max_rad_s,
                    m.rotor_min_rad_s,
                    e.rotor_min_rad_s
                );
            }
        }
    }
    Ok(())
}

/// Block extrema (2 s) of run `id`'s rotor speed, measured and simulated with
/// the final model rebuilt by hand (findings, phases, μs, rotor damping).
#[allow(dead_code)]
pub fn blocks(
    c: &rig_types::Campaign,
    d: &rig_diagnose::Diagnosis,
    base: &RigParams,
    id: &str,
    c_r: f64,
    so: &rig_model::SimOptions,
) {
    use rig_types::RunKind;
    let p = final_model(d, base, id, c_r, 0.0);
    let run = c.runs.iter().find(|r| r.id == id).unwrap();
    let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else { return };
    let t = &run.data.time_s;
    let input = rig_types::RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s };
    let tr = rig_model::simulate(&p, &input, t, so).unwrap();
    let h = 10;
    let speed = |a: &[f64]| rig_types::sensor::central_difference_rad_s(t, a, h);
    let meas =
        speed(&rig_types::sensor::ticks_to_rad(run.data.rotor_ticks.as_ref().unwrap(), c.rig.encoder_ticks_per_rev));
    let sim = speed(&tr.rotor_angle_rad);
    for (name, w) in [("meas", &meas), ("sim ", &sim)] {
        let mut line = format!("  {id} {name}");
        for b in 0..20 {
            let (lo, hi) = (b as f64 * 2.0, b as f64 * 2.0 + 2.0);
            let v: Vec<f64> = t.iter().zip(w.iter()).filter(|(x, _)| **x >= lo && **x < hi).map(|(_, y)| *y).collect();
            let mx = v.iter().copied().fold(f64::MIN, f64::max);
            let mn = v.iter().copied().fold(f64::MAX, f64::min);
            line.push_str(&format!(" {mx:.1}/{mn:.1}"));
        }
        println!("{line}");
    }
}

/// The final model of run `id` rebuilt by hand (findings, phases, μs; C = 0
/// unless TW is set, rotor damping `c_r` on Ω1 when ≥ 0), with `dphase`
/// added to the modulation's phase.
fn final_model(d: &rig_diagnose::Diagnosis, base: &RigParams, id: &str, c_r: f64, dphase: f64) -> RigParams {
    let vocab: Vec<_> = d
        .findings
        .iter()
        .filter_map(|f| rig_diagnose::EffectId::from_id(&f.effect).map(|e| (e, f.params.clone())))
        .collect();
    let row = d.detail.runs.iter().find(|r| r.id == id).unwrap();
    let ph = (row.phases_rad.0 + dphase, row.phases_rad.1);
    let mut p = rig_diagnose::channels::with_run_phases(&rig_diagnose::extended_params(base, &vocab), ph);
    if let Some(l) = &d.detail.breakaway {
        p = rig_diagnose::breakaway::with_static_level(&p, l);
    }
    if std::env::var("TW").is_err() {
        p.shaft_damping_nm_s_rad = 0.0;
    }
    if c_r >= 0.0 {
        p.rotor_damping_nm_s_rad = c_r;
    }
    p
}

/// Transient length of every operating point: the last time after the ramp
/// at which Ω1 (±8-sample centred difference) is at or below 0.3 rad/s
/// (the classifier's stick floor), record vs final model, and the regime of
/// the free-run window; with PHASES="d1,d2,…" (rad) the model is rerun with
/// the modulation's phase moved by each.
fn transients(
    c: &rig_types::Campaign,
    d: &rig_diagnose::Diagnosis,
    base: &RigParams,
    c_r: f64,
    opts: &DiagnoseOptions,
) {
    use rig_types::RunKind;
    let dphases: Vec<f64> = std::env::var("PHASES")
        .map(|v| v.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or_else(|_| vec![0.0]);
    let only: Option<Vec<String>> = std::env::var("RUNS").ok().map(|v| v.split(',').map(String::from).collect());
    let (settle, steady) = (opts.settle_s, opts.channels.free_run_steady_s);
    for run in c.runs_of("operating_point") {
        if only.as_ref().is_some_and(|o| !o.contains(&run.id)) {
            continue;
        }
        let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else { continue };
        let t = &run.data.time_s;
        let input = rig_types::RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s };
        let speed = |a: &[f64]| rig_types::sensor::central_difference_rad_s(t, a, 8);
        let read = |w: &[f64]| {
            let last =
                t.iter().zip(w).filter(|(x, v)| **x > ramp_s + 0.5 && v.abs() <= 0.3).map(|(x, _)| *x).next_back();
            let (a, b) =
                (t.partition_point(|&x| x < ramp_s + settle), t.partition_point(|&x| x < ramp_s + settle + steady));
            let fs = (b - a - 1) as f64 / (t[b - 1] - t[a]);
            let cl = rig_sweep::classify(&w[a..b], fs, &opts.classify);
            let half = (b - a) / 2;
            let pp =
                |x: &[f64]| x.iter().copied().fold(f64::MIN, f64::max) - x.iter().copied().fold(f64::MAX, f64::min);
            // The attractor: the same classifier over the record's last `steady` s.
            let e = t.partition_point(|&x| x < t[t.len() - 1] - steady).max(a);
            let fe = (t.len() - e - 1) as f64 / (t[t.len() - 1] - t[e]);
            let end = rig_sweep::classify(&w[e..], fe, &opts.classify).regime.stick_slip();
            (last.unwrap_or(0.0), cl.regime.stick_slip(), pp(&w[a + half..b]) / pp(&w[a..a + half]), end)
        };
        let meas = speed(&rig_types::sensor::ticks_to_rad(
            run.data.rotor_ticks.as_ref().unwrap(),
            c.rig.encoder_ticks_per_rev,
        ));
        let (lm, sm, rm, em) = read(&meas);
        let mut line = format!(
            "  {} {:>5.1}rpm {:>4.1}N record last-stick {lm:5.1}s ss {sm:5} decay {rm:.2} end {em:5} | model",
            run.id, motor_rpm_setpoint, normal_force_n
        );
        for dp in &dphases {
            let p = final_model(d, base, &run.id, c_r, *dp);
            match rig_model::simulate(&p, &input, t, &opts.integrator) {
                Ok(tr) => {
                    let (l, s, r, e) = read(&speed(&tr.rotor_angle_rad));
                    let ab = |b: bool| if b { "SS" } else { "--" };
                    line.push_str(&format!(" [{dp:+.2}] {l:5.1}s {} {r:.2} {}", ab(s), ab(e)));
                }
                Err(e) => line.push_str(&format!(" [{dp:+.2}] err {e}")),
            }
        }
        println!("{line}");
    }
}
