//! The full battery judged case by case, streamed: each case generated,
//! diagnosed blind and judged ([`rig_virtual_rig::battery::judge`], the
//! confusion stage's rule), one JSON line per case as it finishes, so a run
//! cut short still leaves a stratified sample. Cases go in rounds r = k mod 40
//! (each round samples every group in proportion, the battery being in group
//! order); process PART of PARTS takes the rounds r ≡ PART (mod PARTS), so
//! two processes with `RAYON_NUM_THREADS=1` keep 2 cores busy.
//! `cargo run --workspace --example battery_stream -- PART PARTS > part.jsonl`;
//! `python3 scripts/battery_summary.py part*.jsonl` tabulates them
//! (docs/battery-full/2026-11-26.md). The confusion stage
//! (`--set confusion.battery=full`) gives the same answers with its tables.

use rig_virtual_rig::battery::{Battery, DiagnosisResult, judge};

/// CPU time (user + system) of this process so far, s (`rig_types::cpu`).
fn cpu_s() -> f64 {
    rig_types::cpu::process_cpu_s().expect("/proc/self/stat")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let part: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(0);
    let parts: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1).max(1);
    let battery = Battery::named("full", 7000).expect("the full battery");
    let opts =
        rig_diagnose::BlindChain::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis");
    let thesis = rig_calibrate::thesis_data(&rig_ingest::thesis::read_thesis_tables(&dir).expect("data/thesis"))
        .expect("thesis data");
    let n = battery.cases.len();
    for r in (0..40).filter(|r| r % parts == part) {
        for k in (r..n).step_by(40) {
            let case = &battery.cases[k];
            let c0 = cpu_s();
            let result = case
                .generate(&battery.protocol)
                .map_err(|e| e.to_string())
                .and_then(|c| rig_diagnose::diagnose_campaign(&c, Some(&thesis), &opts).map_err(|e| e.to_string()))
                .and_then(|d| serde_json::to_value(&d).map_err(|e| e.to_string()))
                .and_then(|v| serde_json::from_value::<DiagnosisResult>(v).map_err(|e| e.to_string()));
            let j = judge(case, &result);
            let (verdict, findings) = result
                .as_ref()
                .map(|d| (d.verdict.clone(), d.findings.iter().map(|f| f.effect.clone()).collect::<Vec<_>>()))
                .unwrap_or_else(|e| (format!("error: {e}"), vec![]));
            let line = serde_json::json!({"k": k, "round": r, "case": case.id, "group": case.group.name(),
                "right": j.right, "reason": j.reason, "verdict": verdict, "findings": findings, "cpu_s": cpu_s() - c0});
            println!("{line}");
        }
    }
}
