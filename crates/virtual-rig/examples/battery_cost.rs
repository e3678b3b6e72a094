//! What a battery's campaigns cost, case by case: generation and blind
//! diagnosis of every `STRIDE`-th case of a battery (from case `OFFSET`), one
//! case after the other (rayon inside each diagnosis), each with the CPU time
//! of its generation and of its diagnosis (/proc/self/stat, 10 ms ticks; wall
//! time is what other jobs on the shared cores inflate) and its answer to the
//! last bit (the shard slices' `ExactResult`), one JSON line per case. A
//! stride samples every group of the battery in proportion (the cases are in
//! group order), so its CPU total × stride estimates the whole battery's
//! (docs/performance.md, issue 23); two builds that print the same answers
//! diagnose alike.
//! `cargo run --workspace --example battery_cost -- [full|ci|smoke] [STRIDE] [OFFSET] [SEED]`
//! (SEED: the first case seed, 7000 as the confusion stage's)
//! (the dev profile optimises the numeric crates; never --release, which rebuilds polars).

use rig_virtual_rig::battery::{Battery, DiagnosisResult, ExactResult};

/// CPU time (user + system) of this process so far, s (`rig_types::cpu`).
fn cpu_s() -> f64 {
    rig_types::cpu::process_cpu_s().expect("/proc/self/stat")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("ci", String::as_str);
    let stride: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1).max(1);
    let offset: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    // pipeline.toml's `[stage.params] seed` of the confusion stage.
    let seed: u64 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(7000);
    let battery = Battery::named(name, seed).expect("battery: full, ci or smoke");
    let opts =
        rig_diagnose::BlindChain::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis");
    let thesis = rig_calibrate::thesis_data(&rig_ingest::thesis::read_thesis_tables(&dir).expect("data/thesis"))
        .expect("thesis data");
    let (mut gen_total, mut diag_total, mut n) = (0.0, 0.0, 0);
    let w0 = std::time::Instant::now();
    for case in battery.cases.iter().skip(offset).step_by(stride) {
        let c0 = cpu_s();
        let campaign = case.generate(&battery.protocol).expect("generate");
        let c1 = cpu_s();
        let result = rig_diagnose::diagnose_campaign(&campaign, Some(&thesis), &opts)
            .map_err(|e| e.to_string())
            .and_then(|d| serde_json::to_value(&d).map_err(|e| e.to_string()))
            .and_then(|v| serde_json::from_value::<DiagnosisResult>(v).map_err(|e| e.to_string()))
            .map(ExactResult::from);
        let c2 = cpu_s();
        gen_total += c1 - c0;
        diag_total += c2 - c1;
        n += 1;
        let line = serde_json::json!({
            "case": case.id, "group": case.group.name(), "generate_cpu_s": c1 - c0, "diagnose_cpu_s": c2 - c1,
            "result": result,
        });
        println!("{line}");
    }
    eprintln!(
        "{name} battery, {n} of {} cases (every {stride}th from {offset}): generation {gen_total:.2} s CPU, \
         diagnosis {diag_total:.2} s CPU, {:.2} s wall; × {stride} ≈ {:.0} s CPU for the whole battery",
        battery.cases.len(),
        w0.elapsed().as_secs_f64(),
        (gen_total + diag_total) * stride as f64
    );
}
