//! A mid-size battery for the README's open-world numbers: 20 null draws,
//! one draw of every vocabulary effect, every compound pair once and every
//! effect outside the vocabulary once, on the small protocol (12 operating
//! points of 30 s), each diagnosed blind with a baseline estimated from the
//! thesis' published values. Prints battery.md.
//! `cargo run -p rig-virtual-rig --example battery [SEED]`

use rig_virtual_rig::battery::{Battery, DiagnosisResult, Sizes, report_markdown};
use rig_virtual_rig::{Hidden, Protocol};

fn main() {
    let seed: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(60_000);
    let opts =
        rig_diagnose::BlindChain::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis");
    let thesis = rig_calibrate::thesis_data(&rig_ingest::thesis::read_thesis_tables(&dir).expect("data/thesis"))
        .expect("thesis data");
    let sizes = Sizes {
        nulls: 20,
        stick_slip_nulls: 0,
        singles_per_effect: 1,
        compound_seeds: 1,
        vocabulary_plus_outside: 0,
        outside_seeds: 1,
        structural_seeds: 0,
        structural_plus_vocabulary: 0,
        ladder_seeds: 0,
    };
    let battery = Battery::build("mid", Protocol::small(), sizes, seed, &Hidden::OUTSIDE, &[]);
    let out = battery.run(|case, c| {
        let t0 = std::time::Instant::now();
        let d = rig_diagnose::diagnose_campaign(c, Some(&thesis), &opts).map_err(|e| e.to_string())?;
        eprintln!("{} -> {} ({:.1} s)", case.id, d.verdict, t0.elapsed().as_secs_f64());
        serde_json::to_value(&d).and_then(serde_json::from_value::<DiagnosisResult>).map_err(|e| e.to_string())
    });
    println!("{}", report_markdown(&battery, &out));
}
