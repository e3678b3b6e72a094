//! Probe (issue 25): the shipped campaign's diagnosis with the baseline's
//! static friction coefficient replaced, to see what the free run does.
//! `cargo run --example breakaway_probe -- <mu_static[,mu_kinetic]>...`

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
        for r in &d.detail.runs {
            if let (m, Some(e)) = (r.measured, r.extended) {
                println!("  {} ss {}/{} max {:.2}/{:.2} min {:.2}/{:.2}", r.id, m.stick_slip(), e.stick_slip(), m.rotor_max_rad_s, e.rotor_max_rad_s, m.rotor_min_rad_s, e.rotor_min_rad_s);
            }
        }
    }
    Ok(())
}
