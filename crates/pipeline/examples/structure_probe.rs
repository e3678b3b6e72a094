//! Where the damping acts (issue 25): the shipped campaign's free run under
//! the extended model with the damping on the twist rate (the baseline),
//! moved to the absolute rotor speed with the motor constants unchanged, and
//! moved with the motor constants re-estimated under that structure
//! (`rig_estimate::DampingStructure`).
//!
//! `cargo run --example structure_probe [campaign dir] [C_r N·m·s/rad]`
//! (defaults: data/emulated-rig-2026; C_r 6.91e-3, the diagnosis' rotor
//! torque-balance drag on this campaign, printed below for checking). The
//! extended model's effects are the findings of `reports/diagnosis.json`.
//! Prints, per variant, the motor constants and the four free-run checks of
//! `rig_diagnose::channels` (regime, rotor max/min, fundamental; ratios to
//! their floors), then the runs whose regime differs; the same for the
//! models without effects, and for four phases of the normal-force modulation.

use anyhow::{Context, Result};
use rig_diagnose::channels::{FreeRunSettings, free_run_checks_of, free_run_pairs, torque_balance_check};
use rig_diagnose::{DiagnoseOptions, EffectId, extended_params};
use rig_estimate::{DampingStructure, EstimateOptions, InitialValues, RotorDamping, estimate_rig};
use rig_types::RigParams;
use std::collections::BTreeMap;
use std::path::Path;

fn findings(path: &Path) -> Result<Vec<(EffectId, BTreeMap<String, f64>)>> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?)?;
    let mut out = Vec::new();
    for f in v["findings"].as_array().context("diagnosis.json: no findings array")? {
        let Some(e) = f["effect"].as_str().and_then(EffectId::from_id) else { continue };
        let params: BTreeMap<String, f64> = serde_json::from_value(f["params"].clone())?;
        out.push((e, params));
    }
    Ok(out)
}

fn motor_line(p: &RigParams) -> String {
    let m = &p.motor;
    format!(
        "k_T {:.5} k_e {:.5} T_f {:.5} J_m {:.3e} J1 {:.5} C {:.3e} C_r {:.3e} Kp {:.3} Ki {:.2}",
        m.torque_constant_nm_a,
        m.voltage_constant_v_s_rad,
        m.friction_torque_nm,
        m.inertia_kgm2,
        p.rotor_inertia_kgm2,
        p.shaft_damping_nm_s_rad,
        p.rotor_damping_nm_s_rad,
        p.drive.kp_v_s_rad,
        p.drive.ki_v_rad
    )
}

fn main() -> Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let args: Vec<String> = std::env::args().collect();
    let dir = args.get(1).map_or_else(|| root.join("data/emulated-rig-2026"), |d| d.into());
    let c_r: f64 = args.get(2).map_or(Ok(6.91e-3), |s| s.parse()).context("C_r must be a number")?;
    let c = rig_ingest::read_campaign(&dir)?;
    let opts = DiagnoseOptions::from_pipeline_toml(&std::fs::read_to_string(root.join("pipeline.toml"))?)
        .map_err(anyhow::Error::msg)?;
    let th = rig_calibrate::thesis_data(&rig_ingest::thesis::read_thesis_tables(&root.join("data/thesis"))?)?;
    let cal = rig_calibrate::calibrate_campaign(&c)?;
    let found = findings(&root.join("reports/diagnosis.json"))?;
    println!("campaign {} · extended by {:?}", c.name, found);

    let base_opts = EstimateOptions::new(InitialValues::from_thesis_data(&th), opts.integrator.clone());
    let est = |d: DampingStructure| -> Result<rig_estimate::RigEstimate> {
        let o = EstimateOptions { damping: d, ..base_opts.clone() };
        let t0 = std::time::Instant::now();
        let e = estimate_rig(&c, &cal, &o)?;
        println!(
            "  estimate {d:?}: ssr {:.4e} ({} it, {:.0} s), held-out rotor fit {:?}",
            e.report.ssr,
            e.report.iterations,
            t0.elapsed().as_secs_f64(),
            e.report
                .runs
                .iter()
                .filter(|r| !r.used)
                .map(|r| format!("{} {:.1}%", r.run, r.channels[1].fit_percent))
                .collect::<Vec<_>>()
        );
        let m = &e.modes;
        println!(
            "    coupled mode {:.3} rad/s xi {:.4} | fixed base xi {:.4} | log decrement {:.3} rad/s xi {:.4}",
            m.coupled_natural_rad_s.unwrap_or(f64::NAN),
            m.coupled_damping_ratio.unwrap_or(f64::NAN),
            m.fixed_base_damping_ratio,
            m.log_decrement_natural_rad_s,
            m.log_decrement_damping_ratio
        );
        Ok(e)
    };
    let a = est(DampingStructure::TwistRate)?.params;
    let shipped: RigParams =
        serde_json::from_str(&std::fs::read_to_string(root.join("reports/data/rig-params.json"))?)?;
    println!("baseline equals reports/data/rig-params.json: {}", shipped == a);
    let bal = torque_balance_check(&c, &cal, &a, &opts, &opts.channels);
    println!("torque balance (baseline): {}", bal.detail);

    let mut variants: Vec<(&str, RigParams)> = vec![("a twist C (baseline)", a.clone())];
    let moved = |c_rot: f64| RigParams { shaft_damping_nm_s_rad: 0.0, rotor_damping_nm_s_rad: c_rot, ..a.clone() };
    variants.push(("b1 C->Omega1 same C, motor unchanged", moved(a.shaft_damping_nm_s_rad)));
    variants.push(("b2 C_r=balance, motor unchanged", moved(c_r)));
    let held = RotorDamping::Held { nm_s_rad: c_r };
    variants.push((
        "c1 C_r=balance held, re-estimated",
        est(DampingStructure::RotorAbsolute { rotor_damping: held })?.params,
    ));
    variants.push((
        "c2 C_r fitted, re-estimated",
        est(DampingStructure::RotorAbsolute { rotor_damping: RotorDamping::Fitted })?.params,
    ));
    variants.push(("c3 both, C_r held, re-estimated", est(DampingStructure::Both { rotor_damping: held })?.params));

    // Controls: the same models without the diagnosed effects (what the structure alone does).
    let bare: Vec<(String, RigParams)> =
        [0, 4].iter().map(|&i| (format!("{} (no effects)", variants[i].0), variants[i].1.clone())).collect();

    let s = FreeRunSettings::of(&opts, &opts.channels);
    let runs = variants.iter().map(|(l, p)| (l.to_string(), extended_params(p, &found))).chain(bare);
    for (label, ext) in runs {
        let p = &ext;
        let pairs = free_run_pairs(&c, &ext, &s);
        let checks = free_run_checks_of(&c, &pairs, &s, &opts.channels);
        println!("\n== {label}\n   {}", motor_line(p));
        for ch in &checks {
            println!(
                "   {:<30} stat {:>9.4} ratio {:>6.2} (thr {:.1}){} {}",
                ch.channel,
                ch.statistic,
                ch.ratio,
                ch.threshold,
                if ch.flagged { " FLAGGED" } else { "" },
                ch.detail
            );
        }
        for q in &pairs {
            let Some(f) = q.simulated else { continue };
            if f.stick_slip() != q.measured.stick_slip() {
                println!(
                    "   {} measured ss={} max {:.2} min {:.2} | simulated ss={} max {:.2} min {:.2}",
                    q.id,
                    q.measured.stick_slip(),
                    q.measured.rotor_max_rad_s,
                    q.measured.rotor_min_rad_s,
                    f.stick_slip(),
                    f.rotor_max_rad_s,
                    f.rotor_min_rad_s
                );
            }
        }
    }

    // Is the regime of a run decided by the modulation's phase (per-run
    // nuisance the diagnosis does not report; extended_params sets 0)?
    println!("\n== phase of the normal-force modulation, c2 (C_r fitted, re-estimated)");
    for k in 0..4 {
        let phase_rad = f64::from(k) * std::f64::consts::FRAC_PI_2;
        let mut ext = extended_params(&variants[4].1, &found);
        for e in &mut ext.effects {
            if let rig_types::Effect::NormalForceModulation { phase_rad: ph, .. } = e {
                *ph = phase_rad;
            }
        }
        let pairs = free_run_pairs(&c, &ext, &s);
        let checks = free_run_checks_of(&c, &pairs, &s, &opts.channels);
        println!(
            "   phase {phase_rad:.3} rad: regime {} | rotor_max ratio {:.2} | rotor_min ratio {:.2}",
            checks[0].detail, checks[1].ratio, checks[2].ratio
        );
    }
    Ok(())
}
